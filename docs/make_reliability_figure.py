"""Make docs/reliability.png: the reliability plot of `gsrwt estimate`'s confidence on the
York Urban DB's training split. For each confidence bin of the accepted estimates (status
ok), the share of photos whose pose is within 2 degrees (vertical and wall normal) against
the bin's mean confidence, with the focal length given (calibrated) and without (estimated
from the photo, EXIF removed); the diagonal is a perfectly calibrated confidence. Bars: the
68 % Wilson interval of each share; below, how many photos each bin holds.

    python docs/make_reliability_figure.py PATH-TO-york-urban-train
    python docs/make_reliability_figure.py --json OUTPUT.json

The first runs `python benchmarks/bench_real_photos.py PATH --json`; the second draws a
saved output of it.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
BENCHMARK = ROOT / "benchmarks" / "bench_real_photos.py"

WIDTH, PLOT_HEIGHT, COUNT_HEIGHT = 760, 440, 120
LEFT, RIGHT, TOP, GAP, BOTTOM = 70, 200, 66, 40, 50
FONT = cv2.FONT_HERSHEY_SIMPLEX
INK, GRID = (40, 40, 40), (225, 225, 225)
#: One colour (BGR) and marker per run, in the benchmark's order.
STYLES = [((180, 110, 30), "circle"), ((30, 120, 230), "square")]


def benchmark_json(data: Path) -> dict:
    """``bench_real_photos.py DATA --json``'s output."""
    done = subprocess.run([sys.executable, str(BENCHMARK), str(data), "--json"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(done.stderr.strip() or f"{BENCHMARK.name} failed")
    return json.loads(done.stdout)


def wilson(share: float, count: int, z: float = 1.0) -> tuple[float, float]:
    """The Wilson score interval of a binomial share of ``count`` trials (``z`` standard
    deviations: 1 is 68 %)."""
    centre = (share + z * z / (2 * count)) / (1 + z * z / count)
    half = z * math.sqrt(share * (1 - share) / count + z * z / (4 * count * count)) / (
        1 + z * z / count)
    return centre - half, centre + half


def text(canvas: np.ndarray, words: str, at: tuple[float, float], scale: float = 0.45,
         colour: tuple[int, int, int] = INK, anchor: str = "left") -> None:
    """Write ``words`` with its baseline at ``at``, its left, centre or right end there."""
    (width, _), _ = cv2.getTextSize(words, FONT, scale, 1)
    x = at[0] - {"left": 0, "centre": width / 2, "right": width}[anchor]
    cv2.putText(canvas, words, (round(x), round(at[1])), FONT, scale, colour, 1, cv2.LINE_AA)


def marker(canvas: np.ndarray, at: tuple[int, int], shape: str,
           colour: tuple[int, int, int]) -> None:
    if shape == "circle":
        cv2.circle(canvas, at, 6, colour, -1, cv2.LINE_AA)
    else:
        cv2.rectangle(canvas, (at[0] - 5, at[1] - 5), (at[0] + 5, at[1] + 5), colour, -1)


def draw(result: dict) -> np.ndarray:
    """The reliability plot and the bins' counts of the benchmark's ``result``: its first two
    runs, focal length given and none, on which the confidence was fitted (the third, the
    photos as taken with their EXIF focal length, is in the benchmark's table)."""
    runs = result["runs"][:len(STYLES)]
    edges = sorted({edge for run in runs for b in run["calibration"] for edge in
                    (b["low"], b["high"])})
    low = min([b["low"] for run in runs for b in run["calibration"] if b["count"]] + [0.5])
    edges = [edge for edge in edges if edge >= low]
    # The share's axis from 0.5, or lower to hold every interval, in tenths.
    floor = min([0.5] + [wilson(b["fraction_within"], b["count"])[0] for run in runs
                         for b in run["calibration"] if b["count"] and b["low"] >= low])
    floor = math.floor(floor * 10) / 10
    height = TOP + PLOT_HEIGHT + GAP + COUNT_HEIGHT + BOTTOM
    canvas = np.full((height, WIDTH, 3), 255, np.uint8)
    x0, x1 = LEFT, WIDTH - RIGHT
    plot_bottom = TOP + PLOT_HEIGHT
    count_top, count_bottom = plot_bottom + GAP, plot_bottom + GAP + COUNT_HEIGHT

    def x_of(confidence: float) -> int:
        return round(x0 + (confidence - low) / (1 - low) * (x1 - x0))

    def y_of(share: float) -> int:
        return round(plot_bottom - (share - floor) / (1 - floor) * PLOT_HEIGHT)

    for tick in np.arange(floor, 1.05, 0.1):
        cv2.line(canvas, (x0, y_of(tick)), (x1, y_of(tick)), GRID, 1)
        text(canvas, f"{tick:.1f}", (x0 - 8, y_of(tick) + 5), anchor="right")
    for edge in edges:
        for top, bottom in ((TOP, plot_bottom), (count_top, count_bottom)):
            cv2.line(canvas, (x_of(edge), top), (x_of(edge), bottom), GRID, 1)
        text(canvas, f"{edge:.1f}", (x_of(edge), count_bottom + 20), anchor="centre")
    # The diagonal: a confidence that is the chance of being within 2 degrees.
    cv2.line(canvas, (x_of(low), y_of(low)), (x_of(1), y_of(1)), (150, 150, 150), 1, cv2.LINE_AA)
    for frame in ((x0, TOP, x1, plot_bottom), (x0, count_top, x1, count_bottom)):
        cv2.rectangle(canvas, frame[:2], frame[2:], INK, 1)
    text(canvas, f"gsrwt estimate on the York Urban DB's training split ({result['photos']} "
         "photos)", (x0, 22), 0.55)
    text(canvas, "share of the bin within 2 deg (vertical and wall)", (12, TOP - 12), 0.4)
    text(canvas, "confidence (each bin's mean; the bins as the grid)", ((x0 + x1) / 2,
         count_bottom + 42), 0.45, anchor="centre")
    text(canvas, "photos", (12, count_top + 12), 0.4)

    most = max(b["count"] for run in runs for b in run["calibration"]) or 1
    bar = 14
    for index, (run, (colour, shape)) in enumerate(zip(runs, STYLES)):
        points = []
        for b in run["calibration"]:
            if not b["count"] or b["low"] < low:
                continue
            share, count = b["fraction_within"], b["count"]
            at = (x_of(b["mean_confidence"]), y_of(share))
            lower, upper = wilson(share, count)
            cv2.line(canvas, (at[0], y_of(lower)), (at[0], y_of(upper)), colour, 1, cv2.LINE_AA)
            points.append(at)
            # Counts: one bar per run, side by side in the bin.
            middle = (x_of(b["low"]) + x_of(b["high"])) // 2
            left = middle - bar - 2 + index * (bar + 4)
            top = round(count_bottom - count / most * (COUNT_HEIGHT - 18))
            cv2.rectangle(canvas, (left, top), (left + bar, count_bottom), colour, -1)
            text(canvas, str(count), (left + bar / 2, top - 4), 0.35, colour, "centre")
        cv2.polylines(canvas, [np.array(points, np.int32)], False, colour, 2, cv2.LINE_AA)
        for at in points:
            marker(canvas, at, shape, colour)
        # Legend: the run's name and its count of accepted estimates.
        accepted = sum(b["count"] for b in run["calibration"])
        legend_y = TOP + 20 + index * 52
        marker(canvas, (x1 + 20, legend_y - 5), shape, colour)
        name = "focal length given" if index == 0 else "no focal length"
        text(canvas, name, (x1 + 34, legend_y), 0.45, colour)
        text(canvas, f"{accepted} of {result['photos']} ok", (x1 + 34, legend_y + 18), 0.4)
    below = TOP + 20 + len(runs) * 52
    cv2.line(canvas, (x1 + 12, below - 5), (x1 + 28, below - 5), (150, 150, 150), 1, cv2.LINE_AA)
    text(canvas, "perfectly calibrated", (x1 + 34, below), 0.4)
    text(canvas, "bars: 68 % interval", (x1 + 14, below + 24), 0.4)
    text(canvas, f"{result['date']}", (x1 + 14, below + 44), 0.4)
    return canvas


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", nargs="?", type=Path,
                        help="the York Urban training split (truth.csv, images/)")
    parser.add_argument("--json", type=Path, help="a saved `bench_real_photos.py --json` output")
    arguments = parser.parse_args()
    if (arguments.data is None) == (arguments.json is None):
        parser.error("give the data's path or --json FILE")
    result = (json.loads(arguments.json.read_text()) if arguments.json
              else benchmark_json(arguments.data))
    cv2.imwrite(str(ROOT / "docs" / "reliability.png"), draw(result))


if __name__ == "__main__":
    main()
