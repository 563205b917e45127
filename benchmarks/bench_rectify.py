"""Throughput of ``gsrwt rectify`` on 12-megapixel JPEGs, as ratios measured in one run.

Four pipelines over the same directory of JPEGs, each as its own process tree with the same
number of worker processes, forked as gsrwt forks its workers, timed wall-clock:

- ``gsrwt``: the real command, ``gsrwt rectify DIR --sidecar ... -o OUT --jobs P``;
- ``floor``: the minimal script of the same OpenCV calls: decode (``cv2.imdecode``, what
  ``cv2.imread`` does), one ``cv2.warpPerspective`` with gsrwt's homography into gsrwt's
  frame, encode (quality 95), an atomic write;
- ``best floor``: the same with the best decoder call found (libjpeg-turbo through
  simplejpeg, straight to BGRA into reused memory, warped as BGRA);
- ``skimage``: OpenCV's I/O with ``skimage.transform.warp`` (bilinear, its 3x3 fast path).

It prints images per second, the ratios gsrwt/floor (goal: at most 1.15; below 1 by using
the codec better than ``imread`` does), gsrwt/best floor (goal: at most 1.3) and
skimage/gsrwt (goal: at least 5), and the peak memory of a gsrwt worker (its loop run over
every image in a fresh process) above the same process idle, in units of one decoded image
(goal: under 4).

With ``--small N`` it compares gsrwt and the floors on N frames of 640x480 instead (goal:
within 1.10x of the floor).

    python benchmarks/bench_rectify.py [--images 64] [--jobs N] [--repeat 3] [--keep DIR]
    python benchmarks/bench_rectify.py --small 2000
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

WIDTH, HEIGHT, FOCAL = 4000, 3000, 3200.0
POSES = [(15, 30), (-20, 10), (30, -15), (-10, -25), (25, 20), (5, 35), (-30, 5), (0, 20)]


def make_images(folder: Path, count: int, size: tuple[int, int] = (WIDTH, HEIGHT),
                focal: float = FOCAL) -> None:
    """Textured JPEGs (12 megapixels unless ``size`` says, quality 95) and their sidecar."""
    width, height = size
    rng = np.random.default_rng(0)
    coarse = rng.uniform(0, 255, (height // 8, width // 8, 3)).astype(np.uint8)
    base = cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    lines = ["image,pan,tilt,focal"]
    for index in range(count):
        image = np.roll(base, 37 * index, axis=1)
        name = f"img{index:04d}.jpg"
        cv2.imwrite(str(folder / name), image, [cv2.IMWRITE_JPEG_QUALITY, 95])
        pan, tilt = POSES[index % len(POSES)]
        lines.append(f"{name},{pan},{tilt},{focal}")
    (folder / "views.csv").write_text("\n".join(lines) + "\n")


#: The small frames of ``--small``: a robot's 640x480 camera.
SMALL, SMALL_FOCAL = (640, 480), 520.0


def small_frames(root: Path, count: int, jobs: int, repeat: int, gsrwt: str) -> None:
    """``count`` 640x480 frames: gsrwt against the two floors, alternating; the best counts."""
    folder = root / "small"
    if len(list(folder.glob("img*.jpg"))) != count:
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        make_images(folder, count, SMALL, SMALL_FOCAL)
    me = [sys.executable, __file__, "--folder", str(folder), "--jobs", str(jobs)]
    commands = {
        "gsrwt": [gsrwt, "rectify", str(folder), "--sidecar", str(folder / "views.csv"),
                  "-o", str(root / "small-gsrwt"), "--jobs", str(jobs), "--quiet",
                  "--overwrite"],
        "floor": [*me, "--stage", "floor", "--out", str(root / "small-floor")],
        "best floor": [*me, "--stage", "best-floor", "--out", str(root / "small-best")],
    }
    best = {name: min(timed(command) for _ in range(1)) for name, command in commands.items()}
    for _ in range(repeat - 1):
        for name, command in commands.items():
            best[name] = min(best[name], timed(command))
    print(f"{count} frames of {SMALL[0]}x{SMALL[1]}, {jobs} processes, best of {repeat}:")
    for name, seconds in best.items():
        print(f"  {name:10s} {seconds:6.2f} s  {count / seconds:7.1f} images/s  "
              f"{seconds / count * 1000 * jobs:5.2f} ms of a core per image")
    print(f"gsrwt time / OpenCV floor time:   {best['gsrwt'] / best['floor']:.2f}"
          "  (goal <= 1.10)")
    print(f"gsrwt time / best-codec floor time:   {best['gsrwt'] / best['best floor']:.2f}")


#: The wide-angle lens of the ``--lens`` runs (plumb_bob, as a calibration gives it).
LENS = {"k1": -0.12, "k2": 0.03, "p1": 0.0004, "p2": -0.0003}


def write_lens_sidecars(folder: Path) -> tuple[Path, Path]:
    """Sidecars of the same images seen through :data:`LENS`: with the 8 poses of
    :data:`POSES` repeated (a pan-tilt unit's), and with a distinct pose for every image."""
    columns = "image,pan,tilt,focal,distortion_model," + ",".join(LENS)
    coefficients = ",".join(str(v) for v in LENS.values())
    repeated, distinct = [columns], [columns]
    for index, (path, pan, tilt, _) in enumerate(_views(folder)):
        repeated.append(f"{path.name},{pan},{tilt},{FOCAL},plumb_bob,{coefficients}")
        distinct.append(f"{path.name},{pan + 0.01 * index},{tilt},{FOCAL},plumb_bob,"
                        f"{coefficients}")
    paths = folder / "views_lens_repeated.csv", folder / "views_lens_distinct.csv"
    for path, lines in zip(paths, (repeated, distinct)):
        path.write_text("\n".join(lines) + "\n")
    return paths


def _views(folder: Path) -> list[tuple[Path, float, float, float]]:
    """(image, pan, tilt, focal) of every row of the folder's ``views.csv``."""
    rows = (folder / "views.csv").read_text().splitlines()[1:]
    cells = [row.split(",") for row in rows]
    return [(folder / c[0], float(c[1]), float(c[2]), float(c[3])) for c in cells]


def _task(path: Path, out: Path, pan: float, tilt: float, focal: float) -> tuple:
    """A floor's task: the image, its output, and the homography and size of gsrwt's frame."""
    from gsrwt_cli import View
    from gsrwt_cli.api.rectify import plan_image
    from gsrwt_cli.imaging.images import image_file_size

    width, height = image_file_size(path)
    plan = plan_image(View(pan, tilt, focal), width, height)
    return str(path), str(out / path.name), plan.homography, plan.size


_buffer = np.empty(0, np.uint8)


def _read(source: str) -> np.ndarray:
    """OpenCV's decode of the bytes Python read (``cv2.imdecode``, as ``cv2.imread`` does)."""
    return cv2.imdecode(np.fromfile(source, np.uint8), cv2.IMREAD_UNCHANGED)


def _read_best(source: str) -> np.ndarray:
    """The best codec call here: libjpeg-turbo (simplejpeg) straight to BGRA, into memory
    reused from image to image (the warp's layout; OpenCV's encoder drops the fourth channel
    itself)."""
    import simplejpeg

    global _buffer
    data = Path(source).read_bytes()
    height, width, _, _ = simplejpeg.decode_jpeg_header(data)
    if _buffer.nbytes < height * width * 4:
        _buffer = np.empty(height * width * 4, np.uint8)
    return simplejpeg.decode_jpeg(data, colorspace="BGRA", buffer=_buffer)


def _write(target: str, image: np.ndarray) -> None:
    """OpenCV's JPEG encode (quality 95), written atomically (temporary file, rename)."""
    from gsrwt_cli.io.outputs import write_atomic

    ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    write_atomic(target, encoded.tobytes())


def _floor_one(task: tuple) -> None:
    """The minimal script of the same OpenCV calls: decode, one warp, encode, write."""
    source, target, homography, size = task
    _write(target, cv2.warpPerspective(_read(source), homography, size))


def _io_floor_one(task: tuple) -> None:
    """Decode, encode, write: no warp (the floor of the real-cameras goals)."""
    source, target, _, _ = task
    _write(target, _read(source))


def _best_floor_one(task: tuple) -> None:
    source, target, homography, size = task
    _write(target, cv2.warpPerspective(_read_best(source), homography, size))


def _skimage_one(task: tuple) -> None:
    from skimage.transform import warp

    source, target, homography, (width, height) = task
    # skimage's inverse_map takes output (col, row) to input (col, row), like OpenCV's.
    # The 3x3 matrix itself: warp's fast path (a callable would be called per pixel block).
    warped = warp(_read(source), np.linalg.inv(homography), output_shape=(height, width),
                  order=1, preserve_range=True)
    _write(target, warped.astype(np.uint8))


def _init(threads: int) -> None:
    """Each pool process as a gsrwt worker starts: its OpenCV threads and its heap."""
    from gsrwt_cli.imaging.images import keep_freed_memory

    keep_freed_memory()
    cv2.setNumThreads(threads)


def run_pool(stage: str, folder: Path, out: Path, jobs: int) -> None:
    """Entry point of the floor and skimage pipelines (run in their own process)."""
    out.mkdir(parents=True, exist_ok=True)
    tasks = [_task(path, out, pan, tilt, focal) for path, pan, tilt, focal in _views(folder)]
    work = {"floor": _floor_one, "best-floor": _best_floor_one, "io-floor": _io_floor_one,
            "skimage": _skimage_one}[stage]
    # Started as gsrwt starts its workers: forked from a process that has run no OpenCV code.
    context = multiprocessing.get_context("fork")
    with context.Pool(jobs, initializer=_init, initargs=(1 if jobs > 1 else 0,)) as pool:
        list(pool.imap(work, tasks, chunksize=1))


def timed(command: list[str]) -> float:
    """Wall-clock seconds of a command. What the previous one wrote is flushed to disk first
    (``sync``), so that its writeback does not land in this one's time."""
    os.sync()
    start = time.perf_counter()
    subprocess.run(command, check=True)
    return time.perf_counter() - start


def high_water_kib() -> int:
    """This process's peak resident memory (VmHWM, reset at exec unlike ru_maxrss)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    raise RuntimeError("no VmHWM in /proc/self/status")


def worker_memory(folder: Path, out: Path) -> None:
    """Run one gsrwt worker's loop over all images; print idle and peak memory (KiB)."""
    from gsrwt_cli.batch.rectify_jobs import ImageWorker, Job, Settings

    worker = ImageWorker.in_own_process(Settings(overwrite=True), opencv_threads=1)
    idle = high_water_kib()
    for path, pan, tilt, _ in _views(folder):
        job = Job(path, out / path.name, {"pan": pan, "tilt": tilt, "focal": FOCAL}, "bench")
        assert worker(job)["status"] == "ok"
    print(idle, high_water_kib())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=64)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--repeat", type=int, default=3,
                        help="Runs of gsrwt and of the floor, alternating; the best counts.")
    parser.add_argument("--keep", type=Path, help="Use (and keep) this directory for the data.")
    parser.add_argument("--lens", action="store_true",
                        help="Also time the images through a plumb_bob lens (one remap pass), "
                             "with repeated poses (cached maps) and with distinct ones.")
    parser.add_argument("--small", type=int, metavar="N",
                        help="Instead: N frames of 640x480 (a robot's camera) against the "
                             "floors.")
    parser.add_argument("--stage", choices=["floor", "best-floor", "io-floor", "skimage",
                                            "memory"],
                        help=argparse.SUPPRESS)
    parser.add_argument("--folder", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.stage == "memory":
        worker_memory(args.folder, args.out)
        return
    if args.stage:
        run_pool(args.stage, args.folder, args.out, args.jobs)
        return

    root = args.keep or Path(tempfile.mkdtemp(prefix="gsrwt-bench-"))
    if args.small:
        gsrwt = shutil.which("gsrwt") or str(Path(sys.executable).with_name("gsrwt"))
        small_frames(root, args.small, args.jobs, args.repeat, gsrwt)
        if not args.keep:
            shutil.rmtree(root)
        return
    folder = root / "in"
    if not (folder / "views.csv").exists() or len(_views(folder)) != args.images:
        folder.mkdir(parents=True, exist_ok=True)
        make_images(folder, args.images)
    gsrwt = shutil.which("gsrwt") or str(Path(sys.executable).with_name("gsrwt"))
    me = [sys.executable, __file__, "--folder", str(folder), "--jobs", str(args.jobs)]
    # The inputs were just written (or read by an earlier run): all read them from the page
    # cache. gsrwt and the floor alternate --repeat times and each keeps its best time, so
    # that a noisy neighbour on the machine slows both or neither; scikit-image runs once.
    commands = {
        "gsrwt": [gsrwt, "rectify", str(folder), "--sidecar", str(folder / "views.csv"),
                  "-o", str(root / "gsrwt"), "--jobs", str(args.jobs), "--quiet",
                  "--overwrite"],
        "floor": [*me, "--stage", "floor", "--out", str(root / "floor")],
        "best floor": [*me, "--stage", "best-floor", "--out", str(root / "best-floor")],
    }
    if args.lens:
        commands["I/O floor"] = [*me, "--stage", "io-floor", "--out", str(root / "io-floor")]
        for name, sidecar in zip(("lens, repeated poses", "lens, distinct poses"),
                                 write_lens_sidecars(folder)):
            commands[name] = [*commands["gsrwt"][:4], str(sidecar), *commands["gsrwt"][5:]]
    runs: dict[str, list[float]] = {name: [] for name in commands}
    # The command run after another is slowed by what that one leaves behind (measured: +10 %
    # after the I/O floor, whichever it was), so no command may always follow the same one:
    # each round starts one command later, and every other round runs backwards (rotating
    # alone kept the cycle, and the lens runs with repeated poses always followed the I/O
    # floor: 1.52-1.68x against 1.39-1.50x for distinct poses, the same work).
    names = list(commands)
    for round_ in range(args.repeat):
        order = names[round_ % len(names):] + names[:round_ % len(names)]
        for name in (order if round_ % 2 == 0 else order[::-1]):
            runs[name].append(timed(commands[name]))
    results = {name: min(times) for name, times in runs.items()}
    results["skimage"] = timed([*me, "--stage", "skimage", "--out", str(root / "skimage")])
    decoded_kib = WIDTH * HEIGHT * 3 / 1024
    memory = subprocess.run([*me, "--stage", "memory", "--out", str(root / "memory")],
                            capture_output=True, text=True, check=True).stdout.split()
    idle, peak = (int(v) for v in memory)
    rate = {name: args.images / seconds for name, seconds in results.items()}
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}, "
          f"OpenCV {cv2.__version__}; {args.images} JPEGs of {WIDTH}x{HEIGHT}, {args.jobs} "
          f"processes; best of {args.repeat} for gsrwt and the floor")
    for name in ("floor", "best floor", "gsrwt", "skimage"):
        print(f"  {name:10s} {results[name]:6.2f} s  {rate[name]:6.2f} images/s")
    print(f"gsrwt time / OpenCV floor time:   {results['gsrwt'] / results['floor']:.2f}"
          "  (goal <= 1.15; stretch: < 1)")
    print(f"gsrwt time / best-codec floor time:   {results['gsrwt'] / results['best floor']:.2f}"
          "  (goal <= 1.3)")
    if "I/O floor" in results:  # what a warp alone costs, for the lens goals' scale
        print(f"OpenCV floor (decode, warpPerspective, encode) / I/O floor: "
              f"{results['floor'] / results['I/O floor']:.2f}  (no goal: the warp's own cost)")
    for name, goal in (("lens, repeated poses", 1.45), ("lens, distinct poses", 1.6)):
        if name in results:
            print(f"{name} / I/O floor (no warp): {results[name] / results['I/O floor']:.2f}"
                  f"  (goal <= {goal}; {args.images / results[name]:.2f} images/s)")
    print(f"skimage time / gsrwt time:     {results['skimage'] / results['gsrwt']:.2f}"
          "  (goal >= 5)")
    print(f"gsrwt worker peak memory:      {(peak - idle) / 1024:.0f} MiB above its idle "
          f"{idle / 1024:.0f} MiB = {(peak - idle) / decoded_kib:.2f} decoded images  (goal < 4)")
    if not args.keep:
        shutil.rmtree(root)


if __name__ == "__main__":
    main()
