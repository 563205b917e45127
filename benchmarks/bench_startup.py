"""Start-up and ``gsrwt params`` on big sidecars, as ratios measured in one run.

- Start-up: ``gsrwt --version``, ``gsrwt --help`` and one ``gsrwt params`` view (goals: under
  100, 100 and 150 ms), against ``python -c`` of a ten-line ``math`` script (the floor of any
  Python command). Each is run ``--repeat`` times, alternating; the best counts.
- ``gsrwt params --sidecar`` on a CSV of ``--rows`` views against a vectorised numpy script
  (the floor: no validation, one pass, output byte for byte the same, checked): the time
  ratio (goal: at most 1.5), the time to the first row of twice as many rows (goal: under
  200 ms), and the peak memory of both sizes (goal: flat in the number of rows).

    python benchmarks/bench_startup.py [--rows 100000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import filecmp
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FLOOR_SCRIPT = """
import math, sys
pan, tilt, focal = 15.0, 30.0, 280.0
a, b = math.radians(pan), math.radians(tilt)
theta = math.degrees(math.acos(math.cos(a) * math.cos(b)))
delta = math.degrees(math.atan2(math.sin(a), math.cos(a) * math.sin(b)))
shift = focal * math.cos(a) * math.cos(b) / math.sin(math.radians(theta))
gamma = math.degrees(math.atan2(-math.sin(a) * math.cos(b), math.sin(b)))
sys.stdout.write(f"{theta:.6f},{delta:.6f},{shift:.6f},{gamma:.6f}\\n")
"""


def write_sidecar(path: Path, rows: int) -> None:
    """``rows`` views of a 640x480 camera at random pan, tilt and focal length."""
    rng = np.random.default_rng(1)
    pan, tilt = rng.uniform(-60, 60, rows), rng.uniform(-60, 60, rows)
    focal = rng.uniform(200, 2000, rows)
    with path.open("w") as out:
        out.write("image,pan,tilt,focal,width,height\n")
        for index in range(rows):
            out.write(f"img{index:07d}.jpg,{pan[index]:.3f},{tilt[index]:.3f},"
                      f"{focal[index]:.1f},640,480\n")


def floor_params(sidecar: Path) -> None:
    """The vectorised floor: the same table as ``gsrwt params --sidecar`` (csv) in numpy."""
    names = np.loadtxt(sidecar, delimiter=",", skiprows=1, usecols=0, dtype=str)
    pan, tilt, focal, width, height = np.loadtxt(sidecar, delimiter=",", skiprows=1,
                                                 usecols=(1, 2, 3, 4, 5), unpack=True)
    atan2 = np.frompyfunc(math.atan2, 2, 1)
    alpha, beta = np.radians(pan), np.radians(tilt)
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    fore = ca * cb
    sin_theta = np.sqrt(sa * sa + ca * ca * sb * sb)
    theta = np.degrees(atan2(sin_theta, fore).astype(float))
    delta = np.degrees(atan2(sa, ca * sb).astype(float))
    gamma = np.degrees(atan2(-sa * cb, sb).astype(float))
    shift = focal * fore / sin_theta
    vp_x, vp_y = shift * np.cos(np.radians(delta)), shift * -np.sin(np.radians(delta))
    cx, cy = (width - 1) / 2.0, (height - 1) / 2.0
    line_a, line_b = sa, ca * sb
    line_c = cy * -line_b + -cx * line_a + focal * ca * cb
    norm = np.hypot(line_a, line_b)
    line_a, line_b, line_c = line_a / norm, line_b / norm, line_c / norm
    crosses = np.zeros(len(pan), bool)
    for col in (-0.5, width - 0.5):
        for row in (-0.5, height - 0.5):
            crosses |= line_a * col + line_b * row + line_c <= 0

    def text(values: np.ndarray) -> list[str]:
        cells = [f"{v:.6f}".rstrip("0").rstrip(".") for v in values.tolist()]
        return ["0" if cell == "-0" else cell for cell in cells]

    zero = ["0"] * len(pan)
    columns = [names.tolist(), text(pan), text(tilt), text(focal), zero, text(focal),
               text(focal), text(theta), text(delta), text(shift), text(gamma), text(vp_x),
               text(vp_y), text(vp_y + cx), text(cy - vp_x), text(line_a), text(line_b),
               text(line_c), text(fore), np.where(crosses, "true", "false").tolist()]
    out = sys.stdout
    out.write("image,pan_deg,tilt_deg,focal_px,roll_deg,fx_px,fy_px,theta_deg,delta_deg,a_px,"
              "gamma_deg,vp_x,vp_y,vp_col,vp_row,vl_a,vl_b,vl_c,foreshortening,"
              "horizon_in_image\n")
    out.writelines(",".join(cells) + "\n" for cells in zip(*columns))


def timed(command: list[str], output: Path | None = None) -> tuple[float, int]:
    """Wall-clock seconds and peak memory (KiB) of a command, its stdout to ``output``."""
    with open(output or os.devnull, "wb") as sink:
        start = time.perf_counter()
        process = subprocess.Popen(command, stdout=sink)
        _, status, usage = os.wait4(process.pid, 0)
        seconds = time.perf_counter() - start
    assert os.waitstatus_to_exitcode(status) == 0, command
    return seconds, usage.ru_maxrss


def first_row_seconds(command: list[str]) -> float:
    """Seconds until the first row after the header is out on the pipe."""
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE)
    assert process.stdout is not None
    process.stdout.readline()
    process.stdout.readline()
    seconds = time.perf_counter() - start
    process.kill()
    process.wait()
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--floor", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.floor:
        floor_params(args.floor)
        return
    gsrwt = shutil.which("gsrwt") or str(Path(sys.executable).with_name("gsrwt"))
    startup = {
        "python -c (math floor)": [sys.executable, "-c", FLOOR_SCRIPT],
        "gsrwt --version": [gsrwt, "--version"],
        "gsrwt --help": [gsrwt, "--help"],
        "gsrwt params (one view)": [gsrwt, "params", "--pan", "15", "--tilt", "30", "--focal",
                                    "280", "-f", "csv"],
    }
    best = {name: math.inf for name in startup}
    for _ in range(args.repeat):
        for name, command in startup.items():
            best[name] = min(best[name], timed(command)[0])
    goals = {"gsrwt --version": 0.100, "gsrwt --help": 0.100, "gsrwt params (one view)": 0.150}
    print(f"start-up, best of {args.repeat} (this machine: {os.cpu_count()} cores):")
    floor = best["python -c (math floor)"]
    for name, seconds in best.items():
        goal = f"  (goal < {goals[name] * 1000:.0f} ms)" if name in goals else ""
        print(f"  {name:26s} {seconds * 1000:6.0f} ms  {seconds / floor:5.2f}x the floor{goal}")

    with tempfile.TemporaryDirectory(prefix="gsrwt-bench-") as work:
        root = Path(work)
        small, big = root / "views.csv", root / "views2.csv"
        write_sidecar(small, args.rows)
        write_sidecar(big, 2 * args.rows)
        commands = {
            "gsrwt": [gsrwt, "params", "--sidecar", str(small), "-f", "csv"],
            "floor": [sys.executable, __file__, "--floor", str(small)],
        }
        outputs = {name: root / f"{name}.csv" for name in commands}
        times = {name: math.inf for name in commands}
        memory = {}
        for _ in range(max(1, args.repeat // 2)):
            for name, command in commands.items():
                seconds, memory[name] = timed(command, outputs[name])
                times[name] = min(times[name], seconds)
        # Compared in blocks: the children's peak memory (wait4) counts this process's own
        # memory until they exec, so it must stay small.
        same = filecmp.cmp(outputs["gsrwt"], outputs["floor"], shallow=False)
        _, memory_big = timed([gsrwt, "params", "--sidecar", str(big), "-f", "csv"])
        first = min(first_row_seconds([gsrwt, "params", "--sidecar", str(big), "-f", "csv"])
                    for _ in range(3))
    print(f"params --sidecar, {args.rows} rows (output byte-identical to the floor's: {same}):")
    print(f"  gsrwt {times['gsrwt']:.2f} s, floor {times['floor']:.2f} s: "
          f"{times['gsrwt'] / times['floor']:.2f}x  (goal <= 1.5)")
    print(f"  first row of {2 * args.rows} rows after {first * 1000:.0f} ms  (goal < 200 ms)")
    print(f"  peak memory {memory['gsrwt'] / 1024:.0f} MiB for {args.rows} rows, "
          f"{memory_big / 1024:.0f} MiB for {2 * args.rows}  (goal: flat); the floor "
          f"{memory['floor'] / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
