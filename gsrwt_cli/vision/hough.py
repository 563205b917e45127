"""Straight segments (door boundaries) by the one-vote-per-pixel Hough transform (Sec. 5.2.2).

Every edge pixel (:mod:`.edges`) casts ONE vote, in the orientation bin of its own gradient
direction (and the bins beside it, as far as the orientation's noise reaches), for the line
through it with that normal. Each line of the accumulator is then cut into segments where its
edge pixels have gaps, so that a door edge is reported as the door edge and not as a line
across the whole view, and a segment is kept if it stands out from what lies beside it.
Pixel coordinates and angles as in :mod:`.edges`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .edges import (
    DEFAULT_LINE_THRESHOLD,
    EdgeMap,
    bin_of_orientation,
    compatible_bins,
    line_edges,
    orientation_bin_count,
)

#: Hough orientation sampling and line criterion of the thesis (Sec. 5.2.2).
DEFAULT_THETA_STEP_DEG = 2.0
DEFAULT_MIN_VOTES = 25

#: A line's edge pixels further apart than this (frontal pixels, along the line) split it.
DEFAULT_MAX_GAP = 10.0

#: Segments shorter than this (frontal pixels) are not reported.
DEFAULT_MIN_LENGTH = 30.0

#: A segment's ends are moved outward, by whole pixels, at most this far, while the raw
#: gradient across the line keeps at least half its strength and its polarity: the
#: orientation of the last pixels before a corner turns, and they do not vote. The gradient
#: (3x3 Sobel after a blur of sigma 1) sees a corner from 1 + 2 = 3 px away; further out, an
#: edge that goes on beyond a corner would carry the end past it.
MAX_END_EXTENSION = 3

#: A segment holds at least this many edge pixels per pixel of its length (a diagonal edge
#: one pixel thick holds 0.71): a chain of scattered texture pixels is no segment.
MIN_FILL = 0.5

#: ``orientation`` filters: a vertical line's normal is within this of 0 or 180 degrees, a
#: horizontal one's within this of 90 or 270 degrees.
ORIENTATION_TOLERANCE_DEG = 5.0
ORIENTATIONS = ("all", "vertical", "horizontal")

#: Each edge pixel votes in the orientation bins within at least this many of its own (+-4
#: degrees with 2-degree bins): on a straight edge that a warp has resampled, the Sobel
#: orientation of single pixels wanders by a few degrees, and one-bin votes would split a
#: line's support.
DEFAULT_ORIENTATION_SPREAD_BINS = 2

#: ... and in the bins within this many standard errors of its orientation, ``gradient_noise
#: / magnitude`` radians (:attr:`~.edges.EdgeMap.gradient_noise`): the orientation of a
#: faint edge's pixels, a few grey levels of contrast quantized to whole levels, wanders by
#: ten degrees and more, that of a strong edge's by a degree.
ORIENTATION_ERRORS = 2.0

#: ... but in none further than this (degrees) from its own.
MAX_ORIENTATION_TOLERANCE_DEG = 12.0

#: Hough non-maximum suppression half-widths: +-2 orientation bins (wrapping), +-3 rho bins.
HOUGH_SUPPRESSION_THETA_BINS = 2
HOUGH_SUPPRESSION_RHO_BINS = 3

#: Voters of a Hough line lie at most this far (pixels) from the line (cell's, then fitted).
HOUGH_VOTER_DISTANCE = 1.5

#: A segment's edge pixels lie at most this far from its refitted line (the thin chain of a
#: faint, noisy edge wanders by a pixel or two).
PIECE_VOTER_DISTANCE = 2.5

#: A cell's line is fitted among the voters this close to it (pixels): its fits move it by a
#: pixel or two, not more.
NEAR_CELL_DISTANCE = 8.0

#: A segment stands out from what lies beside it: the median gradient magnitude of the edge
#: map (:attr:`~.edges.EdgeMap.magnitude`, smoothed and compensated for magnification) on
#: its pixels is at least ``1 + CONTRAST_MARGIN * sqrt(CONTRAST_LENGTH / length)`` times the
#: median on the pixels :data:`SURROUND_OFFSETS` px to either side: 4.9 times for a segment
#: of 30 px, 4 times for one of 50 px, 2.2 times for one of 300 px. A short line in clutter
#: (branches, brick, a reflection in glass, the shading of a pole) must stand out clearly;
#: the longer a segment, the surer the comparison of the two medians, and the fainter it may
#: be (a white door frame on a white wall, 8 grey levels under noise of 2.5). The bar
#: depends on the image only through what lies beside each segment: a photo's clutter sets it.
CONTRAST_MARGIN = 3.0
CONTRAST_LENGTH = 50.0
SURROUND_OFFSETS = (4.0, 6.0, 8.0, 10.0)


@dataclass(frozen=True)
class Line:
    """A straight segment on the line ``x cos(theta) + y sin(theta) = rho``.

    ``theta_deg`` in ``[0, 360)`` is the (refined) gradient direction of its edge pixels,
    ``rho`` the signed distance from the image origin. ``votes``: its edge pixels.
    ``(x1, y1)``, ``(x2, y2)``: its first and last edge pixels along the line, projected
    onto it; ``length`` the distance between them. ``contrast``: the median gradient
    magnitude of its edge pixels (as thresholded: 3x3 Sobel, a sharp step of ``d`` grey
    levels gives ``4 d``).
    """

    rho: float
    theta_deg: float
    votes: int
    x1: float
    y1: float
    x2: float
    y2: float
    length: float = 0.0
    contrast: float = 0.0


def _max_filter_wrapping_rows(values: np.ndarray, half_width: int) -> np.ndarray:
    """Maximum over rows ``i - half_width .. i + half_width``, rows wrapping around."""
    result = values.copy()
    for shift in range(1, half_width + 1):
        np.maximum(result, np.roll(values, shift, axis=0), out=result)
        np.maximum(result, np.roll(values, -shift, axis=0), out=result)
    return result


def _max_filter_columns(values: np.ndarray, half_width: int, fill: int) -> np.ndarray:
    """Maximum over columns ``j - half_width .. j + half_width``; ``fill`` outside."""
    columns = values.shape[1]
    padded = np.pad(values, ((0, 0), (half_width, half_width)), constant_values=fill)
    result = padded[:, half_width : half_width + columns].copy()
    for start in range(2 * half_width + 1):
        np.maximum(result, padded[:, start : start + columns], out=result)
    return result


def orientation_allows(theta_deg: np.ndarray | float, orientation: str,
                       tolerance_deg: float = ORIENTATION_TOLERANCE_DEG) -> np.ndarray:
    """Whether line normals ``theta_deg`` pass the ``orientation`` filter (see
    :data:`ORIENTATIONS`): ``vertical`` within ``tolerance_deg`` of 0 or 180 degrees."""
    theta = np.asarray(theta_deg, dtype=np.float64)
    if orientation == "all":
        return np.ones(theta.shape, bool)
    if orientation not in ORIENTATIONS:
        raise ValueError(f"orientation must be one of {', '.join(ORIENTATIONS)}, "
                         f"got {orientation!r}")
    centre = 0.0 if orientation == "vertical" else 90.0
    off = np.abs((theta - centre + 90.0) % 180.0 - 90.0)
    return off <= tolerance_deg


def hough_lines(
    image: np.ndarray,
    *,
    edge_threshold: float = DEFAULT_LINE_THRESHOLD,
    theta_step_deg: float = DEFAULT_THETA_STEP_DEG,
    min_votes: int = DEFAULT_MIN_VOTES,
    rho_step: float = 1.0,
    max_lines: int | None = None,
    orientation_spread_bins: int = DEFAULT_ORIENTATION_SPREAD_BINS,
    max_gap: float = DEFAULT_MAX_GAP,
    min_length: float = DEFAULT_MIN_LENGTH,
    orientation: str = "all",
    edges: EdgeMap | None = None,
) -> list[Line]:
    """Straight segments of ``image`` by the thesis's Hough transform (Sec. 5.2.2), longest first.

    Edge pixels: ``edges`` if given, else :func:`~.edges.line_edges` with ``edge_threshold``
    (thin hysteresis edges). Every edge pixel votes in the orientation bin of its own
    gradient direction (bins of ``theta_step_deg`` centred on multiples of it, over ``[0,
    360)``) and the bins on either side within its orientation's noise (:func:`_spread_bins`:
    at least
    ``orientation_spread_bins``), once per bin, for ``rho = x cos(theta) + y sin(theta)``
    with ``theta`` the bin centre, rounded to bins of ``rho_step``. Cells with at least
    ``min_votes`` votes that are the maximum of their +-(2 + ``orientation_spread_bins``)
    orientation bins (wrapping) x +-3 rho bins neighbourhood are candidate lines; equal
    counts go to the cell of lower orientation, then lower rho.

    Candidates are taken strongest first (see :func:`_segments`): the line through the
    cell's edge pixels is fitted, cut where its edge pixels along it are more than
    ``max_gap`` pixels apart, and each piece of at least ``min_length`` pixels (and
    :data:`MIN_FILL` edge pixels per pixel) is refitted on its own pixels (total least
    squares weighted by gradient magnitude, on the not-thinned ``support`` pixels: sub-pixel
    positions) and reported if it stands out from what lies beside it
    (:data:`CONTRAST_MARGIN`). An edge pixel belongs to one segment at most: later
    candidates skip the pixels of segments already found, so a line is not reported twice.

    ``orientation`` (:data:`ORIENTATIONS`) keeps only vertical or horizontal segments (normals
    within :data:`ORIENTATION_TOLERANCE_DEG`) of those found among all (a pixel goes to the
    strongest line it may belong to, whatever its orientation). The refined normal
    keeps the polarity of the cell (within 90 deg of it), so a dark-to-light vertical edge at
    ``x = 100.5`` gives ``theta ~ 0, rho ~ 100.5`` and a light-to-dark one ``theta ~ 180,
    rho ~ -100.5``. Segments come sorted by length (descending), at most ``max_lines``.
    """
    theta_bin_count = orientation_bin_count(theta_step_deg)
    if not rho_step > 0:
        raise ValueError(f"rho_step must be positive, got {rho_step}")
    orientation_allows(0.0, orientation)  # checks the name
    if edges is None:
        edges = line_edges(image, edge_threshold)
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0 or (max_lines is not None and max_lines <= 0):
        return []
    spread = min(max(int(orientation_spread_bins), 0), (theta_bin_count - 1) // 2)
    theta_bin = bin_of_orientation(edges.orientation_deg[rows, cols], theta_step_deg,
                                  theta_bin_count)
    pixel_spread = _spread_bins(edges, rows, cols, theta_step_deg, spread, theta_bin_count)
    x = cols.astype(np.float64)
    y = rows.astype(np.float64)
    bin_theta = np.radians(np.arange(theta_bin_count) * theta_step_deg)
    bin_cos, bin_sin = np.cos(bin_theta), np.sin(bin_theta)
    widest = int(pixel_spread.max())
    shifts = np.arange(-widest, widest + 1)[:, None]
    vote_bin = (theta_bin[None, :] + shifts) % theta_bin_count
    counted = np.abs(shifts) <= pixel_spread[None, :]  # each pixel's own spread
    vote_bin = vote_bin[counted]
    rho = np.broadcast_to(x, counted.shape)[counted] * bin_cos[vote_bin] + np.broadcast_to(
        y, counted.shape)[counted] * bin_sin[vote_bin]

    height, width = edges.mask.shape
    rho_offset = int(math.ceil(math.hypot(width, height) / rho_step)) + 1
    rho_bin_count = 2 * rho_offset + 1
    rho_bin = np.rint(rho / rho_step).astype(np.int64) + rho_offset
    cell = vote_bin * rho_bin_count + rho_bin
    cell_count = theta_bin_count * rho_bin_count
    votes = np.bincount(cell, minlength=cell_count)

    # Unique keys (votes first, then the lower cell index) make the local maxima unambiguous.
    key = votes * cell_count + (cell_count - 1 - np.arange(cell_count))
    key = key.reshape(theta_bin_count, rho_bin_count)
    neighbourhood_max = _max_filter_columns(
        _max_filter_wrapping_rows(key, HOUGH_SUPPRESSION_THETA_BINS + spread),
        HOUGH_SUPPRESSION_RHO_BINS, fill=-1,
    )
    is_peak = (key == neighbourhood_max).ravel() & (votes >= max(int(min_votes), 1))
    peak_cells = np.flatnonzero(is_peak)
    if peak_cells.size == 0:
        return []
    peak_cells = peak_cells[np.argsort(-key.ravel()[peak_cells], kind="stable")]
    support = _Support(edges, theta_step_deg, theta_bin_count, spread)
    voters = _Pixels(x, y, theta_bin, edges.magnitude[rows, cols].astype(np.float64),
                     theta_bin_count, pixel_spread)
    found = _segments(peak_cells, rho_bin_count, rho_offset, rho_step, theta_step_deg,
                      voters, support, max(widest, 1), float(max_gap), float(min_length),
                      max(int(min_votes), 1), edges.gradient, edges.magnitude,
                      edges.measured)
    found = [line for line in found if orientation_allows(line.theta_deg, orientation)]
    found.sort(key=lambda line: -line.length)
    return found if max_lines is None else found[:max_lines]


def _spread_bins(edges: EdgeMap, rows: np.ndarray, cols: np.ndarray, theta_step_deg: float,
                 spread: int, bin_count: int) -> np.ndarray:
    """How many orientation bins on either side of its own each pixel ``(rows, cols)`` votes
    in: its orientation's :data:`ORIENTATION_ERRORS` standard errors (``gradient_noise /
    magnitude`` radians), at least ``spread`` bins, at most
    :data:`MAX_ORIENTATION_TOLERANCE_DEG`; ``spread`` everywhere if the noise is unknown."""
    widest = max(spread, int(MAX_ORIENTATION_TOLERANCE_DEG // theta_step_deg))
    widest = min(widest, (bin_count - 1) // 2)
    if edges.gradient_noise is None or not edges.gradient_noise > 0:
        return np.full(rows.size, spread, np.int64)
    magnitude = edges.magnitude[rows, cols].astype(np.float64)
    with np.errstate(divide="ignore"):
        tolerance = np.degrees(ORIENTATION_ERRORS * edges.gradient_noise / magnitude)
    return np.clip(np.ceil(tolerance / theta_step_deg), spread, widest).astype(np.int64)


class _Support:
    """The ``support`` pixels of an edge map (:attr:`~.edges.EdgeMap.support_mask`) with
    their orientation bins, spreads (as :func:`_spread_bins`) and fit weights, as images:
    those near a line are looked up along it, not searched among all of them."""

    def __init__(self, edges: EdgeMap, theta_step_deg: float, bin_count: int,
                 spread: int) -> None:
        self.mask = edges.support_mask
        rows, cols = np.nonzero(self.mask)
        self.theta_bin = np.zeros(self.mask.shape, np.int64)
        self.theta_bin[rows, cols] = bin_of_orientation(edges.orientation_deg[rows, cols],
                                                        theta_step_deg, bin_count)
        self.spread = np.zeros(self.mask.shape, np.int64)
        self.spread[rows, cols] = _spread_bins(edges, rows, cols, theta_step_deg, spread,
                                               bin_count)
        self.weight = edges.fit_weight
        self.bin_count = bin_count

    def near(self, theta: float, rho: float, first: float, last: float, distance: float,
             theta_bin: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``x``, ``y`` and weights of the support pixels within ``distance`` of the line
        ``(theta, rho)`` between ``first`` and ``last`` along it, whose orientation is within
        their own spread of bin ``theta_bin``."""
        c, s = math.cos(theta), math.sin(theta)
        height, width = self.mask.shape
        # Walk the line's major axis pixel by pixel; across it, the pixels of the band.
        steep = abs(c) >= abs(s)  # normal mostly along x: the line runs down the rows
        ends = (np.array([rho * s + first * c, rho * s + last * c]) if steep
                else np.array([rho * c - first * s, rho * c - last * s]))
        lo, hi = math.floor(ends.min() - distance - 1), math.ceil(ends.max() + distance + 1)
        major = np.arange(max(lo, 0), min(hi, (height if steep else width) - 1) + 1)
        normal, other = (c, s) if steep else (s, c)
        centre = (rho - major * other) / normal  # the line's minor coordinate there
        half_width = math.ceil(distance / abs(normal)) + 1
        minor = np.rint(centre)[:, None].astype(np.int64) + np.arange(-half_width,
                                                                      half_width + 1)
        major = np.broadcast_to(major[:, None], minor.shape)
        rows, cols = (major, minor) if steep else (minor, major)
        inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
        rows, cols = rows[inside], cols[inside]
        half = self.bin_count // 2
        off = np.abs((self.theta_bin[rows, cols] - theta_bin + half) % self.bin_count - half)
        keep = self.mask[rows, cols] & (off <= self.spread[rows, cols])
        rows, cols = rows[keep], cols[keep]
        px, py = cols.astype(np.float64), rows.astype(np.float64)
        pixel_along, pixel_across = _along_and_across(px, py, theta, rho)
        keep = ((np.abs(pixel_across) <= distance) & (pixel_along >= first)
                & (pixel_along <= last))
        return px[keep], py[keep], self.weight[rows[keep], cols[keep]].astype(np.float64)


