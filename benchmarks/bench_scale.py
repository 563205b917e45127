"""``gsrwt rectify --scheduler local`` against the worker-process pool, as ratios of one run.

Two measurements, each the real command in its own process tree, wall-clock, best of
``--repeat`` runs taken in alternation (so both see the same load on a shared machine):

- throughput on 12-megapixel JPEGs (bench_rectify.py's): ``-j 2`` worker processes against
  ``--scheduler local -j 2`` (a Dask LocalCluster of two single-threaded worker processes),
  for whole runs (the cluster's start included) and past the fixed costs of a run
  ((N - 1) / (t(N) - t(1)), the one-image run's time taken off); goal: Dask within 10 %
  (ratio dask/pool at least 0.90);
- the scheduler's overhead per task, on ``--small`` tiny PNGs (64x48) where the work is
  almost nothing: ((dask(N) - dask(1)) - (pool(N) - pool(1))) / (N - 1), the fixed costs of
  a run (the cluster's start, imports) cancelled by the one-image runs; goal: under 5 ms.

    python benchmarks/bench_scale.py [--images 24] [--small 2000] [--repeat 2]
"""

from __future__ import annotations

import argparse
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_rectify import make_images  # noqa: E402

GSRWT = Path(sys.executable).with_name("gsrwt")


def make_small(folder: Path, count: int) -> None:
    """``count`` distinct 64x48 PNGs and their sidecar."""
    rng = np.random.default_rng(1)
    lines = ["image,pan,tilt,focal"]
    for index in range(count):
        name = f"s{index:05d}.png"
        cv2.imwrite(str(folder / name), rng.integers(0, 255, (48, 64, 3), dtype=np.uint8))
        lines.append(f"{name},{10 + index % 20},{5 + index % 15},60")
    (folder / "views.csv").write_text("\n".join(lines) + "\n")


def timed(folder: Path, out: Path, *extra: str) -> float:
    """Seconds of one ``gsrwt rectify`` run into a fresh ``out``."""
    shutil.rmtree(out, ignore_errors=True)
    command = [str(GSRWT), "rectify", str(folder), "--sidecar", str(folder / "views.csv"),
               "-o", str(out), "-q", "-j", "2", *extra]
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True,
                            env={**os.environ, "DASK_SCHEDULER_ADDRESS": ""})
    elapsed = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed: {result.stderr}")
    return elapsed


def best_of(repeat: int, folder: Path, out: Path) -> tuple[float, float]:
    """Best seconds of the pool and of the local cluster, runs alternating."""
    pool, dask = [], []
    for _ in range(repeat):
        pool.append(timed(folder, out))
        dask.append(timed(folder, out, "--scheduler", "local"))
    return min(pool), min(dask)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=24, help="12 MP JPEGs")
    parser.add_argument("--small", type=int, default=2000, help="tiny PNGs")
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}, load average {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        big, small, one = root / "big", root / "small", root / "one"
        for folder in (big, small, one):
            folder.mkdir()
        make_images(big, args.images)
        make_small(small, args.small)
        make_small(one, 1)

        big_one = root / "big_one"
        big_one.mkdir()
        make_images(big_one, 1)
        pool, dask = best_of(args.repeat, big, root / "out")
        pool_1, dask_1 = best_of(args.repeat, big_one, root / "out")
        steady_pool = (args.images - 1) / (pool - pool_1)
        steady_dask = (args.images - 1) / (dask - dask_1)
        print(f"12 MP x {args.images}, 2 workers, whole runs: pool {pool:.2f} s, "
              f"--scheduler local {dask:.2f} s (its cluster's start included); "
              f"ratio dask/pool {pool / dask:.3f}")
        print(f"12 MP, 2 workers, throughput past the fixed costs (one-image runs: pool "
              f"{pool_1:.2f} s, dask {dask_1:.2f} s): pool {steady_pool:.2f} img/s, "
              f"dask {steady_dask:.2f} img/s; ratio dask/pool {steady_dask / steady_pool:.3f} "
              f"(goal >= 0.90)")

        pool_n, dask_n = best_of(args.repeat, small, root / "out")
        pool_1, dask_1 = best_of(args.repeat, one, root / "out")
        overhead = ((dask_n - dask_1) - (pool_n - pool_1)) / (args.small - 1)
        print(f"64x48 x {args.small}: pool {pool_n:.2f} s (1 image {pool_1:.2f} s), "
              f"--scheduler local {dask_n:.2f} s (1 image {dask_1:.2f} s)")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")
        print(f"per-task overhead of the scheduler {overhead * 1000:.2f} ms/image "
              f"(goal < 5); per image: pool {(pool_n - pool_1) / (args.small - 1) * 1000:.2f} "
              f"ms, dask {(dask_n - dask_1) / (args.small - 1) * 1000:.2f} ms")


if __name__ == "__main__":
    main()
