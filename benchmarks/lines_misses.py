"""Why ``gsrwt lines`` misses the long vertical labels of York Urban: one reason per miss.

Each long vertical label (``lines_measure``: > 40 px in the frontal view) that no reported
line finds gets the first of these reasons that applies, in this order:

- ``tilted label``: no line within 1 degree of vertical can pass within 2 px of both of its
  ends (the label itself leans: its ends are off by a pixel or two, or the pose is);
- ``no edge pixels``: fewer than half of its length has an edge pixel (the thin hysteresis
  edges of ``gsrwt lines``) within 2 px of it, oriented within 15 degrees of its normal;
- ``edges in pieces``: they do, but no run of them with gaps of at most ``max_gap`` (10 px)
  covers half of it;
- ``off by > 2 px / > 1 deg``: a reported line covers half of it within 4 px and 3 degrees
  but misses the 2-px or the 1-degree bar (split by which);
- ``pieces too short``: reported lines within 2 px and 1 degree cover some of it, each less
  than half;
- ``merged / crossed``: a reported line more than 3 degrees off runs through half of it
  (its pixels went to that line);
- ``contrast bar`` / ``min length`` / ``fill`` / ``gap``: found when that one test of the
  Hough stage is relaxed (the contrast bar off; min length 10 px; no fill test; gaps of
  30 px joined);
- ``near a parallel line``: a reported line lies within 6 px and 5 degrees of it;
- ``other``: none of these.

It also sorts the reported lines that lie on no label (precision's losses): ``parallel``
to a label (within 2 degrees) but 2 to 6 px off it over half their length, ``past a
label's end`` (within 2 px of its line but less than half of them beside it), ``turned``
(within 3 px over half their length but more than 2 degrees off), ``far`` from every label.

    python benchmarks/lines_misses.py [YORK_DIR]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from collections import Counter
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import lines_measure  # noqa: E402

from gsrwt_cli.vision import hough  # noqa: E402
from gsrwt_cli.vision.edges import grey8  # noqa: E402
from gsrwt_cli.vision.frontal_pixels import frontal_edges  # noqa: E402

REASONS = ("tilted label", "no edge pixels", "edges in pieces", "off by > 1 deg",
           "off by > 2 px", "pieces too short", "merged / crossed", "contrast bar",
           "min length", "fill", "gap", "suppression", "all relaxed", "near a parallel line",
           "other")


def _reachable(label: lines_measure.Label) -> bool:
    dx, dy = np.abs(label.end - label.start)
    return dx - dy * math.tan(math.radians(lines_measure.RECALL_ANGLE_DEG)) <= 2 * 2.0


def _edge_cover(edges, label: lines_measure.Label, max_gap: float) -> tuple[float, float]:
    """Share of the label's length with an edge pixel near it, and the share of the
    longest run of such samples with gaps of at most ``max_gap``."""
    length = label.length
    direction = (label.end - label.start) / length
    normal = np.array([direction[1], -direction[0]])
    along = np.arange(0.0, length + 0.5, 1.0)
    across = np.arange(-2.0, 2.01, 1.0)
    points = (label.start[None, None] + along[:, None, None] * direction
              + across[None, :, None] * normal)
    cols, rows = np.rint(points[..., 0]).astype(int), np.rint(points[..., 1]).astype(int)
    height, width = edges.mask.shape
    inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
    cols, rows = np.clip(cols, 0, width - 1), np.clip(rows, 0, height - 1)
    theta = np.radians(edges.orientation_deg[rows, cols])
    normal_angle = math.atan2(normal[1], normal[0])
    off = np.abs((np.degrees(theta - normal_angle) + 90.0) % 180.0 - 90.0)
    hit = (inside & edges.mask[rows, cols] & (off <= 15.0)).any(axis=1)
    cover = float(hit.mean())
    at = along[hit]
    if at.size == 0:
        return cover, 0.0
    cuts = np.flatnonzero(np.diff(at) > max_gap) + 1
    best = max(float(piece[-1] - piece[0]) for piece in np.split(at, cuts))
    return cover, best / length


def _near(line, label: lines_measure.Label, distance: float, angle: float) -> tuple[bool, float]:
    """Whether ``line`` lies within ``angle`` of the label and ``distance`` of its ends, and
    how much of it it covers."""
    start, end = lines_measure._ends(line)
    if lines_measure._angle_deg(end - start, label.end - label.start) > angle:
        return False, 0.0
    ends = np.array([label.start, label.end])
    if np.any(lines_measure._distance_to_line(ends, start, end) > distance):
        return False, 0.0
    return True, lines_measure._overlap(label.start, label.end, start, end)


def _crosses(line, label: lines_measure.Label) -> bool:
    """A line more than 3 degrees off the label whose middle half lies within 2 px of it
    over half its length: the label's pixels went to it."""
    start, end = lines_measure._ends(line)
    if lines_measure._angle_deg(end - start, label.end - label.start) <= 3.0:
        return False
    samples = start + np.linspace(0, 1, 21)[:, None] * (end - start)
    direction = (label.end - label.start) / label.length
    t = (samples - label.start) @ direction
    close = (lines_measure._distance_to_line(samples, label.start, label.end) <= 2.0) & (
        t >= 0) & (t <= label.length)
    if not close.any():
        return False
    return float(np.ptp(t[close])) >= 0.5 * label.length


