"""Documents in photos: the largest convex quadrilateral of strong, straight edges (a page, a
sign, a screen, a painting, a whiteboard), whose corners show the pose (``--auto document``).

Plain pixel coordinates, as in :mod:`~gsrwt_cli.vision.edges`: ``x`` the column, ``y`` the
row, pixel centres at integers. The corners come out in the order guided correction takes
them (top-left, top-right, bottom-right, bottom-left, clockwise as displayed), turned so that
the top side is the one nearest to the image's horizontal: a document's own up is not in its
outline, and the least roll is the reading a photographer means.

How (no constant here is fitted to any one photo):

1. Candidates: Canny edges of the image at a working size (longer side
   :data:`WORK_SIDE`), closed by one pixel, their outer contours' convex hulls simplified
   (Douglas-Peucker, 2 % of the perimeter) to four corners, at least
   :data:`MIN_AREA_FRACTION` of the image, no corner angle below :data:`MIN_ANGLE_DEGREES`.
2. Evidence: each side's share of points that lie on a Canny edge (within
   :data:`SUPPORT_REACH` pixels) whose gradient is across the side (within
   :data:`ORIENTATION_TOLERANCE_DEGREES`). A side along clutter or texture is rarely
   straight edge for long; a quadrilateral needs every side at :data:`MIN_SIDE_SUPPORT`.
3. Refusals: none found; the largest one runs along the image's border (the frame, not the
   document, makes that side, and the corners there are not the document's); another one,
   mostly outside it, nearly as large (:data:`RIVAL_AREA_RATIO`): no clear one. Outlines
   that overlap almost wholly (:data:`SAME_OVERLAP`) are one document's, the best supported
   standing for it.
4. The corners at full resolution: along each side, the edge's sub-pixel position across
   it (the peak of the grey level's derivative, one polarity for the whole side) at
   :data:`REFINE_SAMPLES` points, a line fitted through them (Huber), adjacent lines
   intersected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .edges import grey8

#: The longer side, in pixels, the candidates are searched at.
WORK_SIDE = 640
#: The least area of a document, as a share of the image's.
MIN_AREA_FRACTION = 0.05
#: The least interior angle of a document's outline, in degrees (a rectangle seen from up to
#: about 75 degrees off its normal keeps its angles above this).
MIN_ANGLE_DEGREES = 25.0
#: The least share of every side that must lie on straight edge across it.
MIN_SIDE_SUPPORT = 0.7
#: How far, in working pixels, a side's point may be from the edge pixel that supports it
#: (a printed page is rarely quite flat).
SUPPORT_REACH = 2
#: How far, in degrees, an edge pixel's gradient may be from the side's normal.
ORIENTATION_TOLERANCE_DEGREES = 20.0
#: Another candidate, not inside the largest, with at least this share of its area: no clear one.
RIVAL_AREA_RATIO = 0.8
#: A side within this share of the image's longer side of its border runs along it.
BORDER_FRACTION = 0.015
#: Outlines that share this much of the larger one's area are one document's.
SAME_OVERLAP = 0.9
#: The outlines tried per edge map, the largest first.
MAX_OUTLINES = 12
#: The bands, in working pixels either side of a rough outline's side, that its edge is
#: looked for in, narrowing.
SNAP_BANDS = (12.0, 6.0, 3.0)
#: Points per side where the edge is located at full resolution.
REFINE_SAMPLES = 64


BORDER_REASON = ("the largest quadrilateral runs along the image's border: the frame cuts the "
                 "document, its corners are not in the photo; give --corners")


class DocumentError(ValueError):
    """No clear document in the image; the message says why."""


@dataclass(frozen=True)
class Document:
    """A document found: its ``corners`` ((4, 2): top-left, top-right, bottom-right,
    bottom-left, in image pixels), the least share of a side on straight edge
    (``support``, 0-1) and its area as a share of the image's (``area_fraction``)."""

    corners: np.ndarray
    support: float
    area_fraction: float

    def corners_text(self) -> str:
        """The corners as ``--corners`` takes them: ``"x1,y1 x2,y2 x3,y3 x4,y4"``."""
        return " ".join(f"{x:.2f},{y:.2f}" for x, y in self.corners)


