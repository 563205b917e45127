"""A labelled set of straight edges on real photos, for free: OpenCV's chessboard photos.

``tests/data/right*.jpg`` rectified with their solvePnP poses and calibration (as ``gsrwt lines
--sidecar tests/data/right_poses.csv --camera tests/data/right_camera.yml`` does). Every
square's sides are known from the corners that ``cv2.findChessboardCorners`` finds in the RAW
photo (independent of gsrwt's edges), mapped into the frontal view through the view's own
pixel map (through the least-squares homography of the 54 corners). The labels are the
sides between neighbouring corners where the squares on the two sides differ by at least
:data:`MIN_STEP` grey levels (the outer squares are cut to different widths on different
boards, so their sides are left out, as is everything outside the corners' outline).

Scores follow issue 15's definitions:

- **recall** of long vertical edges (> 40 px, wholly in view): an edge is found by a reported
  line within 1 degree of vertical that passes within 2 px of both of its ends and covers at
  least half of it;
- **precision**: of the reported lines (all of them, or the vertical ones) whose middle lies
  inside the outline of the corners, the fraction that lies on a labelled edge: within 2
  degrees of it, both ends within 2 px of its line, at least half of its length beside it.
  Lines off the board (the person holding it, the room) have no labels and are not counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from gsrwt_cli.batch.canonical_views import CanonicalView, canonical_views
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.vision.frontal_pixels import seen
from tests.helpers.paths import DATA

BOARD = (9, 6)
MIN_STEP = 40.0
LONG = 40.0
DISTANCE_PX = 2.0
RECALL_ANGLE_DEG = 1.0
PRECISION_ANGLE_DEG = 2.0


@dataclass(frozen=True)
class Edge:
    """A labelled edge: end points in the frontal view, whether wholly in view."""

    start: np.ndarray
    end: np.ndarray
    in_view: bool
    group: int = 0  # which door of a render the edge belongs to

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.end - self.start)))

    @property
    def vertical(self) -> bool:
        dx, dy = self.end - self.start
        return abs(dx) < abs(dy)


@dataclass(frozen=True)
class Board:
    """One photo: its frontal view, labelled edges and the board's outline (frontal px)."""

    view: CanonicalView
    edges: list[Edge]
    outline: np.ndarray  # (4, 2)
    source: np.ndarray | None = None  # the camera image, when it is not the view's file


def photos() -> list[Path]:
    return sorted(DATA.glob("right*.jpg"))


def frontal_views(paths: list[Path] | None = None) -> list[CanonicalView]:
    """The photos rectified with their poses (default frame, frontal resolution)."""
    paths = photos() if paths is None else paths
    views = list(canonical_views(paths, load_sidecar(DATA / "right_poses.csv"),
                                 {"camera": str(DATA / "right_camera.yml")}))
    assert all(isinstance(view, CanonicalView) for view in views), views
    return views


def _inside(points: np.ndarray, width: int, height: int, margin: float) -> np.ndarray:
    return ((points[:, 0] >= margin) & (points[:, 0] <= width - 1 - margin)
            & (points[:, 1] >= margin) & (points[:, 1] <= height - 1 - margin))


def label(view: CanonicalView) -> Board:
    """The labelled edges of one rectified chessboard photo."""
    raw = cv2.imread(str(view.path), cv2.IMREAD_GRAYSCALE)
    found, corners = cv2.findChessboardCorners(raw, BOARD)
    assert found, f"{view.path}: no board"
    corners = cv2.cornerSubPix(raw, corners, (11, 11), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 1e-3))
    frontal = view.pixel_map.to_output(corners.reshape(-1, 2).astype(np.float64))
    board = np.array([[i, j] for j in range(BOARD[1]) for i in range(BOARD[0])], np.float64)
    homography, _ = cv2.findHomography(board, frontal, 0)

    def at(i, j):
        points = np.column_stack([np.ravel(i), np.ravel(j)]).astype(np.float64)
        return cv2.perspectiveTransform(points[None], homography)[0]

    grey = view.pixels if view.pixels.ndim == 2 else cv2.cvtColor(view.pixels, cv2.COLOR_BGR2GRAY)
    height, width = grey.shape
    valid = cv2.erode(seen(view.pixel_map, (raw.shape[1], raw.shape[0])).astype(np.uint8),
                      np.ones((3, 3), np.uint8))

    def shade(i, j):
        """Mean grey of a 5x5 patch at board point (i, j); NaN if not in view."""
        point = at(i, j)[0]
        col, row = int(round(point[0])), int(round(point[1]))
        if not (2 <= col < width - 2 and 2 <= row < height - 2) or not valid[row, col]:
            return math.nan
        return float(grey[row - 2:row + 3, col - 2:col + 3].mean())

    edges = []
    columns, rows = BOARD
    for i in range(columns):  # vertical sides at i, from j to j + 1
        for j in range(rows - 1):
            if abs(shade(i - 0.5, j + 0.5) - shade(i + 0.5, j + 0.5)) >= MIN_STEP:
                ends = at([i, i], [j, j + 1])  # NaN (out of view) compares False above
                edges.append(Edge(ends[0], ends[1], bool(_inside(ends, width, height, 3).all())))
    for j in range(rows):  # horizontal sides at j, from i to i + 1
        for i in range(columns - 1):
            if abs(shade(i + 0.5, j - 0.5) - shade(i + 0.5, j + 0.5)) >= MIN_STEP:
                ends = at([i, i + 1], [j, j])
                edges.append(Edge(ends[0], ends[1], bool(_inside(ends, width, height, 3).all())))
    outline = at([0, columns - 1, columns - 1, 0], [0, 0, rows - 1, rows - 1])
    return Board(view, edges, outline)