class _Pixels:
    """Edge pixels ``x``, ``y`` with their orientation bins, weights and spreads (how many
    bins on either side of their own they belong to), indexed by bin."""

    def __init__(self, x: np.ndarray, y: np.ndarray, theta_bin: np.ndarray, weight: np.ndarray,
                 bin_count: int, spread: np.ndarray) -> None:
        self.x, self.y, self.weight = x, y, weight
        self.theta_bin, self.spread = theta_bin, spread
        self.order = np.argsort(theta_bin, kind="stable")
        self.bin_starts = np.searchsorted(theta_bin[self.order], np.arange(bin_count + 1))
        self.bin_count = bin_count
        self._near: dict[tuple[int, int], np.ndarray] = {}

    def near_bin(self, theta_bin: int, spread_bins: int) -> np.ndarray:
        """Indices of the pixels in the bins within ``spread_bins`` of ``theta_bin`` and
        within their own spread of it (kept: many candidate lines share a bin)."""
        key = (theta_bin, spread_bins)
        if key not in self._near:
            near = np.concatenate([
                self.order[self.bin_starts[b]:self.bin_starts[b + 1]]
                for b in compatible_bins(theta_bin, spread_bins, self.bin_count)
            ])
            half = self.bin_count // 2
            off = np.abs((self.theta_bin[near] - theta_bin + half) % self.bin_count - half)
            self._near[key] = near[off <= self.spread[near]]
        return self._near[key]