def _relaxed(view, edges, what: str) -> list:
    saved = (hough.CONTRAST_MARGIN, hough.MIN_FILL, hough.HOUGH_SUPPRESSION_RHO_BINS,
             hough.HOUGH_SUPPRESSION_THETA_BINS)
    kwargs = {}
    try:
        if what == "all relaxed":
            hough.CONTRAST_MARGIN, hough.MIN_FILL = -1.0, 0.0
            hough.HOUGH_SUPPRESSION_RHO_BINS, hough.HOUGH_SUPPRESSION_THETA_BINS = 1, 0
            kwargs = {"min_length": 10.0, "max_gap": 30.0, "min_votes": 5}
        elif what == "suppression":
            hough.HOUGH_SUPPRESSION_RHO_BINS, hough.HOUGH_SUPPRESSION_THETA_BINS = 1, 0
        elif what == "contrast bar":
            hough.CONTRAST_MARGIN = -1.0  # margin <= 0: every piece stands out
        elif what == "fill":
            hough.MIN_FILL = 0.0
        elif what == "min length":
            kwargs["min_length"] = 10.0
        elif what == "gap":
            kwargs["max_gap"] = 30.0
        return hough.hough_lines(view.pixels, edges=edges, **kwargs)
    finally:
        (hough.CONTRAST_MARGIN, hough.MIN_FILL, hough.HOUGH_SUPPRESSION_RHO_BINS,
         hough.HOUGH_SUPPRESSION_THETA_BINS) = saved


OFF_LABEL = ("parallel", "past a label's end", "turned", "far")


def _off_label(line, labels: list[lines_measure.Label]) -> str | None:
    """Why ``line`` lies on no label (:data:`OFF_LABEL`); None if it lies on one."""
    if any(lines_measure.lies_on(line, label) for label in labels):
        return None
    start, end = lines_measure._ends(line)
    length = float(np.hypot(*(end - start)))
    reason = "far"
    for label in labels:
        overlap = lines_measure._overlap(start, end, label.start, label.end)
        distance = lines_measure._distance_to_line(np.array([start, end]), label.start,
                                                   label.end)
        angle = lines_measure._angle_deg(end - start, label.end - label.start)
        if angle <= lines_measure.PRECISION_ANGLE_DEG:
            if np.all(distance <= lines_measure.DISTANCE_PX) and overlap > 0:
                return "past a label's end"
            if np.all(distance <= 6.0) and overlap >= 0.5 * length:
                reason = "parallel"
        elif np.all(distance <= 3.0) and overlap >= 0.5 * length and reason == "far":
            reason = "turned"
    return reason


