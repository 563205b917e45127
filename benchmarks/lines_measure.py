"""``gsrwt lines`` measured on real photos with hand-labelled segments: the York Urban set.

The data's README (``../shared/data/york-urban-train/README.md``) defines the measures:
``gsrwt lines`` with the true pose (``truth.csv``: ``pan, tilt, roll, focal_px, cx, cy``);

- **recall**: of the labelled ``vertical`` segments longer than :data:`LONG` px in the frontal
  view, the share found by a reported line within :data:`DISTANCE_PX` of both of its ends and
  within :data:`RECALL_ANGLE_DEG` of vertical, covering at least half of it;
- **precision**: the share of reported lines that lie on some labelled segment of any
  direction (vertical precision: of the reported lines within :data:`RECALL_ANGLE_DEG` of
  vertical).

Where the README leaves a detail open, this module takes the definitions of
``tests/chessboard_edges.py`` (issue 15), so that chessboards, door renders and York Urban
are scored alike:

- "within 2 px at both ends": both ends of the label lie within 2 px of the reported line
  (the infinite line through its ends); "covering at least half": the reported segment's
  projection onto the label covers half of the label's length;
- "lies on a label": within :data:`PRECISION_ANGLE_DEG` of its direction, both ends of the
  reported line within 2 px of the label's line, at least half of the reported line's length
  beside the label. A stricter reading is counted too (``within``): within
  :data:`RECALL_ANGLE_DEG` of the label's direction and both ends within 2 px of the label
  itself (the segment, not its line): a line that runs on past a label's end is not on it.

The labels are in the photo's pixels. They are mapped into the frontal view through the
view's own pixel map (:attr:`CanonicalView.pixel_map`, source to frontal, built from the
true pose by the same code that builds ``gsrwt lines``' view), as ``tests/chessboard_edges``
does with the chessboard's corners; :func:`map_check_px` checks that map independently
against a homography fitted (OpenCV) to the reported lines' own frontal and source ends.
Only the part of a label that the frontal view shows counts: points of the label whose
source pixel is at least :data:`~gsrwt_cli.vision.frontal_pixels.SOURCE_MARGIN` px inside
the photo, in front of the wall's horizon and inside the frontal frame (3 px margin), the
longest run of them (a straight label stays straight: the lens is a pinhole).
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from gsrwt_cli.batch.canonical_views import CanonicalView, canonical_views
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.vision.frontal_pixels import SOURCE_MARGIN

#: The training half, relative to the repository's root.
DEFAULT_ROOT = Path(__file__).resolve().parents[2] / "shared" / "data" / "york-urban-train"

LONG = 40.0
DISTANCE_PX = 2.0
RECALL_ANGLE_DEG = 1.0
PRECISION_ANGLE_DEG = 2.0
#: Labels' points closer than this to the frontal view's border do not count as in view.
FRAME_MARGIN = 3.0
#: Labels are followed through the map at this spacing (source pixels).
SAMPLE_STEP_PX = 0.5


class Segment(Protocol):
    """A reported line: end points ``(x1, y1)``, ``(x2, y2)`` in the frontal view."""

    x1: float
    y1: float
    x2: float
    y2: float


@dataclass(frozen=True)
class Label:
    """A labelled segment's visible part in the frontal view, and its scene direction."""

    start: np.ndarray
    end: np.ndarray
    direction: str  # vertical, wall, side

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.end - self.start)))


@dataclass
class Score:
    """Counts of one image or a set; the ratios as properties."""

    long_vertical: int = 0
    found: int = 0
    vertical_lines: int = 0
    vertical_on_labels: int = 0
    lines: int = 0
    on_labels: int = 0
    vertical_within: int = 0
    within: int = 0

    def add(self, other: Score) -> None:
        for field in fields(self):
            setattr(self, field.name, getattr(self, field.name) + getattr(other, field.name))

    @property
    def recall(self) -> float:
        return self.found / max(self.long_vertical, 1)

    @property
    def vertical_precision(self) -> float:
        return self.vertical_on_labels / max(self.vertical_lines, 1)

    @property
    def precision(self) -> float:
        return self.on_labels / max(self.lines, 1)

    @property
    def strict_vertical_precision(self) -> float:
        return self.vertical_within / max(self.vertical_lines, 1)

    @property
    def strict_precision(self) -> float:
        return self.within / max(self.lines, 1)