def _median(values: np.ndarray) -> float:
    """``np.median`` of a non-empty 1-D array (the middle value, or the mean of the two middle
    ones), by one partial sort: numpy's own checks cost more than the sort on the short runs
    of pixels of one segment."""
    middle = values.size // 2
    if values.size % 2:
        return float(np.partition(values, middle)[middle])
    pair = np.partition(values, (middle - 1, middle))[middle - 1:middle + 1]
    return float((pair[0] + pair[1]) / 2)


def _along_and_across(x: np.ndarray, y: np.ndarray, theta: float, rho: float):
    """Positions along the line (direction ``(-sin, cos)``) and signed distances from it."""
    c, s = math.cos(theta), math.sin(theta)
    return -x * s + y * c, x * c + y * s - rho


def _weighted_line_fit(
    x: np.ndarray, y: np.ndarray, weight: np.ndarray, near_theta: float,
) -> tuple[float, float]:
    """Total least squares line ``(theta, rho)`` (radians) through weighted points.

    The normal is perpendicular to the principal direction of the points and taken within
    90 deg of ``near_theta`` (the polarity of the edge); a single point keeps ``near_theta``.
    """
    total = float(weight.sum())
    if not total > 0:  # no weight anywhere (a flat support): every point alike
        weight = np.ones_like(x)
        total = float(x.size)
    mean_x, mean_y = float(weight @ x) / total, float(weight @ y) / total
    dx, dy = x - mean_x, y - mean_y
    spread_xx, spread_xy = float(weight @ (dx * dx)), float(weight @ (dx * dy))
    spread_yy = float(weight @ (dy * dy))
    if spread_xx + spread_yy <= 1e-9 * total:
        theta = near_theta
    else:
        theta = 0.5 * math.atan2(2.0 * spread_xy, spread_xx - spread_yy) + 0.5 * math.pi
        if math.cos(theta - near_theta) < 0:
            theta += math.pi
    theta %= 2.0 * math.pi
    return theta, float(mean_x * math.cos(theta) + mean_y * math.sin(theta))