def classify(view, labels: list[lines_measure.Label]) -> tuple[Counter, int, int, Counter]:
    """Reasons of the misses of one frontal view; its long vertical labels and finds; the
    kinds of its lines that lie on no label (``("all" | "vertical", kind)``)."""
    edges = frontal_edges(grey8(view.pixels), view.pixel_map, view.source_size)
    lines = hough.hough_lines(view.pixels, edges=edges)
    off: Counter = Counter()
    for line in lines:
        kind = _off_label(line, labels)
        if kind is not None:
            off["all", kind] += 1
            if lines_measure.is_vertical(line):
                off["vertical", kind] += 1
    vertical = [line for line in lines if lines_measure.is_vertical(line)]
    relaxed: dict[str, list] = {}
    reasons: Counter = Counter()
    total = found = 0
    for label in labels:
        if label.direction != "vertical" or label.length <= lines_measure.LONG:
            continue
        total += 1
        if any(lines_measure.finds(line, label) for line in vertical):
            found += 1
            continue
        reasons[_reason(view, edges, lines, label, relaxed)] += 1
    return reasons, total, found, off


def _reason(view, edges, lines, label, relaxed) -> str:
    if not _reachable(label):
        return "tilted label"
    cover, run = _edge_cover(edges, label, hough.DEFAULT_MAX_GAP)
    if cover < 0.5:
        return "no edge pixels"
    if run < 0.5:
        return "edges in pieces"
    half = 0.5 * label.length
    for line in lines:
        near, covered = _near(line, label, 4.0, 3.0)
        if near and covered >= half:
            start, end = lines_measure._ends(line)
            if not lines_measure.is_vertical(line):
                return "off by > 1 deg"
            return "off by > 2 px"
    if any(_near(line, label, 2.0, 1.0)[1] > 0 for line in lines
           if lines_measure.is_vertical(line)):
        return "pieces too short"
    if any(_crosses(line, label) for line in lines):
        return "merged / crossed"
    for what in ("contrast bar", "min length", "fill", "gap", "suppression", "all relaxed"):
        if what not in relaxed:
            relaxed[what] = [line for line in _relaxed(view, edges, what)
                             if lines_measure.is_vertical(line)]
        if any(lines_measure.finds(line, label) for line in relaxed[what]):
            return what
    if any(_near(line, label, 6.0, 5.0)[1] > 0 for line in lines):
        return "near a parallel line"
    return "other"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", nargs="?", type=Path, default=lines_measure.DEFAULT_ROOT)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    labels = lines_measure.read_labels(args.root)
    folds = [Counter(), Counter()]
    off: Counter = Counter()
    counts = [[0, 0], [0, 0]]
    names = sorted(lines_measure.read_truth(args.root))
    with tempfile.TemporaryDirectory() as folder:
        sidecar = lines_measure.write_sidecar(args.root, Path(folder) / "views.csv")
        for view in lines_measure.frontal_views(args.root, sidecar):
            fold = names.index(view.path.name) % 2
            shown = lines_measure.visible_labels(view, labels.get(view.path.name, []))
            reasons, total, found, lost = classify(view, shown)
            folds[fold].update(reasons)
            off.update(lost)
            counts[fold][0] += total
            counts[fold][1] += found
    total = sum(c[0] for c in counts)
    print(f"long vertical labels {total}, found {sum(c[1] for c in counts)}; misses by reason "
          f"(fold 0 = even index, fold 1 = odd, in sorted order):")
    print(f"{'reason':20} {'all':>6} {'share':>7} {'fold 0':>7} {'fold 1':>7}")
    for reason in REASONS:
        n = folds[0][reason] + folds[1][reason]
        print(f"{reason:20} {n:6} {n / total:7.3f} {folds[0][reason]:7} {folds[1][reason]:7}")
    print("reported lines on no label, by kind:")
    print(f"{'kind':20} {'all':>6} {'vertical':>9}")
    for kind in OFF_LABEL:
        print(f"{kind:20} {off['all', kind]:6} {off['vertical', kind]:9}")


if __name__ == "__main__":
    main()
