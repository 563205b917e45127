"""Previews that cost little: an 800x600 preview of a 12-megapixel JPEG against decoding it.

The JPEG is a real photo made big: ``tests/data/facade/building.jpg`` (868x600, a facade),
its middle 800x600 (4:3) upscaled to 4000x3000 with ``cv2.resize`` (bicubic) and written as
JPEG quality 90 into a temporary directory (so it has a real photo's content, smoothed by the
upscaling). It is rectified with ``--max-size 800x600`` (the default frame, its scale
lowered to fit) at a few poses of a 3200 px focal length, in one process as a batch worker
runs (one OpenCV thread, freed memory kept), timed in alternating rounds, best of each, in
CPU time of the one thread that does all the work (``time.thread_time``: what the work costs,
whatever else the machine runs; wall-clock times are printed too):

- ``decode``: the JPEG decoded at full size alone, as gsrwt decodes it (libjpeg-turbo
  through simplejpeg, straight to BGRA into reused memory); the ratios' denominator; and the
  reduced decode alone, for scale (the entropy decoding stays whatever the reduction);
- ``preview``: the preview's pixels from the file: ``Scratch.read`` (the JPEG decoded reduced
  in the DCT, 1/2, 1/4 or 1/8, as the map allows) and ``Scratch.warp`` (antialiased);
  goal: at most 0.6x ``decode``;
- ``today``: the same without the reduced decode (a full decode, then the antialiased warp);
- ``floor``: the least a preview made this way can cost: the reduced decode alone followed by
  one bare ``cv2.warpPerspective`` of its pixels into reused memory (no file read, no checks,
  no antialiasing, no fill beyond the horizon);
- ``job``: the whole per-image work of ``gsrwt rectify`` with the preview (EXIF orientation,
  plan, decode, warp, encode as JPEG quality 95, write), for scale.

Quality: both outputs against an area-averaged reference (the full decode warped to 8x the
output's size, then averaged over 8x8 blocks, ``cv2.INTER_AREA``): the preview's PSNR must be
at most 1 dB below today's (goal); their PSNR against each other is printed too (they differ
in their filter, the DCT's box average against the warp's Gaussian pyramid, which blurs more:
docs/PERFORMANCE.md, "Previews").

    python benchmarks/bench_previews.py [--rounds 20]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gsrwt_cli.api.rectify import plan_image  # noqa: E402
from gsrwt_cli.batch.rectify_jobs import Job, Settings, process_job  # noqa: E402
from gsrwt_cli.geometry.camera import View  # noqa: E402
from gsrwt_cli.geometry.framing import Framing  # noqa: E402
from gsrwt_cli.imaging.images import (  # noqa: E402
    Scratch,
    decode_image,
    from_working,
    keep_freed_memory,
    read_file_bytes,
)

PHOTO = ROOT / "tests" / "data" / "facade" / "building.jpg"
WIDTH, HEIGHT, FOCAL = 4000, 3000, 3200.0
PREVIEW = (800, 600)
#: (pan, tilt) in degrees; the first is the goal's case.
POSES = [(10, 5), (0, 0), (-20, 10), (15, 30)]


def make_photo(folder: Path) -> Path:
    """The 12-megapixel JPEG (quality 90) made from the real photo, in ``folder``."""
    photo = cv2.imread(str(PHOTO))
    height, width = photo.shape[:2]
    crop_width = height * 4 // 3
    left = (width - crop_width) // 2
    big = cv2.resize(photo[:, left:left + crop_width], (WIDTH, HEIGHT),
                     interpolation=cv2.INTER_CUBIC)
    path = folder / "photo12mp.jpg"
    cv2.imwrite(str(path), big, [cv2.IMWRITE_JPEG_QUALITY, 90])
    return path


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    """PSNR in dB of two 8-bit images."""
    error = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return math.inf if error == 0 else 10 * math.log10(255.0**2 / error)


def reference(path: Path, pixel_map) -> np.ndarray:
    """The area-averaged reference: the full decode warped at 8x the output's size (bilinear,
    unfiltered: nothing shrinks there), then each 8x8 block averaged."""
    width, height = pixel_map.size
    fine = pixel_map.then(np.array([[8.0, 0, 3.5], [0, 8.0, 3.5], [0, 0, 1]]),
                          (8 * width, 8 * height))
    scratch = Scratch()
    scratch.read(path)
    big = from_working(scratch.warp(fine))
    return cv2.resize(big, (width, height), interpolation=cv2.INTER_AREA)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=20,
                        help="Alternating rounds of each measurement; the best counts.")
    args = parser.parse_args()
    keep_freed_memory()
    cv2.setNumThreads(1)  # as a batch worker runs
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}, OpenCV {cv2.__version__}, load average "
          f"{os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as folder:
        path = make_photo(Path(folder))
        data = read_file_bytes(path)
        print(f"{path.name}: {WIDTH}x{HEIGHT}, {len(data) / 1e6:.2f} MB, made from "
              f"{PHOTO.relative_to(ROOT)} (upscaled, JPEG quality 90, in a temporary directory)")
        buffer = np.empty(WIDTH * HEIGHT * 4, np.uint8)
        scratch = Scratch()
        for index, (pan, tilt) in enumerate(POSES):
            view = View(pan=pan, tilt=tilt, focal=FOCAL)
            info = plan_image(view, WIDTH, HEIGHT, Framing(max_size=PREVIEW))
            pixel_map = info.pixel_map

            def decode() -> None:
                decode_image(data, padded=True, into=buffer)

            def preview(pixel_map=pixel_map) -> np.ndarray:
                scratch.read(path, preview=pixel_map)
                return scratch.warp(pixel_map, antialias=True).pixels

            def today(pixel_map=pixel_map) -> np.ndarray:
                scratch.read(path)
                return scratch.warp(pixel_map, antialias=True).pixels

            settings = Settings(framing=Framing(max_size=PREVIEW), overwrite=True)
            job = Job(path, Path(folder) / "preview.jpg",
                      {"pan": pan, "tilt": tilt, "focal": FOCAL}, "bench")

            def whole_job(job=job, settings=settings) -> None:
                assert process_job(job, settings, scratch)["status"] == "ok"

            scratch.read(path, preview=pixel_map)
            reduction = scratch.reduction
            new = from_working(scratch.warp(pixel_map, antialias=True))
            scratch.read(path)
            old = from_working(scratch.warp(pixel_map, antialias=True))

            def reduced(reduction=reduction) -> None:
                decode_image(data, padded=True, into=buffer, reduction=reduction)

            homography = np.asarray(pixel_map.reduced(reduction).output_from_input)
            warped = np.empty((*PREVIEW[::-1], 4), np.uint8)

            def floor(reduction=reduction, homography=homography, warped=warped) -> None:
                pixels = decode_image(data, padded=True, into=buffer, reduction=reduction)
                cv2.warpPerspective(pixels, homography, PREVIEW, dst=warped,
                                    flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)

            steps = {"decode": decode, "reduced": reduced, "floor": floor, "preview": preview,
                     "today": today, "job": whole_job}
            best = dict.fromkeys(steps, math.inf)
            names = list(steps)
            wall = dict.fromkeys(steps, math.inf)
            for round_ in range(args.rounds):
                order = names[round_ % len(names):] + names[:round_ % len(names)]
                for name in order if round_ % 2 else order[::-1]:
                    start, cpu = time.perf_counter(), time.thread_time()
                    steps[name]()
                    best[name] = min(best[name], time.thread_time() - cpu)
                    wall[name] = min(wall[name], time.perf_counter() - start)
            truth = reference(path, pixel_map)
            gained, lost = psnr(new, truth), psnr(old, truth)
            ratio = best["preview"] / best["decode"]
            shrink = pixel_map.least_shrink((WIDTH, HEIGHT))
            goal = ""
            if index == 0:
                met = ratio <= 0.6 and gained >= lost - 1
                goal = (f" (goal: ratio <= 0.6 and PSNR at most 1 dB below today's: "
                        f"{'met' if met else 'not met'})")
            print(f"pan {pan:+d} tilt {tilt:+d}: {info.size[0]}x{info.size[1]}, scale "
                  f"{info.frame.scale:.3f}, least shrink {shrink:.2f} -> decoded 1/{reduction}; "
                  f"full decode {best['decode'] * 1e3:.1f} ms, the 1/{reduction} decode alone "
                  f"{best['reduced'] / best['decode']:.2f}x, with a bare warp (floor) "
                  f"{best['floor'] / best['decode']:.2f}x; preview "
                  f"{best['preview'] * 1e3:.1f} ms = {ratio:.2f}x{goal}; today "
                  f"{best['today'] * 1e3:.1f} ms = {best['today'] / best['decode']:.2f}x; "
                  f"whole job {best['job'] * 1e3:.1f} ms = "
                  f"{best['job'] / best['decode']:.2f}x")
            print(f"    wall-clock, best of {args.rounds}: full decode "
                  f"{wall['decode'] * 1e3:.1f} ms, preview "
                  f"{wall['preview'] / wall['decode']:.2f}x, today "
                  f"{wall['today'] / wall['decode']:.2f}x, whole job "
                  f"{wall['job'] / wall['decode']:.2f}x")
            print(f"    PSNR against the area-averaged reference: preview {gained:.2f} dB, "
                  f"today {lost:.2f} dB (difference {lost - gained:+.2f} dB); preview "
                  f"against today {psnr(new, old):.2f} dB")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