def _segment(line) -> tuple[np.ndarray, np.ndarray]:
    return np.array([line.x1, line.y1], float), np.array([line.x2, line.y2], float)


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Undirected angle between two directions, degrees."""
    angle = math.degrees(math.atan2(a[1], a[0]) - math.atan2(b[1], b[0]))
    return abs((angle + 90.0) % 180.0 - 90.0)


def _distance_to_line(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    direction = (end - start) / max(np.hypot(*(end - start)), 1e-12)
    offset = points - start
    return np.abs(offset[:, 0] * direction[1] - offset[:, 1] * direction[0])


def _overlap(a_start, a_end, b_start, b_end) -> float:
    """Length of segment b's projection onto segment a's extent."""
    direction = (a_end - a_start) / max(np.hypot(*(a_end - a_start)), 1e-12)
    a_len = float(np.hypot(*(a_end - a_start)))
    b0, b1 = sorted([float((b_start - a_start) @ direction), float((b_end - a_start) @ direction)])
    return max(0.0, min(a_len, b1) - max(0.0, b0))


def is_vertical(line, tolerance_deg: float) -> bool:
    start, end = _segment(line)
    return _angle_deg(end - start, np.array([0.0, 1.0])) <= tolerance_deg


def finds(line, edge: Edge) -> bool:
    """Issue 15's find: within 1 degree of the edge's direction (vertical), within 2 px of
    both of the edge's ends, covering half of the edge."""
    start, end = _segment(line)
    if _angle_deg(end - start, edge.end - edge.start) > RECALL_ANGLE_DEG:
        return False
    if np.any(_distance_to_line(np.array([edge.start, edge.end]), start, end) > DISTANCE_PX):
        return False
    return _overlap(edge.start, edge.end, start, end) >= 0.5 * edge.length


def lies_on(line, edge: Edge) -> bool:
    """A reported line on a labelled edge: direction within 2 degrees, both of its ends
    within 2 px of the edge's line, half of its length beside the edge."""
    start, end = _segment(line)
    if _angle_deg(end - start, edge.end - edge.start) > PRECISION_ANGLE_DEG:
        return False
    if np.any(_distance_to_line(np.array([start, end]), edge.start, edge.end) > DISTANCE_PX):
        return False
    length = float(np.hypot(*(end - start)))
    return _overlap(start, end, edge.start, edge.end) >= 0.5 * length


def on_board(line, board: Board, grow: float = 3.0) -> bool:
    """Whether the middle of the line lies on the board's outline grown by ``grow`` px."""
    start, end = _segment(line)
    middle = (start + end) / 2
    distance = cv2.pointPolygonTest(board.outline.astype(np.float32).reshape(-1, 1, 2),
                                    (float(middle[0]), float(middle[1])), True)
    return distance >= -grow


@dataclass
class Score:
    long_vertical: int = 0
    found: int = 0
    vertical_lines: int = 0
    vertical_on_edges: int = 0
    lines: int = 0
    on_edges: int = 0

    def add(self, other: Score) -> None:
        for name in self.__dataclass_fields__:
            setattr(self, name, getattr(self, name) + getattr(other, name))

    @property
    def recall(self) -> float:
        return self.found / max(self.long_vertical, 1)

    @property
    def vertical_precision(self) -> float:
        return self.vertical_on_edges / max(self.vertical_lines, 1)

    @property
    def precision(self) -> float:
        return self.on_edges / max(self.lines, 1)


def score(board: Board, lines) -> Score:
    """Recall of long vertical edges and precision of the lines on the board."""
    result = Score()
    for edge in board.edges:
        if edge.in_view and edge.vertical and edge.length > LONG:
            result.long_vertical += 1
            result.found += any(finds(line, edge) for line in lines
                                if is_vertical(line, RECALL_ANGLE_DEG))
    for line in lines:
        if not on_board(line, board):
            continue
        hit = any(lies_on(line, edge) for edge in board.edges)
        result.lines += 1
        result.on_edges += hit
        if is_vertical(line, RECALL_ANGLE_DEG):
            result.vertical_lines += 1
            result.vertical_on_edges += hit
    return result


def low_contrast_photo(path: Path, factor: float = 0.15, quality: int = 60,
                       noise: float = 2.0, seed: int = 0) -> np.ndarray:
    """The raw photo at ``factor`` of its contrast (around grey 150), with Gaussian noise of
    ``noise`` grey levels, through JPEG at ``quality``: black and white squares 27 grey
    levels apart, as a white door frame on a white wall."""
    raw = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE).astype(np.float32)
    noisy = 150 + (raw - raw.mean()) * factor + np.random.default_rng(seed).normal(
        0, noise, raw.shape)
    low = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
    _, encoded = cv2.imencode(".jpg", low, [cv2.IMWRITE_JPEG_QUALITY, quality])
    return cv2.imdecode(encoded, cv2.IMREAD_GRAYSCALE)


def low_contrast(boards: list[Board]) -> list[Board]:
    """The boards with their photos at low contrast (:func:`low_contrast_photo`), rectified
    through the same pixel maps; the labels stay those of the original photos."""
    result = []
    for index, board in enumerate(boards):
        low = low_contrast_photo(board.view.path, seed=index)
        frontal = board.view.pixel_map.warp(low, cv2.INTER_LINEAR, (0.0, 0.0, 0.0, 0.0))
        view = CanonicalView(board.view.path, frontal, board.view.pixel_map,
                             board.view.source_size, board.view.units_per_pixel)
        result.append(Board(view, board.edges, board.outline, low))
    return result