def _segments(
    peak_cells: np.ndarray, rho_bin_count: int, rho_offset: int, rho_step: float,
    theta_step_deg: float, voters: _Pixels, support: _Support, spread_bins: int,
    max_gap: float, min_length: float, min_votes: int = 1,
    gradient: np.ndarray | None = None, magnitude: np.ndarray | None = None,
    measured: np.ndarray | None = None,
) -> list[Line]:
    """The segments of the Hough cells ``peak_cells`` (strongest first); a loop over cells.

    For each cell: its line is fitted through its free voters (edge pixels whose orientation
    is within their own spread of the cell's, within 1.5 px, at least half a rho bin, of the
    line; total least squares weighted by gradient magnitude, three passes, as the cell's
    line may sit a degree and a pixel off the edge). The free voters within
    :data:`PIECE_VOTER_DISTANCE` of the fitted line (the thin chain of a faint, noisy edge
    wanders) are sorted along it and cut where consecutive ones are more than ``max_gap``
    apart. Each piece long enough that stands out from what lies beside it
    (:func:`_stands_out`) is refitted (:func:`_piece`), and its voters are taken: no later
    cell uses them; a cell left with fewer than ``min_votes`` free voters near its line is
    dropped. Each step is vectorized over the pixels of a few bins.
    """
    voter_distance = max(HOUGH_VOTER_DISTANCE, 0.5 * rho_step)
    free = np.ones(voters.x.size, bool)
    pieces: list[_Piece] = []
    for peak_cell in peak_cells:  # a loop over candidate lines
        peak_theta_bin, peak_rho_bin = divmod(int(peak_cell), rho_bin_count)
        cell_theta = math.radians(peak_theta_bin * theta_step_deg)
        theta, rho = cell_theta, (peak_rho_bin - rho_offset) * rho_step
        nearby = voters.near_bin(peak_theta_bin, spread_bins)
        nearby = nearby[free[nearby]]
        _, across = _along_and_across(voters.x[nearby], voters.y[nearby], theta, rho)
        nearby = nearby[np.abs(across) <= NEAR_CELL_DISTANCE]
        if nearby.size < max(2, min_votes):  # too few left for the test below
            continue
        near_x, near_y, near_weight = voters.x[nearby], voters.y[nearby], voters.weight[nearby]
        close = np.zeros(nearby.size, bool)
        for _ in range(3):  # the cell's line, then the fitted one twice
            _, across = _along_and_across(near_x, near_y, theta, rho)
            close = np.abs(across) <= voter_distance
            if np.count_nonzero(close) < 2:
                break
            theta, rho = _weighted_line_fit(near_x[close], near_y[close], near_weight[close],
                                            cell_theta)
        if np.count_nonzero(close) < max(2, min_votes):
            continue
        voter_along, voter_across = _along_and_across(near_x, near_y, theta, rho)
        along = np.sort(voter_along[np.abs(voter_across) <= PIECE_VOTER_DISTANCE])
        if along.size < 2:
            continue
        voter_band = np.abs(voter_across) <= PIECE_VOTER_DISTANCE + 2.0
        nearby, voter_along = nearby[voter_band], voter_along[voter_band]
        cuts = np.flatnonzero(np.diff(along) > max_gap) + 1
        starts = np.concatenate([[0], cuts])
        ends = np.concatenate([cuts, [along.size]]) - 1
        for start, end in zip(starts, ends):
            first, last = float(along[start]), float(along[end])
            if last - first < min_length - 1e-9:
                continue
            if magnitude is not None and not _stands_out(magnitude, measured, theta, rho,
                                                         first, last):
                continue
            pixels = support.near(theta, rho, first - 2.0, last + 2.0, voter_distance + 2.0,
                                  peak_theta_bin)
            members = nearby[(voter_along >= first - 3.0) & (voter_along <= last + 3.0)]
            piece = _piece(theta, rho, cell_theta, first, last, voters, members, pixels,
                           voter_distance, free, gradient)
            if piece is not None:
                pieces.append(piece)
    return [line for line in _finished(pieces, gradient, measured)
            if line.length >= min_length - 1e-9]