def _polygon_area(points: np.ndarray) -> float:
    """Shoelace area, positive when the points turn clockwise as displayed (``y`` down)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def ordered_corners(points: np.ndarray) -> np.ndarray:
    """Four corners of a convex quadrilateral, clockwise as displayed, from the top-left of
    the turn whose top side (first to second corner) points most nearly to the right."""
    points = np.asarray(points, dtype=np.float64).reshape(4, 2)
    if _polygon_area(points) < 0:
        points = points[::-1]
    sides = np.roll(points, -1, axis=0) - points
    rightward = sides[:, 0] / np.maximum(np.hypot(sides[:, 0], sides[:, 1]), 1e-12)
    return np.roll(points, -int(np.argmax(rightward)), axis=0)


def _least_angle(points: np.ndarray) -> float:
    before = np.roll(points, 1, axis=0) - points
    after = np.roll(points, -1, axis=0) - points
    cosines = np.sum(before * after, axis=1) / np.maximum(
        np.linalg.norm(before, axis=1) * np.linalg.norm(after, axis=1), 1e-12)
    return float(np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0))).min())


def _side_support(points: np.ndarray, edges: np.ndarray, gradients: np.ndarray) -> np.ndarray:
    """Each side's share of sample points (one per pixel, the ends' 5 % left out) with an
    edge pixel within :data:`SUPPORT_REACH` pixels whose gradient is within the tolerance of
    the side's normal. ``gradients``: (height, width, 2) unit gradients."""
    height, width = edges.shape
    support = np.zeros(4)
    least_cosine = math.cos(math.radians(ORIENTATION_TOLERANCE_DEGREES))
    for side in range(4):
        start, end = points[side], points[(side + 1) % 4]
        length = float(np.hypot(*(end - start)))
        count = max(int(length), 2)
        t = np.linspace(0.05, 0.95, count)
        along = start + t[:, None] * (end - start)
        normal = np.array([-(end - start)[1], (end - start)[0]]) / max(length, 1e-12)
        hit = np.zeros(count, dtype=bool)
        for dx in range(-SUPPORT_REACH, SUPPORT_REACH + 1):
            for dy in range(-SUPPORT_REACH, SUPPORT_REACH + 1):
                x = np.clip(np.rint(along[:, 0]) + dx, 0, width - 1).astype(np.intp)
                y = np.clip(np.rint(along[:, 1]) + dy, 0, height - 1).astype(np.intp)
                hit |= (edges[y, x] > 0) & (np.abs(gradients[y, x] @ normal) >= least_cosine)
        support[side] = hit.mean()
    return support


