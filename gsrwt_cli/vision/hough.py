"""Straight segments (door boundaries) by the one-vote-per-pixel Hough transform (Sec. 5.2.2).

Every edge pixel (:mod:`.edges`) casts ONE vote, in the orientation bin of its own gradient
direction (and the bins beside it), for the line through it with that normal. Each line of
the accumulator is then cut into segments where its edge pixels have gaps, so that a door
edge is reported as the door edge and not as a line across the whole view.
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
#: gradient across the line keeps at least half its strength and its polarity: the smoothed
#: orientation of the last few pixels before a corner turns, and they do not vote.
MAX_END_EXTENSION = 6

#: A segment holds at least this many edge pixels per pixel of its length (a diagonal edge
#: one pixel thick holds 0.71): a chain of scattered texture pixels is no segment.
MIN_FILL = 0.5

#: ``orientation`` filters: a vertical line's normal is within this of 0 or 180 degrees, a
#: horizontal one's within this of 90 or 270 degrees.
ORIENTATION_TOLERANCE_DEG = 5.0
ORIENTATIONS = ("all", "vertical", "horizontal")

#: Each edge pixel votes in the orientation bins within this many of its own (+-4 degrees with
#: 2-degree bins): on a straight edge that a warp has resampled, the Sobel orientation of
#: single pixels wanders by a few degrees, and one-bin votes would split a line's support.
DEFAULT_ORIENTATION_SPREAD_BINS = 2

#: Hough non-maximum suppression half-widths: +-2 orientation bins (wrapping), +-3 rho bins.
HOUGH_SUPPRESSION_THETA_BINS = 2
HOUGH_SUPPRESSION_RHO_BINS = 3

#: Voters of a Hough line lie at most this far (pixels) from the line (cell's, then fitted).
HOUGH_VOTER_DISTANCE = 1.5

#: A segment's edge pixels lie at most this far from its refitted line (the thin chain of a
#: faint, noisy edge wanders by a pixel or two).
PIECE_VOTER_DISTANCE = 2.5



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
    (thin hysteresis edges). Every edge pixel votes in the orientation bin of its own gradient
    direction (bins of ``theta_step_deg`` centred on multiples of it, over ``[0, 360)``) and
    the ``orientation_spread_bins`` bins on either side, once per bin, for ``rho = x
    cos(theta) + y sin(theta)`` with ``theta`` the bin centre, rounded to bins of
    ``rho_step``. Cells with at least ``min_votes`` votes that are the maximum of their +-(2 +
    spread) orientation bins (wrapping) x +-3 rho bins neighbourhood are candidate lines;
    equal counts go to the cell of lower orientation, then lower rho.

    Candidates are taken strongest first (see :func:`_segments_of_cell`): the line through
    the cell's edge pixels is fitted, cut where its edge pixels along it are more than
    ``max_gap`` pixels apart, and each piece of at least ``min_length`` pixels (and
    :data:`MIN_FILL` edge pixels per pixel) is refitted on its own pixels (total least
    squares weighted by gradient magnitude, on the not-thinned ``support`` pixels: sub-pixel
    positions) and reported. An edge pixel belongs to one segment at most: later candidates
    skip the pixels of segments already found, so a line is not reported twice.

    ``orientation`` (:data:`ORIENTATIONS`) keeps only vertical or horizontal segments (normals
    within :data:`ORIENTATION_TOLERANCE_DEG`); only their pixels vote. The refined normal
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
    if orientation != "all":
        near = orientation_allows(theta_bin * theta_step_deg, orientation,
                                  ORIENTATION_TOLERANCE_DEG + (spread + 1) * theta_step_deg)
        rows, cols, theta_bin = rows[near], cols[near], theta_bin[near]
        if cols.size == 0:
            return []
    x = cols.astype(np.float64)
    y = rows.astype(np.float64)
    bin_theta = np.radians(np.arange(theta_bin_count) * theta_step_deg)
    bin_cos, bin_sin = np.cos(bin_theta), np.sin(bin_theta)
    vote_bin = (theta_bin[None, :] + np.arange(-spread, spread + 1)[:, None]) % theta_bin_count
    rho = x * bin_cos[vote_bin] + y * bin_sin[vote_bin]

    height, width = edges.mask.shape
    rho_offset = int(math.ceil(math.hypot(width, height) / rho_step)) + 1
    rho_bin_count = 2 * rho_offset + 1
    rho_bin = np.rint(rho / rho_step).astype(np.int64) + rho_offset
    cell = vote_bin * rho_bin_count + rho_bin
    cell_count = theta_bin_count * rho_bin_count
    votes = np.bincount(cell.ravel(), minlength=cell_count)

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
    support_rows, support_cols = np.nonzero(edges.support_mask)
    support = _Pixels(support_cols.astype(np.float64), support_rows.astype(np.float64),
                      bin_of_orientation(edges.orientation_deg[support_rows, support_cols],
                                         theta_step_deg, theta_bin_count),
                      edges.fit_weight[support_rows, support_cols].astype(np.float64),
                      theta_bin_count)
    voters = _Pixels(x, y, theta_bin, edges.magnitude[rows, cols].astype(np.float64),
                     theta_bin_count)
    found = _segments(peak_cells, rho_bin_count, rho_offset, rho_step, theta_step_deg,
                      voters, support, max(spread, 1), float(max_gap), float(min_length),
                      max(int(min_votes), 1), edges.gradient)
    found = [line for line in found if orientation_allows(line.theta_deg, orientation)]
    found.sort(key=lambda line: -line.length)
    return found if max_lines is None else found[:max_lines]


class _Pixels:
    """Edge pixels ``x``, ``y`` with their orientation bins and weights, indexed by bin."""

    def __init__(self, x: np.ndarray, y: np.ndarray, theta_bin: np.ndarray, weight: np.ndarray,
                 bin_count: int) -> None:
        self.x, self.y, self.weight = x, y, weight
        self.order = np.argsort(theta_bin, kind="stable")
        self.bin_starts = np.searchsorted(theta_bin[self.order], np.arange(bin_count + 1))
        self.bin_count = bin_count
        self._near: dict[tuple[int, int], np.ndarray] = {}

    def near_bin(self, theta_bin: int, spread_bins: int) -> np.ndarray:
        """Indices of the pixels in the bins within ``spread_bins`` of ``theta_bin``
        (kept: many candidate lines share a bin)."""
        key = (theta_bin, spread_bins)
        if key not in self._near:
            self._near[key] = np.concatenate([
                self.order[self.bin_starts[b]:self.bin_starts[b + 1]]
                for b in compatible_bins(theta_bin, spread_bins, self.bin_count)
            ])
        return self._near[key]


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
    theta_step_deg: float, voters: _Pixels, support: _Pixels, spread_bins: int,
    max_gap: float, min_length: float, min_votes: int = 1,
    gradient: np.ndarray | None = None,
) -> list[Line]:
    """The segments of the Hough cells ``peak_cells`` (strongest first); a loop over cells.

    For each cell: its line is fitted through its free voters (edge pixels of the cell's and
    the ``spread_bins`` neighbouring orientation bins within 1.5 px, at least half a rho
    bin, of the line; total least squares weighted by gradient magnitude, three passes, as the
    cell's line may sit a degree and a pixel off the edge). The support pixels of the same
    bins within 1.5 px of the fitted line are sorted along it and cut where consecutive ones
    are more than ``max_gap`` apart (a thin chain of edge pixels on a faint, noisy edge
    wanders; the thicker support band around it does not break). Each piece long enough is
    refitted (:func:`_piece`), and its voters are taken: no later cell uses them; a cell
    left with fewer than ``min_votes`` free voters near its line is dropped. Each step is
    vectorized over the pixels of a few bins.
    """
    voter_distance = max(HOUGH_VOTER_DISTANCE, 0.5 * rho_step)
    free = np.ones(voters.x.size, bool)
    lines: list[Line] = []
    for peak_cell in peak_cells:  # a loop over candidate lines
        peak_theta_bin, peak_rho_bin = divmod(int(peak_cell), rho_bin_count)
        cell_theta = math.radians(peak_theta_bin * theta_step_deg)
        theta, rho = cell_theta, (peak_rho_bin - rho_offset) * rho_step
        nearby = voters.near_bin(peak_theta_bin, spread_bins)
        nearby = nearby[free[nearby]]
        if nearby.size < 2:
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
        support_near = support.near_bin(peak_theta_bin, spread_bins)
        support_along, support_across = _along_and_across(
            support.x[support_near], support.y[support_near], theta, rho)
        band = np.abs(support_across) <= voter_distance + 2.0  # where refits may look
        support_near, support_along = support_near[band], support_along[band]
        along = np.sort(support_along[np.abs(support_across[band]) <= voter_distance])
        if along.size < 2:
            continue
        voter_along, voter_across = _along_and_across(near_x, near_y, theta, rho)
        voter_band = np.abs(voter_across) <= PIECE_VOTER_DISTANCE + 2.0
        nearby, voter_along = nearby[voter_band], voter_along[voter_band]
        cuts = np.flatnonzero(np.diff(along) > max_gap) + 1
        starts = np.concatenate([[0], cuts])
        ends = np.concatenate([cuts, [along.size]]) - 1
        for start, end in zip(starts, ends):
            first, last = float(along[start]), float(along[end])
            if last - first < min_length - 1e-9:
                continue
            pixels = support_near[(support_along >= first - 2.0) & (support_along <= last + 2.0)]
            members = nearby[(voter_along >= first - 3.0) & (voter_along <= last + 3.0)]
            line = _piece(theta, rho, cell_theta, first, last, voters, members, support,
                          pixels, voter_distance, free, gradient)
            if line is not None and line.length >= min_length - 1e-9:
                lines.append(line)
    return lines


def _piece(
    theta: float, rho: float, cell_theta: float, first: float, last: float, voters: _Pixels,
    members: np.ndarray, support: _Pixels, pixels: np.ndarray, voter_distance: float,
    free: np.ndarray, gradient: np.ndarray | None = None,
) -> Line | None:
    """One segment between ``first`` and ``last`` along the line ``(theta, rho)``.

    Refitted twice on the support ``pixels`` within ``voter_distance`` of the line and between
    its ends, weighted by the raw Sobel magnitude (a blurred edge is several pixels thick:
    the weighted fit puts the line where the grey level changes most, a sharp step half-way
    between its two pixel columns). Its ends are its first and last free voters (of
    ``members``) within :data:`PIECE_VOTER_DISTANCE` of the refitted line, projected onto it;
    they are then taken (marked in ``free``). None if they are fewer than :data:`MIN_FILL`
    per pixel of its length. With the raw ``gradient``, each end then moves outward by whole
    pixels (at most :data:`MAX_END_EXTENSION`) while the gradient across the line, sampled
    on it, keeps half the median strength of its voters, with their polarity.
    """
    sx, sy, sw = support.x[pixels], support.y[pixels], support.weight[pixels]
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
    first, last = float(along.min()), float(along.max())
    c, s = math.cos(theta), math.sin(theta)
    if gradient is not None:
        cols, rows = voters.x[members].astype(np.int64), voters.y[members].astype(np.int64)
        strength = float(np.median(gradient[0, rows, cols] * c + gradient[1, rows, cols] * s))
        if strength > 0:
            before, after = _extensions(gradient, theta, rho, first, last, strength)
            first, last = first - before, last + after
    return Line(
        rho=float(rho), theta_deg=math.degrees(theta) % 360.0, votes=int(members.size),
        x1=rho * c - first * s, y1=rho * s + first * c,
        x2=rho * c - last * s, y2=rho * s + last * c,
        length=last - first, contrast=float(np.median(voters.weight[members])),
    )


def _extensions(gradient: np.ndarray, theta: float, rho: float, first: float, last: float,
                strength: float) -> tuple[int, int]:
    """Whole pixels by which a segment's ends ``first`` and ``last`` (along its line) may move
    outward: how many of the points 1, 2, .. :data:`MAX_END_EXTENSION` px beyond each have a
    gradient across the line (bilinear in the raw ``gradient``) of at least half
    ``strength``, counted from the end until the first that has not."""
    c, s = math.cos(theta), math.sin(theta)
    step = np.arange(1, MAX_END_EXTENSION + 1, dtype=np.float64)
    along = np.concatenate([first - step, last + step])
    x, y = rho * c - along * s, rho * s + along * c
    sampled = _bilinear(gradient, x, y)  # (2, points)
    weak = (sampled[0] * c + sampled[1] * s < 0.5 * strength).reshape(2, -1)
    counts = np.where(weak.any(axis=1), weak.argmax(axis=1), MAX_END_EXTENSION)
    return int(counts[0]), int(counts[1])


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