@dataclass(frozen=True)
class _Piece:
    """A segment as :func:`_piece` fitted it, before its ends are finished
    (:func:`_finished`): its line ``(theta, rho)`` radians and pixels, its first and last
    voters along it, their number, their median magnitude
    (``contrast``) and gradient across the line (``strength``)."""

    theta: float
    rho: float
    first: float
    last: float
    votes: int
    contrast: float
    strength: float


def _piece(
    theta: float, rho: float, cell_theta: float, first: float, last: float, voters: _Pixels,
    members: np.ndarray, pixels: tuple[np.ndarray, np.ndarray, np.ndarray],
    voter_distance: float, free: np.ndarray, gradient: np.ndarray | None = None,
) -> _Piece | None:
    """One segment between ``first`` and ``last`` along the line ``(theta, rho)``.

    Refitted twice on the support ``pixels`` within ``voter_distance`` of the line and between
    its ends, weighted by the raw Sobel magnitude (a blurred edge is several pixels thick:
    the weighted fit puts the line where the grey level changes most, a sharp step half-way
    between its two pixel columns). Its ends are its first and last free voters (of
    ``members``) within :data:`PIECE_VOTER_DISTANCE` of the refitted line, projected onto it;
    they are then taken (marked in ``free``). None if they are fewer than :data:`MIN_FILL`
    per pixel of its length. With the raw ``gradient``, its strength: the median gradient
    across the line of its voters (:func:`_finished` moves its ends by it).
    """
    sx, sy, sw = pixels
    for _ in range(2):
        along, across = _along_and_across(sx, sy, theta, rho)
        inside = (np.abs(across) <= voter_distance) & (along >= first - 0.5) & (
            along <= last + 0.5)
        if np.count_nonzero(inside) < 2:
            break
        theta, rho = _weighted_line_fit(sx[inside], sy[inside], sw[inside], cell_theta)
    members = members[free[members]]
    along, across = _along_and_across(voters.x[members], voters.y[members], theta, rho)
    keep = ((np.abs(across) <= PIECE_VOTER_DISTANCE) & (along >= first - 1.0)
            & (along <= last + 1.0))
    members, along = members[keep], along[keep]
    if members.size < max(2.0, MIN_FILL * (last - first)):
        return None
    free[members] = False
    c, s = math.cos(theta), math.sin(theta)
    strength = 0.0
    if gradient is not None:
        cols, rows = voters.x[members].astype(np.int64), voters.y[members].astype(np.int64)
        strength = _median(gradient[0, rows, cols] * c + gradient[1, rows, cols] * s)
    return _Piece(float(theta), float(rho), float(along.min()), float(along.max()),
                  int(members.size), _median(voters.weight[members]), strength)