def _along_border(points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Which sides of the outline run along the image's border."""
    near = BORDER_FRACTION * max(width, height)
    along = np.zeros(4, dtype=bool)
    for side in range(4):
        a, b = points[side], points[(side + 1) % 4]
        for axis, limit in ((0, 0.0), (0, width - 1.0), (1, 0.0), (1, height - 1.0)):
            if abs(a[axis] - limit) <= near and abs(b[axis] - limit) <= near:
                along[side] = True
    return along


def _overlap(first: np.ndarray, second: np.ndarray) -> float:
    """The area two convex outlines share."""
    area, _ = cv2.intersectConvexConvex(first.astype(np.float32).reshape(-1, 1, 2),
                                        second.astype(np.float32).reshape(-1, 1, 2))
    return float(area)


def _fitted_line(points: np.ndarray) -> np.ndarray:
    """The homogeneous line through ``points`` ``(N, 2)``, fitted by OpenCV (Huber)."""
    vx, vy, x0, y0 = cv2.fitLine(points.astype(np.float32), cv2.DIST_HUBER, 0, 0.01,
                                 0.01).ravel()
    return np.cross([x0, y0, 1.0], [x0 + vx, y0 + vy, 1.0])


def _meeting_points(lines: list[np.ndarray]) -> np.ndarray | None:
    """Where each of four sides' lines meets the one before it: the corners ``(4, 2)``;
    None when two adjacent sides are parallel."""
    corners = []
    for corner in range(4):
        point = np.cross(lines[corner - 1], lines[corner])
        if abs(point[2]) < 1e-12:
            return None
        corners.append(point[:2] / point[2])
    return np.array(corners)


def _snapped(points: np.ndarray, edge_points: np.ndarray, edge_gradients: np.ndarray
             ) -> np.ndarray | None:
    """A rough outline moved onto the edges it follows: for each side, the edge pixels
    near it (within :data:`SNAP_BANDS` pixels, narrowing) whose gradient is across it, a
    line fitted through them (Huber), adjacent lines intersected; None when a side has too
    few such pixels or the result is no longer convex. ``edge_gradients``: the edge pixels'
    unit gradients."""
    least_cosine = math.cos(math.radians(ORIENTATION_TOLERANCE_DEGREES))
    reach = SNAP_BANDS[0] + 1
    low, high = points.min(axis=0) - reach, points.max(axis=0) + reach
    nearby = np.all((edge_points >= low) & (edge_points <= high), axis=1)
    edge_points, edge_gradients = edge_points[nearby], edge_gradients[nearby]
    for band in SNAP_BANDS:
        lines = []
        for side in range(4):
            start, end = points[side], points[(side + 1) % 4]
            length = float(np.hypot(*(end - start)))
            if length < 1.0:
                return None
            direction = (end - start) / length
            relative = edge_points - start
            along = relative @ direction
            normal = np.array([-direction[1], direction[0]])
            across = relative @ normal
            near = ((np.abs(across) <= band) & (along >= -0.05 * length)
                    & (along <= 1.05 * length)
                    & (np.abs(edge_gradients @ normal) >= least_cosine))
            if near.sum() < max(8, 0.2 * length):
                return None
            lines.append(_fitted_line(edge_points[near]))
        moved = _meeting_points(lines)
        if moved is None or not cv2.isContourConvex(moved.astype(np.float32).reshape(-1, 1, 2)):
            return None
        points = ordered_corners(moved)
    return points


@dataclass(frozen=True)
class _Candidate:
    points: np.ndarray  # working pixels, ordered
    area: float
    side_support: np.ndarray  # each side's share on straight edge
    border_sides: np.ndarray  # which sides run along the image's border

    @property
    def support(self) -> float:
        return float(self.side_support.min())

    @property
    def on_border(self) -> bool:
        return bool(self.border_sides.any())

    @property
    def cut_by_frame(self) -> bool:
        """Whether its sides along the image's border are all that lacks edge: a document
        the frame cuts."""
        inside = self.side_support[~self.border_sides]
        return self.on_border and inside.size > 0 and inside.min() >= MIN_SIDE_SUPPORT


def _candidates(grey: np.ndarray) -> list[_Candidate]:
    height, width = grey.shape
    blurred = cv2.GaussianBlur(grey, (5, 5), 0)
    gx = cv2.Sobel(blurred, cv2.CV_32F, 1, 0)
    gy = cv2.Sobel(blurred, cv2.CV_32F, 0, 1)
    gradients = np.dstack([gx, gy]) / np.maximum(np.hypot(gx, gy), 1e-6)[..., None]
    min_area = MIN_AREA_FRACTION * width * height
    found: list[_Candidate] = []
    seen: list[np.ndarray] = []
    level, _ = cv2.threshold(blurred, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    opening = np.ones((5, 5), np.uint8)
    regions = [cv2.morphologyEx(((blurred > level) == bright).astype(np.uint8), cv2.MORPH_OPEN,
                                opening) for bright in (True, False)]
    for low, high in ((50, 150), (20, 60)):
        edges = cv2.Canny(blurred, low, high, L2gradient=True)
        rows, cols = np.nonzero(edges)
        edge_points = np.column_stack([cols, rows]).astype(np.float64)
        edge_gradients = gradients[rows, cols].astype(np.float64)
        outlines = [cv2.dilate(edges, np.ones((3, 3), np.uint8))]
        if low == 20:
            outlines += regions  # the bright page and the dark screen, by Otsu's level
        contours = [contour for outline in outlines
                    for contour in cv2.findContours(outline, cv2.RETR_LIST,
                                                    cv2.CHAIN_APPROX_SIMPLE)[0]]
        hulls = [cv2.convexHull(contour) for contour in contours]
        hulls = sorted((hull for hull in hulls if cv2.contourArea(hull) >= min_area),
                       key=cv2.contourArea, reverse=True)
        for hull in hulls[:MAX_OUTLINES]:
            approx = cv2.approxPolyDP(hull, 0.02 * cv2.arcLength(hull, True), True)
            if len(approx) != 4 or not cv2.isContourConvex(approx):
                continue
            points = _snapped(ordered_corners(approx.reshape(4, 2).astype(np.float64)),
                              edge_points, edge_gradients)
            if points is None:
                continue
            area = _polygon_area(points)
            if area < min_area or _least_angle(points) < MIN_ANGLE_DEGREES:
                continue
            if any(np.abs(points - other).max() <= 3.0 for other in seen):
                continue
            seen.append(points)
            found.append(_Candidate(points, area, _side_support(points, edges, gradients),
                                    _along_border(points, width, height)))
    return found


def _refined(grey: np.ndarray, corners: np.ndarray, reach: float) -> np.ndarray:
    """The corners at full resolution: each side's edge located across it at sample points
    (the strongest derivative of one polarity, to a parabola's sub-pixel peak), a line fitted
    through them, adjacent lines intersected. A side that gives too few points keeps its
    first estimate."""
    smooth = cv2.GaussianBlur(grey.astype(np.float32), (0, 0), 1.0)
    step = 0.5
    offsets = np.arange(-reach, reach + step / 2, step, dtype=np.float64)
    lines = []
    for side in range(4):
        start, end = corners[side], corners[(side + 1) % 4]
        direction = (end - start) / max(float(np.hypot(*(end - start))), 1e-12)
        normal = np.array([-direction[1], direction[0]])
        t = np.linspace(0.1, 0.9, REFINE_SAMPLES)
        centres = start + t[:, None] * (end - start)
        where = centres[:, None, :] + offsets[None, :, None] * normal
        profile = cv2.remap(smooth, where[..., 0].astype(np.float32),
                            where[..., 1].astype(np.float32), cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
        derivative = np.gradient(profile, step, axis=1)
        rising, falling = derivative.max(axis=1).sum(), (-derivative).max(axis=1).sum()
        sign = 1.0 if rising >= falling else -1.0
        signed = sign * derivative
        peak = np.argmax(signed[:, 1:-1], axis=1) + 1
        rows = np.arange(REFINE_SAMPLES)
        left, middle, right = signed[rows, peak - 1], signed[rows, peak], signed[rows, peak + 1]
        curvature = left - 2 * middle + right
        shift = np.where(curvature < 0, 0.5 * (left - right) / np.where(curvature < 0,
                                                                         curvature, -1.0), 0.0)
        keep = middle >= 0.5 * np.median(middle)
        points = centres + ((offsets[peak] + shift * step)[:, None] * normal)
        if keep.sum() < 8:
            lines.append(np.cross([*start, 1.0], [*end, 1.0]))
            continue
        lines.append(_fitted_line(points[keep]))
    refined_array = _meeting_points(lines)
    if refined_array is None:
        return corners
    if np.abs(refined_array - corners).max() > 2 * reach:
        return corners  # the fit left the edge it started on
    return refined_array


def find_document(image: np.ndarray) -> Document:
    """The largest convex quadrilateral of strong straight edges in ``image`` (any sample
    type :func:`~gsrwt_cli.vision.edges.grey8` takes). Raises :class:`DocumentError`, saying
    why, when there is no clear one."""
    grey = np.ascontiguousarray(grey8(image))
    height, width = grey.shape
    factor = max(height, width) / WORK_SIDE
    if factor > 1:
        work = cv2.resize(grey, (max(1, round(width / factor)), max(1, round(height / factor))),
                          interpolation=cv2.INTER_AREA)
        factor_x, factor_y = width / work.shape[1], height / work.shape[0]
    else:
        work, factor_x, factor_y = grey, 1.0, 1.0
    candidates = _candidates(work)
    supported = sorted((c for c in candidates if c.support >= MIN_SIDE_SUPPORT),
                       key=lambda c: c.area, reverse=True)
    cut = [c for c in candidates if c.cut_by_frame]
    if cut and (not supported or max(c.area for c in cut) > supported[0].area):
        raise DocumentError(BORDER_REASON)
    if not supported:
        best_support = max((c.support for c in candidates), default=0.0)
        raise DocumentError(
            f"no convex quadrilateral of straight edges covering {MIN_AREA_FRACTION:.0%} of "
            f"the image or more (the best outline found has {best_support:.0%} of its "
            f"weakest side on edge; {MIN_SIDE_SUPPORT:.0%} needed)")
    largest = supported[0]
    # Outlines of one document (the two sides of a printed frame, say) overlap almost wholly:
    # the best supported of them stands for it.
    alike = [c for c in supported
             if _overlap(c.points, largest.points) >= SAME_OVERLAP * max(c.area, largest.area)]
    best = max(alike, key=lambda c: c.support)
    if best.on_border:
        raise DocumentError(BORDER_REASON)
    work_size = float(work.shape[0] * work.shape[1])
    for rival in supported:
        if any(rival is c for c in alike) or rival.area < RIVAL_AREA_RATIO * best.area:
            continue
        if _overlap(rival.points, best.points) < 0.5 * rival.area:
            raise DocumentError(
                f"no clear document: two quadrilaterals of {best.area / work_size:.0%} and "
                f"{rival.area / work_size:.0%} of the image; give --corners")
    scale = np.array([factor_x, factor_y])
    coarse = (best.points + 0.5) * scale - 0.5
    corners = _refined(grey, coarse, reach=max(3.0, 2.0 * float(scale.max())))
    return Document(ordered_corners(corners), best.support, best.area / work_size)
