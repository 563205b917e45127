"""Straight lines (door boundaries) by the one-vote-per-pixel Hough transform (thesis Sec. 5.2.2).

Every Sobel edge pixel (:mod:`.edges`) casts ONE vote, in the orientation bin of its own
gradient direction (and the bins beside it), for the line through it with that normal.
Pixel coordinates and angles as in :mod:`.edges`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .edges import (
    DEFAULT_EDGE_THRESHOLD,
    bin_of_orientation,
    compatible_bins,
    edge_map,
    orientation_bin_count,
)

#: Hough orientation sampling and line criterion of the thesis (Sec. 5.2.2).
DEFAULT_THETA_STEP_DEG = 2.0
DEFAULT_MIN_VOTES = 50

#: Each edge pixel votes in the orientation bins within this many of its own (+-4 degrees with
#: 2-degree bins): on a straight edge that a warp has resampled, the Sobel orientation of
#: single pixels wanders by a few degrees, and one-bin votes would split a line's support.
DEFAULT_ORIENTATION_SPREAD_BINS = 2

#: Hough non-maximum suppression half-widths: +-2 orientation bins (wrapping), +-3 rho bins.
HOUGH_SUPPRESSION_THETA_BINS = 2
HOUGH_SUPPRESSION_RHO_BINS = 3

#: Voters of a Hough line lie at most this far (pixels) from the line (cell's, then fitted).
HOUGH_VOTER_DISTANCE = 1.5



@dataclass(frozen=True)
class Line:
    """A straight line ``x cos(theta) + y sin(theta) = rho`` and the segment that supports it.

    ``theta_deg`` in ``[0, 360)`` is the (refined) gradient direction of its edge pixels,
    ``rho`` the signed distance from the image origin. ``votes``: the votes of its Hough
    cell. ``(x1, y1)``, ``(x2, y2)``: the extreme voters along the line, projected onto it.
    """

    rho: float
    theta_deg: float
    votes: int
    x1: float
    y1: float
    x2: float
    y2: float


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


def hough_lines(
    image: np.ndarray,
    *,
    edge_threshold: float = DEFAULT_EDGE_THRESHOLD,
    theta_step_deg: float = DEFAULT_THETA_STEP_DEG,
    min_votes: int = DEFAULT_MIN_VOTES,
    rho_step: float = 1.0,
    max_lines: int | None = None,
    orientation_spread_bins: int = DEFAULT_ORIENTATION_SPREAD_BINS,
) -> list[Line]:
    """Straight lines of ``image`` by the thesis's Hough transform (Sec. 5.2.2), strongest first.

    Every edge pixel (:func:`edge_map` with ``edge_threshold``) votes in the orientation bin
    of its own gradient direction (bins of ``theta_step_deg`` centred on multiples of it, over
    ``[0, 360)``) and the ``orientation_spread_bins`` bins on either side, once per bin, for
    ``rho = x cos(theta) + y sin(theta)`` with ``theta`` the bin centre, rounded to bins of
    ``rho_step``: a line's votes are the edge pixels on it whose orientation agrees with its
    normal within the spread. Cells with at least ``min_votes`` votes that are
    the maximum of their +-(2 + spread) orientation bins (wrapping) x +-3 rho bins
    neighbourhood are lines; equal counts go to the cell of lower orientation, then lower rho.
    Lines that refine to the same line (orientation within the spread, rho within 2 bins)
    are reported once.

    Each line is refined by a total least squares fit through its voters: the edge pixels of
    its cell's and the two neighbouring orientation bins that lie within 1.5 px of the line
    (see :func:`_refine_lines`). The refined normal keeps the polarity of the cell (within
    90 deg of it), so a dark-to-light vertical edge at ``x = 100.5`` gives ``theta ~ 0,
    rho ~ 100.5`` and a light-to-dark one ``theta ~ 180, rho ~ -100.5``. Lines come sorted by
    votes (descending), at most ``max_lines`` of them.
    """
    theta_bin_count = orientation_bin_count(theta_step_deg)
    if not rho_step > 0:
        raise ValueError(f"rho_step must be positive, got {rho_step}")
    edges = edge_map(image, edge_threshold)
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0 or (max_lines is not None and max_lines <= 0):
        return []
    x = cols.astype(np.float64)
    y = rows.astype(np.float64)
    theta_bin = bin_of_orientation(edges.orientation_deg[rows, cols], theta_step_deg,
                                  theta_bin_count)
    bin_theta = np.radians(np.arange(theta_bin_count) * theta_step_deg)
    bin_cos, bin_sin = np.cos(bin_theta), np.sin(bin_theta)
    spread = min(max(int(orientation_spread_bins), 0), (theta_bin_count - 1) // 2)
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
    if max_lines is not None:
        peak_cells = peak_cells[:max_lines]
    refined = _refine_lines(peak_cells, votes, rho_bin_count, rho_offset, rho_step,
                            theta_step_deg, theta_bin, x, y, edges.magnitude[rows, cols],
                            max(spread, 1))
    return _drop_duplicate_lines(refined, theta_step_deg * (spread + 1), 2.0 * rho_step)


def _drop_duplicate_lines(lines: list[Line], theta_tolerance_deg: float,
                          rho_tolerance: float) -> list[Line]:
    """Keep the strongest of lines that refined to the same line (a loop over lines)."""
    kept: list[Line] = []
    for line in lines:  # strongest first
        if not any(
            abs((line.theta_deg - other.theta_deg + 180.0) % 360.0 - 180.0) <= theta_tolerance_deg
            and abs(line.rho - other.rho) <= rho_tolerance
            for other in kept
        ):
            kept.append(line)
    return kept


def _weighted_line_fit(
    x: np.ndarray, y: np.ndarray, weight: np.ndarray, near_theta: float,
) -> tuple[float, float]:
    """Total least squares line ``(theta, rho)`` (radians) through weighted points.

    The normal is perpendicular to the principal direction of the points and taken within
    90 deg of ``near_theta`` (the polarity of the edge); a single point keeps ``near_theta``.
    """
    total = float(weight.sum())
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


def _refine_lines(
    peak_cells: np.ndarray, votes: np.ndarray, rho_bin_count: int, rho_offset: int,
    rho_step: float, theta_step_deg: float, theta_bin: np.ndarray, x: np.ndarray, y: np.ndarray,
    magnitude: np.ndarray, spread_bins: int = 1,
) -> list[Line]:
    """Refined ``rho``, ``theta`` and end points of the Hough lines of ``peak_cells``.

    Voters of a line: the edge pixels of its cell's orientation bin and the ``spread_bins``
    neighbouring bins on either side that lie within 1.5 px (at least half a rho bin) of the
    line. They are first taken around the cell's own line, fitted (total least squares weighted
    by gradient magnitude: a blurred or anti-aliased edge is two or three pixels thick and the
    weights put the line where the grey level changes most; a sharp step lands half-way between
    its two pixel columns), then taken again around the fitted line and refitted, twice. The
    second and third passes matter where the Sobel orientation is biased by a degree or so
    (oblique anti-aliased edges): the cell then sits off-centre on the edge and its first voters
    are one-sided. A loop over lines; each pass is vectorized over the pixels of three bins.
    """
    theta_bin_count = orientation_bin_count(theta_step_deg)
    pixel_order = np.argsort(theta_bin, kind="stable")
    bin_starts = np.searchsorted(theta_bin[pixel_order], np.arange(theta_bin_count + 1))
    voter_distance = max(HOUGH_VOTER_DISTANCE, 0.5 * rho_step)
    lines = []
    for peak_cell in peak_cells:  # a loop over lines
        peak_theta_bin, peak_rho_bin = divmod(int(peak_cell), rho_bin_count)
        cell_theta = math.radians(peak_theta_bin * theta_step_deg)
        theta, rho = cell_theta, (peak_rho_bin - rho_offset) * rho_step
        nearby = np.concatenate([
            pixel_order[bin_starts[b]:bin_starts[b + 1]]
            for b in compatible_bins(peak_theta_bin, spread_bins, theta_bin_count)
        ])
        near_x, near_y, near_weight = x[nearby], y[nearby], magnitude[nearby].astype(np.float64)
        for _ in range(3):  # the cell's line, then the fitted one twice
            close = np.abs(near_x * math.cos(theta) + near_y * math.sin(theta) - rho)
            close = close <= voter_distance
            if not np.any(close):  # only if a refit moved away from every voter
                break
            voter_x, voter_y = near_x[close], near_y[close]
            theta, rho = _weighted_line_fit(voter_x, voter_y, near_weight[close], cell_theta)
        normal_cos, normal_sin = math.cos(theta), math.sin(theta)
        # Extreme voters along the direction (-sin, cos), projected onto the refined line.
        along = -voter_x * normal_sin + voter_y * normal_cos
        first, last = float(along.min()), float(along.max())
        lines.append(Line(
            rho=float(rho), theta_deg=math.degrees(theta) % 360.0,
            votes=int(votes[peak_cell]),
            x1=rho * normal_cos - first * normal_sin, y1=rho * normal_sin + first * normal_cos,
            x2=rho * normal_cos - last * normal_sin, y2=rho * normal_sin + last * normal_cos,
        ))
    return lines