def _finished(pieces: list[_Piece], gradient: np.ndarray | None,
              measured: np.ndarray | None) -> list[Line]:
    """The pieces as lines, their ends finished, all pieces at once: with the raw
    ``gradient``, each end of a piece of positive strength moves outward by whole pixels (at
    most :data:`MAX_END_EXTENSION`) while the gradient across the line, sampled on it, keeps
    half the piece's strength, with its polarity (:func:`_extensions`); with the
    ``measured`` pixels, each end then moves inward until it lies on one
    (:func:`_measured_ends`)."""
    if not pieces:
        return []
    turns = [(math.cos(p.theta), math.sin(p.theta)) for p in pieces]
    rho, c, s, first, last, strength = (np.array(values, dtype=np.float64) for values in zip(
        *[(p.rho, cos, sin, p.first, p.last, p.strength) for p, (cos, sin) in zip(pieces, turns)]))
    if gradient is not None:
        before, after = _extensions(gradient, rho, c, s, first, last, strength)
        first, last = first - before, last + after
    if measured is not None:
        first, last = _measured_ends(measured, rho, c, s, first, last)
    return [Line(rho=p.rho, theta_deg=math.degrees(p.theta) % 360.0, votes=p.votes,
                 x1=p.rho * cos - a * sin, y1=p.rho * sin + a * cos,
                 x2=p.rho * cos - b * sin, y2=p.rho * sin + b * cos,
                 length=b - a, contrast=p.contrast)
            for p, (cos, sin), a, b in zip(pieces, turns, first.tolist(), last.tolist())]


