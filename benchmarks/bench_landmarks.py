"""Landmarks on real photos and realistic renders: recall, precision and time of ``gsrwt lines``.

Three labelled sets (see ``tests/helpers/chessboard_edges.py`` and ``door_renders.py``):
OpenCV's 13 chessboard photos rectified with their solvePnP poses (every square's sides
known from ``cv2.findChessboardCorners`` on the raw photo), the same photos at 15 % contrast
with noise and JPEG, and rendered doors (a white frame on a white wall among them) at pans up
to 40 degrees through blur, noise and JPEG. Scores as issue 15 defines them; time per
640x480 image in this one process with OpenCV on one thread (edge stage, fill mask,
magnification and Hough): the median over images of each image's best of ``--repeat``
runs, wall clock and CPU time (the CPU time is the steadier on a shared machine).
Goals: recall >= 0.75, precision >= 0.55 (vertical) and >= 0.45 (all), at most 100 ms per
image.

``--source-edges`` also measures the other edge stage of the issue: edges found in the
source photo and mapped into the frontal view through the pixel map.

    python benchmarks/bench_landmarks.py [--repeat 5] [--source-edges]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the tests' helpers

from gsrwt_cli.vision.edges import FILL_MARGIN, line_edges  # noqa: E402
from gsrwt_cli.vision.frontal_pixels import frontal_edges, seen  # noqa: E402
from gsrwt_cli.vision.landmarks import EdgeMap, hough_lines  # noqa: E402
from tests.helpers import chessboard_edges, door_renders  # noqa: E402


def frontal_stage(board, compensate: bool = True) -> EdgeMap:
    view = board.view
    if compensate:
        return frontal_edges(view.pixels, view.pixel_map, view.source_size)
    return line_edges(view.pixels, valid=seen(view.pixel_map, view.source_size))


def source_stage(board) -> EdgeMap:
    """Edges of the source photo, their pixels mapped (rounded) into the frontal view; the
    orientations, support and weights of the frontal view's own gradient."""
    view = board.view
    source = board.source if board.source is not None else cv2.imread(
        str(view.path), cv2.IMREAD_GRAYSCALE)
    rows, cols = np.nonzero(line_edges(source).mask)
    mapped = np.rint(view.pixel_map.to_output(np.column_stack([cols, rows]).astype(float)))
    frontal = frontal_stage(board)
    height, width = frontal.mask.shape
    inside = np.all(np.isfinite(mapped), axis=1)
    mapped = mapped[inside].astype(int)
    inside = ((mapped[:, 0] >= 0) & (mapped[:, 0] < width) & (mapped[:, 1] >= 0)
              & (mapped[:, 1] < height))
    mask = np.zeros((height, width), bool)
    mask[mapped[inside, 1], mapped[inside, 0]] = True
    valid = cv2.erode(seen(view.pixel_map, view.source_size).astype(np.uint8),
                      np.ones((3, 3), np.uint8), iterations=FILL_MARGIN).astype(bool)
    return EdgeMap(frontal.magnitude, frontal.orientation_deg, mask & valid, frontal.support,
                   frontal.weight, frontal.gradient)


def measure(boards, stage, repeat: int) -> tuple[chessboard_edges.Score, float, float]:
    total = chessboard_edges.Score()
    times, cpu_times = [], []
    for board in boards:
        runs, cpu_runs = [], []
        for _ in range(repeat):
            start, cpu_start = time.perf_counter(), time.process_time()
            found = hough_lines(board.view.pixels, edges=stage(board))
            runs.append(time.perf_counter() - start)
            cpu_runs.append(time.process_time() - cpu_start)
        times.append(min(runs))
        cpu_times.append(min(cpu_runs))
        total.add(chessboard_edges.score(board, found))
    return total, 1000 * statistics.median(times), 1000 * statistics.median(cpu_times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--source-edges", action="store_true")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    boards = [chessboard_edges.label(view) for view in chessboard_edges.frontal_views()]
    sets = {
        "chessboard photos": boards,
        "low-contrast photos": chessboard_edges.low_contrast(boards),
        "rendered doors": door_renders.door_views(),
    }
    stages = {"frontal (default)": frontal_stage}
    if args.source_edges:
        stages["frontal, no magnification"] = lambda board: frontal_stage(board, False)
        stages["source, mapped"] = source_stage
    print(f"{'set':22s} {'edge stage':26s} {'recall':>14s} {'prec. vert.':>14s} "
          f"{'prec. all':>14s} {'ms/image':>9s} {'cpu ms':>7s}")
    for set_name, labelled in sets.items():
        for stage_name, stage in stages.items():
            score, ms, cpu_ms = measure(labelled, stage, args.repeat)
            print(f"{set_name:22s} {stage_name:26s} "
                  f"{score.recall:6.3f} ({score.found:3d}/{score.long_vertical:3d}) "
                  f"{score.vertical_precision:6.3f} ({score.vertical_on_edges:3d}/"
                  f"{score.vertical_lines:3d}) {score.precision:6.3f} ({score.on_edges:3d}/"
                  f"{score.lines:3d}) {ms:9.1f} {cpu_ms:7.1f}")
    print("goals: recall >= 0.75, precision >= 0.55 (vertical), >= 0.45 (all), <= 100 ms")


if __name__ == "__main__":
    main()