def read_truth(root: Path) -> dict[str, dict[str, float]]:
    """``truth.csv``: image name to its numbers."""
    with open(root / "truth.csv", newline="") as file:
        return {row["image"]: {key: float(value) for key, value in row.items() if key != "image"}
                for row in csv.DictReader(file)}


def read_labels(root: Path) -> dict[str, list[tuple[np.ndarray, np.ndarray, str]]]:
    """``segments.csv``: image name to its labelled segments (source pixels)."""
    labels: dict[str, list[tuple[np.ndarray, np.ndarray, str]]] = {}
    with open(root / "segments.csv", newline="") as file:
        for row in csv.DictReader(file):
            start = np.array([float(row["x1"]), float(row["y1"])])
            end = np.array([float(row["x2"]), float(row["y2"])])
            labels.setdefault(row["image"], []).append((start, end, row["direction"]))
    return labels


def write_sidecar(root: Path, target: Path) -> Path:
    """A ``gsrwt`` sidecar with each photo's true pose and calibration (``truth.csv``)."""
    with open(target, "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["image", "pan", "tilt", "roll", "focal", "cx", "cy"])
        for name, truth in read_truth(root).items():
            writer.writerow([name, *(repr(truth[key]) for key in
                                     ("pan", "tilt", "roll", "focal_px", "cx", "cy"))])
    return target


def photos(root: Path) -> list[Path]:
    """The photos that ``truth.csv`` lists, in its order."""
    return [root / "images" / name for name in read_truth(root)]


def frontal_views(root: Path, sidecar: Path) -> Iterator[CanonicalView]:
    """The photos rectified with their true poses, as ``gsrwt lines --sidecar`` makes them."""
    for view in canonical_views(photos(root), load_sidecar(sidecar), {}):
        if not isinstance(view, CanonicalView):
            raise RuntimeError(f"{view[0]}: {view[1]}")
        yield view


def visible_labels(view: CanonicalView,
                   labels: Iterable[tuple[np.ndarray, np.ndarray, str]]) -> list[Label]:
    """The labels' parts that the frontal view shows (see the module's docstring)."""
    homography = np.asarray(view.pixel_map.output_from_input, np.float64)
    source_width, source_height = view.source_size
    width, height = view.pixel_map.size
    result = []
    for start, end, direction in labels:
        count = max(2, int(math.ceil(np.hypot(*(end - start)) / SAMPLE_STEP_PX)) + 1)
        points = start + np.linspace(0.0, 1.0, count)[:, None] * (end - start)
        mapped = np.column_stack([points, np.ones(count)]) @ homography.T
        ahead = mapped[:, 2] > 0
        frontal = mapped[:, :2] / np.where(ahead, mapped[:, 2], 1.0)[:, None]
        in_photo = np.all((points >= SOURCE_MARGIN)
                          & (points <= np.array([source_width, source_height]) - 1 - SOURCE_MARGIN),
                          axis=1)
        in_frame = np.all((frontal >= FRAME_MARGIN)
                          & (frontal <= np.array([width, height]) - 1 - FRAME_MARGIN), axis=1)
        shown = ahead & in_photo & in_frame
        index = np.flatnonzero(shown)
        if index.size < 2:
            continue
        runs = np.split(index, np.flatnonzero(np.diff(index) > 1) + 1)
        run = max(runs, key=len)
        if run.size >= 2:
            result.append(Label(frontal[run[0]], frontal[run[-1]], direction))
    return result


def _ends(line: Segment) -> tuple[np.ndarray, np.ndarray]:
    return np.array([line.x1, line.y1], float), np.array([line.x2, line.y2], float)


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Undirected angle between two directions, degrees."""
    angle = math.degrees(math.atan2(a[1], a[0]) - math.atan2(b[1], b[0]))
    return abs((angle + 90.0) % 180.0 - 90.0)


def _distance_to_line(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    direction = (end - start) / max(float(np.hypot(*(end - start))), 1e-12)
    offset = points - start
    return np.abs(offset[:, 0] * direction[1] - offset[:, 1] * direction[0])


def _overlap(a_start: np.ndarray, a_end: np.ndarray, b_start: np.ndarray,
             b_end: np.ndarray) -> float:
    """Length of segment b's projection onto segment a's extent."""
    a_length = float(np.hypot(*(a_end - a_start)))
    direction = (a_end - a_start) / max(a_length, 1e-12)
    b0, b1 = sorted([float((b_start - a_start) @ direction), float((b_end - a_start) @ direction)])
    return max(0.0, min(a_length, b1) - max(0.0, b0))


def is_vertical(line: Segment, tolerance_deg: float = RECALL_ANGLE_DEG) -> bool:
    start, end = _ends(line)
    return _angle_deg(end - start, np.array([0.0, 1.0])) <= tolerance_deg


def finds(line: Segment, label: Label) -> bool:
    """The README's find: ``line`` within 1 degree of vertical, both of the label's ends
    within 2 px of it, covering half of the label."""
    start, end = _ends(line)
    if not is_vertical(line):
        return False
    if np.any(_distance_to_line(np.array([label.start, label.end]), start, end) > DISTANCE_PX):
        return False
    return _overlap(label.start, label.end, start, end) >= 0.5 * label.length


def lies_on(line: Segment, label: Label) -> bool:
    """A reported line on a label: within 2 degrees of its direction, both of its ends within
    2 px of the label's line, half of its length beside the label."""
    start, end = _ends(line)
    if _angle_deg(end - start, label.end - label.start) > PRECISION_ANGLE_DEG:
        return False
    if np.any(_distance_to_line(np.array([start, end]), label.start, label.end) > DISTANCE_PX):
        return False
    length = float(np.hypot(*(end - start)))
    return _overlap(start, end, label.start, label.end) >= 0.5 * length


def _distance_to_segment(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    direction = end - start
    t = float(np.clip((point - start) @ direction / max(float(direction @ direction), 1e-12),
                      0.0, 1.0))
    return float(np.hypot(*(point - start - t * direction)))


def lies_within(line: Segment, label: Label) -> bool:
    """The stricter reading: within 1 degree of the label's direction, both ends within
    2 px of the label itself."""
    start, end = _ends(line)
    if _angle_deg(end - start, label.end - label.start) > RECALL_ANGLE_DEG:
        return False
    return all(_distance_to_segment(point, label.start, label.end) <= DISTANCE_PX
               for point in (start, end))


def score(labels: Sequence[Label], lines: Sequence[Segment]) -> Score:
    """Recall of the long vertical labels and precision of ``lines`` on one image."""
    result = Score()
    vertical = [line for line in lines if is_vertical(line)]
    for label in labels:
        if label.direction == "vertical" and label.length > LONG:
            result.long_vertical += 1
            result.found += any(finds(line, label) for line in vertical)
    for line in lines:
        hit = any(lies_on(line, label) for label in labels)
        inside = any(lies_within(line, label) for label in labels)
        result.lines += 1
        result.on_labels += hit
        result.within += inside
        if is_vertical(line):
            result.vertical_lines += 1
            result.vertical_on_labels += hit
            result.vertical_within += inside
    return result


def map_check_px(view: CanonicalView, rows: Sequence[Segment]) -> float:
    """Largest distance (frontal px) between the view's pixel map and a homography fitted by
    OpenCV to the reported lines' source ends (``x1_src`` .. ``y2_src``) and frontal ends: 0
    up to rounding when labels and lines are in one frame. NaN with fewer than 4 lines."""
    if len(rows) < 4:
        return math.nan
    source = np.array([[r.x1_src, r.y1_src] for r in rows] + [[r.x2_src, r.y2_src] for r in rows])
    frontal = np.array([[r.x1, r.y1] for r in rows] + [[r.x2, r.y2] for r in rows])
    fitted, _ = cv2.findHomography(source, frontal, 0)
    by_fit = cv2.perspectiveTransform(source[None], fitted)[0]
    return float(np.max(np.hypot(*(by_fit - view.pixel_map.to_output(source)).T)))


@dataclass(frozen=True)
class Measured:
    """One image: its score, its lines and the time of the edge and Hough stages."""

    name: str
    score: Score
    lines: list
    cpu_s: float
    wall_s: float


def measure(root: Path, sidecar: Path, find_lines, names: Iterable[str] | None = None,
            ) -> Iterator[Measured]:
    """Each photo's score with ``find_lines(view) -> lines`` (timed: CPU and wall clock)."""
    labels = read_labels(root)
    wanted = None if names is None else set(names)
    for view in frontal_views(root, sidecar):
        if wanted is not None and view.path.name not in wanted:
            continue
        cpu, wall = time.process_time(), time.perf_counter()
        found = find_lines(view)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        shown = visible_labels(view, labels.get(view.path.name, []))
        yield Measured(view.path.name, score(shown, found), found, cpu, wall)


def total(measured: Iterable[Measured]) -> Score:
    """The scores of several images added up."""
    result = Score()
    for item in measured:
        result.add(item.score)
    return result