def _stands_out(magnitude: np.ndarray, measured: np.ndarray | None, theta: float, rho: float,
                first: float, last: float) -> bool:
    """Whether the segment from ``first`` to ``last`` along the line ``(theta, rho)``
    stands out from what lies beside it (:data:`CONTRAST_MARGIN`): the gradient
    ``magnitude`` at the pixels on it against that at the pixels :data:`SURROUND_OFFSETS`
    px to either side (medians of the ``measured`` pixels, all if None). Not if either side
    is mostly unmeasured :data:`SURROUND_OFFSETS` ``[0]`` px away: the segment runs along
    the border of the image or of the fill."""
    c, s = math.cos(theta), math.sin(theta)
    along = np.arange(first, last + 0.5, 1.0)
    offsets = np.array([0.0, *SURROUND_OFFSETS, *(-v for v in SURROUND_OFFSETS)])[:, None]
    height, width = magnitude.shape
    cols = np.rint(rho * c - along * s + offsets * c).astype(np.int64)
    rows = np.rint(rho * s + along * c + offsets * s).astype(np.int64)
    seen = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
    np.minimum(np.maximum(rows, 0, out=rows), height - 1, out=rows)  # np.clip, less overhead
    np.minimum(np.maximum(cols, 0, out=cols), width - 1, out=cols)
    if measured is not None:
        seen &= measured[rows, cols]
    nearest = 1 + len(SURROUND_OFFSETS)  # the row of -SURROUND_OFFSETS[0]
    half = 0.5 * along.size
    if not (np.count_nonzero(seen[1]) >= half and np.count_nonzero(seen[nearest]) >= half
            and seen[0].any()):
        return False
    sampled = magnitude[rows, cols]
    strength = _median(sampled[0][seen[0]])
    surround = _median(sampled[1:][seen[1:]])
    margin = 1.0 + CONTRAST_MARGIN * math.sqrt(CONTRAST_LENGTH / max(last - first, 1.0))
    return strength > 0 and strength >= margin * surround


