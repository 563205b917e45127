"""Throughput of ``gsrwt rectify VIDEO --poses FILE`` against PyAV alone.

A 640x480, 30 frames/s H.264 clip is made from renders of a textured wall seen by a camera
sweeping in pan and tilt (libx264, CRF 18), with a pose log of one sample every five frames.
Two pipelines over it, each a process of its own, timed wall-clock:

- ``gsrwt``: the real command, ``gsrwt rectify clip.mp4 --poses poses.csv --codec h264
  --jobs P`` (decoding and encoding in the main process, warping on P workers);
- ``floor``: PyAV alone, decoding the clip and encoding every frame again with the same
  encoder and options (libx264, CRF 18, preset veryfast, yuv420p), no warp, each frame
  through BGR (``to_ndarray``, ``from_ndarray``) as an application that looks at its pixels
  does: the issue's floor;
- ``planes``: the same without the BGR round trip, the decoder's frames handed to the
  encoder as they are (a stricter floor: gsrwt warps a frame's YUV planes when the camera
  has no lens, so it no longer pays that round trip either).

It prints frames per second of each and the ratios gsrwt/floor (goal: at most 1.3) and
gsrwt/planes. Each command runs once untimed first, and every run keeps Python's byte-code
(``PYTHONPYCACHEPREFIX`` in the benchmark's temporary folder), as an installed package
does: where ``PYTHONDONTWRITEBYTECODE`` is set and the checkout has no ``__pycache__``,
every start of gsrwt would otherwise compile its ~70 modules again (about 0.2-0.4 s here);
``--no-bytecode-cache`` measures that way.

    python benchmarks/bench_video.py [--frames 300] [--jobs N] [--repeat 3]
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

WIDTH, HEIGHT, FOCAL, RATE = 640, 480, 600.0, 30


def make_clip(folder: Path, frames: int) -> tuple[Path, Path]:
    """The clip (rendered by OpenCV's projection of a textured wall) and its pose log."""
    import av

    rng = np.random.default_rng(0)
    texture = cv2.GaussianBlur(rng.integers(0, 255, (1600, 2000, 3)).astype(np.uint8),
                               (0, 0), 1.5)
    clip, log = folder / "clip.mp4", folder / "poses.csv"
    rows = ["time,pan,tilt"]
    k = np.array([[FOCAL, 0, WIDTH / 2], [0, FOCAL, HEIGHT / 2], [0, 0, 1]])
    # The wall: texture pixels at 1 unit per pixel, 1000 units in front of the camera.
    th, tw = texture.shape[:2]
    corners = np.array([[-tw / 2, -th / 2, 1000], [tw / 2, -th / 2, 1000],
                        [tw / 2, th / 2, 1000], [-tw / 2, th / 2, 1000]], dtype=np.float64)
    source = np.array([[0, 0], [tw, 0], [tw, th], [0, th]], dtype=np.float32)
    with av.open(str(clip), mode="w") as container:
        stream = container.add_stream("libx264", rate=RATE,
                                      options={"crf": "18", "preset": "veryfast"})
        stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "yuv420p"
        for index in range(frames):
            t = index / RATE
            pan, tilt = 20 * np.sin(t), 10 + 10 * np.sin(0.7 * t)
            if index % 5 == 0:
                rows.append(f"{float(t)!r},{float(pan)!r},{float(tilt)!r}")
            # OpenCV's camera: turned by pan about the vertical (y) and tilt about x.
            rvec = cv2.Rodrigues(cv2.Rodrigues(np.array([np.radians(tilt), 0.0, 0.0]))[0]
                                 @ cv2.Rodrigues(np.array([0.0, -np.radians(pan), 0.0]))[0]
                                 )[0]
            points, _ = cv2.projectPoints(corners, rvec, np.zeros(3), k, None)
            homography = cv2.getPerspectiveTransform(source, points.reshape(4, 2)
                                                     .astype(np.float32))
            image = cv2.warpPerspective(texture, homography, (WIDTH, HEIGHT))
            frame = av.VideoFrame.from_ndarray(image, format="bgr24")
            frame.pts = index
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    log.write_text("\n".join(rows) + "\n")
    return clip, log


FLOOR = r"""
import sys, av
source, target = sys.argv[1], sys.argv[2]
with av.open(source) as inp, av.open(target, mode="w") as out:
    video = inp.streams.video[0]
    video.thread_type = "SLICE"
    stream = out.add_stream("libx264", rate=video.average_rate,
                            options={"crf": "18", "preset": "veryfast"})
    stream.width, stream.height, stream.pix_fmt = video.width, video.height, "yuv420p"
    stream.time_base = video.time_base
    for frame in inp.decode(video):
        image = frame.to_ndarray(format="bgr24")
        again = av.VideoFrame.from_ndarray(image, format="bgr24")
        again.pts, again.time_base = frame.pts, frame.time_base
        for packet in stream.encode(again):
            out.mux(packet)
    for packet in stream.encode():
        out.mux(packet)
"""

PLANES = FLOOR.replace(
    """        image = frame.to_ndarray(format="bgr24")
        again = av.VideoFrame.from_ndarray(image, format="bgr24")
        again.pts, again.time_base = frame.pts, frame.time_base
""", """        again = frame
        again.pict_type = 0  # the encoder chooses, as it does for a new frame
""")


def timed(command: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """Wall-clock seconds of ``command``, and the CPU seconds of its process tree."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    if result.returncode:
        raise SystemExit(f"{command[0]} failed: {result.stderr.strip()}")
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 1) - 1),
                        help="gsrwt's -j [default: the command's own, the cores less one]")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-bytecode-cache", action="store_true",
                        help="run in this environment as it is (byte-code as it sets it)")
    args = parser.parse_args()
    gsrwt = Path(sys.executable).with_name("gsrwt")
    with tempfile.TemporaryDirectory() as folder:
        env = None
        if not args.no_bytecode_cache:
            env = {name: value for name, value in os.environ.items()
                   if name != "PYTHONDONTWRITEBYTECODE"}
            env["PYTHONPYCACHEPREFIX"] = str(Path(folder) / "pycache")
        clip, log = make_clip(Path(folder), args.frames)
        commands = {
            "gsrwt": [str(gsrwt), "rectify", str(clip), "--poses", str(log), "--focal",
                      str(FOCAL), "--codec", "h264", "-o", str(Path(folder) / "out"), "-j",
                      str(args.jobs), "-q", "--overwrite"],
            "floor": [sys.executable, "-c", FLOOR, str(clip), str(Path(folder) / "f.mp4")],
            "planes": [sys.executable, "-c", PLANES, str(clip), str(Path(folder) / "f.mp4")],
        }
        for command in commands.values():  # untimed: byte-code and the disk's cache warm
            timed(command, env)
        best = {name: (math.inf, math.inf) for name in commands}
        for repeat in range(args.repeat):
            run = {name: timed(command, env) for name, command in commands.items()}
            print(f"run {repeat + 1}: " + ", ".join(f"{name} {wall:.2f} s (CPU {cpu:.2f})"
                                                   for name, (wall, cpu) in run.items())
                  + f"; gsrwt/floor {run['gsrwt'][0] / run['floor'][0]:.2f}, gsrwt/planes "
                  f"{run['gsrwt'][0] / run['planes'][0]:.2f}", flush=True)
            for name in commands:
                best[name] = min(best[name], run[name])
    for name, (seconds, cpu) in best.items():
        print(f"{name:6s} {seconds:6.2f} s  {args.frames / seconds:6.1f} frames/s  "
              f"(CPU {cpu:.2f} s)")
    print(f"gsrwt/floor {best['gsrwt'][0] / best['floor'][0]:.2f} wall-clock (goal: at most "
          f"1.3), {best['gsrwt'][1] / best['floor'][1]:.2f} in CPU time; "
          f"{args.frames} frames of {WIDTH}x{HEIGHT}, {args.jobs} workers, "
          f"{os.cpu_count()} cores")
    print(f"gsrwt/planes {best['gsrwt'][0] / best['planes'][0]:.2f} wall-clock, "
          f"{best['gsrwt'][1] / best['planes'][1]:.2f} in CPU time (the floor without BGR)")


if __name__ == "__main__":
    main()