def _measured_ends(measured: np.ndarray, rho: np.ndarray, c: np.ndarray, s: np.ndarray,
                   first: np.ndarray, last: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ends ``first`` and ``last`` along the lines ``rho`` (normals ``(c, s)``; arrays,
    one entry a line) moved inward, by half pixels and at most :data:`PIECE_VOTER_DISTANCE`
    + 1 px, until each lies on a ``measured`` pixel: an end projected from an edge pixel
    beside the line may fall outside the image or on the fill."""
    inward = np.arange(0.0, PIECE_VOTER_DISTANCE + 1.25, 0.5)
    along = np.concatenate([first[:, None] + inward, last[:, None] - inward], axis=1)
    cols = np.rint((rho * c)[:, None] - along * s[:, None]).astype(np.int64)
    rows = np.rint((rho * s)[:, None] + along * c[:, None]).astype(np.int64)
    height, width = measured.shape
    inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
    on = (inside & measured[np.where(inside, rows, 0), np.where(inside, cols, 0)]).reshape(
        len(rho), 2, -1)
    steps = np.where(on.any(axis=2), on.argmax(axis=2), 0)
    return first + inward[steps[:, 0]], last - inward[steps[:, 1]]


def _extensions(gradient: np.ndarray, rho: np.ndarray, c: np.ndarray, s: np.ndarray,
                first: np.ndarray, last: np.ndarray, strength: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Whole pixels by which the ends ``first`` and ``last`` of segments along the lines
    ``rho`` (normals ``(c, s)``; arrays, one entry a segment) may move outward: how many of
    the points 1, 2, .. :data:`MAX_END_EXTENSION` px beyond each have a gradient across the
    line (bilinear in the raw ``gradient``) of at least half ``strength``, counted from the
    end until the first that has not; none where ``strength`` is not positive."""
    step = np.arange(1, MAX_END_EXTENSION + 1, dtype=np.float64)
    along = np.concatenate([first[:, None] - step, last[:, None] + step], axis=1)
    x = (rho * c)[:, None] - along * s[:, None]
    y = (rho * s)[:, None] + along * c[:, None]
    sampled = _bilinear(gradient, x.ravel(), y.ravel()).reshape(2, *x.shape)
    weak = (sampled[0] * c[:, None] + sampled[1] * s[:, None]
            < 0.5 * strength[:, None]).reshape(len(rho), 2, -1)
    counts = np.where(weak.any(axis=2), weak.argmax(axis=2), MAX_END_EXTENSION)
    counts[~(strength > 0)] = 0
    return counts[:, 0].astype(np.float64), counts[:, 1].astype(np.float64)


def _bilinear(values: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The planes of ``values`` ``(planes, height, width)`` at points ``(x, y)``,
    interpolated bilinearly, shape ``(planes, points)``; 0 outside."""
    height, width = values.shape[1:]
    inside = (x >= 0) & (x <= width - 1) & (y >= 0) & (y <= height - 1)
    x, y = np.where(inside, x, 0.0), np.where(inside, y, 0.0)
    col = np.clip(np.floor(x).astype(np.int64), 0, max(width - 2, 0))
    row = np.clip(np.floor(y).astype(np.int64), 0, max(height - 2, 0))
    fx, fy = x - col, y - row
    right, below = np.minimum(col + 1, width - 1), np.minimum(row + 1, height - 1)
    top = values[:, row, col] * (1 - fx) + values[:, row, right] * fx
    bottom = values[:, below, col] * (1 - fx) + values[:, below, right] * fx
    return np.where(inside, top * (1 - fy) + bottom * fy, 0.0)
