"""Landmarks on rectified (frontal) wall images: straight lines and door parts (thesis Sec. 5.2.2).

Once a wall has been rectified into its frontal view, the thesis looks for a door with two
voting schemes on the Sobel edges of the grey image:

- straight lines with a Hough transform in which every edge pixel casts ONE vote, in the
  orientation bin of its own gradient direction (:func:`hough_lines`);
- the door knob and the peek window with the Generalized Hough Transform (GHT, Ballard 1981)
  and a single fixed model cut out of an example image (:func:`build_template`,
  :func:`match_template`).

Pure numpy (and ``cv2`` for the Sobel mask, colour conversion and 3x3 filters): arrays in,
dataclasses out, no file I/O, no printing.

Conventions
-----------
Unlike :mod:`gsrwt_cli.geometry` (``x`` up, ``y`` right), this module works in plain pixel
coordinates: ``x`` is the column (to the right), ``y`` the row (downward), pixel centres at
integers. Angles are degrees. Images are 2-D ``uint8`` grey arrays or ``uint8`` BGR / BGRA
colour arrays, converted to grey with :func:`cv2.cvtColor`.

The gradient orientation ``atan2(gy, gx)`` in ``[0, 360)`` points from dark to light: a dark
left half and light right half gives 0 deg, dark top and light bottom gives 90 deg. It is
the normal ``theta`` of the line ``x cos(theta) + y sin(theta) = rho`` through the edge, so
a vertical edge has ``theta`` near 0 or 180 deg and a horizontal one near 90 or 270 deg.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

#: Sobel magnitude (raw 3x3 mask, grey levels) at which a pixel is an edge (thesis Sec. 5.2.2).
DEFAULT_EDGE_THRESHOLD = 80.0

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

#: GHT R-table orientation bin width (degrees): wide enough that Sobel orientation noise on
#: anti-aliased curves rarely moves a pixel by more than one bin.
DEFAULT_GHT_ORIENTATION_STEP_DEG = 4.0

#: A model edge pixel is found where an image edge pixel's orientation is this many GHT bins
#: (6 degrees by default) or less away from its own.
GHT_FOUND_ORIENTATION_BINS = 1.5

#: Model bounding boxes of the thesis, read as ``(width, height)`` in pixels (Sec. 5.2.2: "40x100"
#: for the door knob, "120x90" for the peek window).
DOOR_KNOB_BOX = (40, 100)
PEEK_WINDOW_BOX = (120, 90)

#: At most this many accumulator peaks are considered, and this many (or ``4 * max_matches``
#: if more) distinct ones are verified, when matching a template.
_GHT_PEAK_CANDIDATES = 256
_GHT_MIN_VERIFIED = 20

#: Votes buffered per ``np.bincount`` call when filling the GHT accumulator (32 MB of int64).
_GHT_VOTE_CHUNK = 1 << 22

GreyImage = NDArray[np.uint8]


# --------------------------------------------------------------------------------------------
# Edges (thesis Sec. 5.2.2: 3x3 Sobel, magnitude threshold 80)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class EdgeMap:
    """Sobel gradient of a grey image and its edge pixels (thesis Sec. 5.2.2).

    ``magnitude``: ``float32``, the raw ``cv2.Sobel`` (``ksize=3``) magnitude
    ``sqrt(gx**2 + gy**2)``. ``orientation_deg``: ``float32``, ``atan2(gy, gx)`` in degrees,
    in ``[0, 360)``, pointing from dark to light. ``mask``: ``bool``, ``magnitude >=
    threshold``, never set on the 1-pixel image border (where the mask sees outside the image).
    """

    magnitude: NDArray[np.float32]
    orientation_deg: NDArray[np.float32]
    mask: NDArray[np.bool_]


def grey_image(image: np.ndarray) -> GreyImage:
    """The 2-D ``uint8`` grey version of a grey, BGR or BGRA ``uint8`` image."""
    pixels = np.asarray(image)
    if pixels.dtype != np.uint8:
        raise TypeError(f"expected an 8-bit (uint8) image, got {pixels.dtype}")
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    if pixels.ndim == 2:
        return np.ascontiguousarray(pixels)
    if pixels.ndim != 3 or pixels.shape[2] not in (3, 4):
        raise ValueError(f"expected a grey, BGR or BGRA image, got shape {pixels.shape}")
    if pixels.shape[0] == 0 or pixels.shape[1] == 0:
        return np.zeros(pixels.shape[:2], np.uint8)
    code = cv2.COLOR_BGR2GRAY if pixels.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
    return cv2.cvtColor(np.ascontiguousarray(pixels), code)


def edge_map(image: np.ndarray, threshold: float = DEFAULT_EDGE_THRESHOLD) -> EdgeMap:
    """Sobel magnitude, orientation and edge pixels of ``image`` (thesis Sec. 5.2.2).

    ``threshold`` is compared with the raw 3x3 Sobel magnitude (a step of ``d`` grey levels
    gives ``4 d``); the thesis uses 80.
    """
    grey = grey_image(image)
    height, width = grey.shape
    if height == 0 or width == 0:
        empty = np.zeros((height, width), np.float32)
        return EdgeMap(empty, empty.copy(), np.zeros((height, width), bool))
    gradient_x = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gradient_y = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    magnitude = cv2.magnitude(gradient_x, gradient_y)
    orientation = np.degrees(np.arctan2(gradient_y, gradient_x)).astype(np.float32)
    orientation[orientation < 0] += np.float32(360.0)
    orientation[orientation >= 360.0] = 0.0  # -tiny + 360 rounds to 360 in float32
    mask = np.zeros((height, width), bool)
    mask[1:-1, 1:-1] = magnitude[1:-1, 1:-1] >= threshold
    return EdgeMap(magnitude, orientation, mask)


def _orientation_bin_count(step_deg: float) -> int:
    """How many bins of ``step_deg`` cover 360 degrees; ``step_deg`` must divide 360."""
    if not step_deg > 0:
        raise ValueError(f"orientation step must be positive, got {step_deg}")
    count = 360.0 / step_deg
    if abs(count - round(count)) > 1e-6:
        raise ValueError(f"orientation step {step_deg} deg does not divide 360 deg")
    return int(round(count))


def _orientation_bins(orientation_deg: np.ndarray, step_deg: float, bin_count: int) -> np.ndarray:
    """Bin ``k`` (centre ``k * step_deg``) of each orientation, wrapping at 360 degrees."""
    return np.rint(orientation_deg / step_deg).astype(np.int64) % bin_count


def _compatible_bins(orientation_bin: int, tolerance_bins: int, bin_count: int) -> list[int]:
    """Orientation bins within ``tolerance_bins`` of ``orientation_bin``, wrapping, no repeats."""
    if 2 * tolerance_bins + 1 >= bin_count:
        return list(range(bin_count))
    return [(orientation_bin + d) % bin_count for d in range(-tolerance_bins, tolerance_bins + 1)]


# --------------------------------------------------------------------------------------------
# Straight lines: one-vote-per-pixel Hough transform (thesis Sec. 5.2.2)
# --------------------------------------------------------------------------------------------


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

    @property
    def length(self) -> float:
        """Length of the supported segment, pixels."""
        return math.hypot(self.x2 - self.x1, self.y2 - self.y1)


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
    theta_bin_count = _orientation_bin_count(theta_step_deg)
    if not rho_step > 0:
        raise ValueError(f"rho_step must be positive, got {rho_step}")
    edges = edge_map(image, edge_threshold)
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0 or (max_lines is not None and max_lines <= 0):
        return []
    x = cols.astype(np.float64)
    y = rows.astype(np.float64)
    theta_bin = _orientation_bins(edges.orientation_deg[rows, cols], theta_step_deg,
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
    theta_bin_count = _orientation_bin_count(theta_step_deg)
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
            for b in _compatible_bins(peak_theta_bin, spread_bins, theta_bin_count)
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


# --------------------------------------------------------------------------------------------
# Door knob and peek window: Generalized Hough Transform with one model (thesis Sec. 5.2.2)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Template:
    """A GHT model: the R-table of a cut-out bounding box (thesis Sec. 5.2.2, Ballard 1981).

    Every edge pixel of the box is a model entry, stored as its offset ``(dx, dy) = reference -
    pixel`` to the reference point (the box centre ``((width - 1) / 2, (height - 1) / 2)``)
    and indexed by its gradient orientation bin. Entries are sorted by bin: those of bin ``b``
    are ``offsets[bin_starts[b]:bin_starts[b + 1]]``.
    """

    width: int
    height: int
    edge_count: int
    orientation_step_deg: float
    offsets: NDArray[np.float64]  # (edge_count, 2): dx, dy
    orientation_bins: NDArray[np.int64]  # (edge_count,), ascending
    orientation_deg: NDArray[np.float32]  # (edge_count,): each entry's gradient orientation
    bin_starts: NDArray[np.int64]  # (bin_count + 1,)

    @property
    def bin_count(self) -> int:
        """Number of orientation bins of the R-table (``360 / orientation_step_deg``)."""
        return self.bin_starts.size - 1

    def entries_in_bin(self, orientation_bin: int) -> NDArray[np.float64]:
        """The R-table row of ``orientation_bin``: offsets of model pixels in that bin."""
        b = orientation_bin % self.bin_count
        return self.offsets[self.bin_starts[b] : self.bin_starts[b + 1]]


def build_template(
    image: np.ndarray,
    *,
    edge_threshold: float = DEFAULT_EDGE_THRESHOLD,
    orientation_step_deg: float = DEFAULT_GHT_ORIENTATION_STEP_DEG,
) -> Template:
    """The GHT model of a cut-out bounding box (e.g. 40x100 for a knob, 120x90 for a window).

    As in the thesis (Sec. 5.2.2) every edge pixel inside the box (:func:`edge_map`; the
    1-pixel rim of the cut-out is left out, its gradient would see beyond the box) is part of
    the model, the reference point is the box centre, and entries are indexed by gradient
    orientation in bins of ``orientation_step_deg``. Raises :class:`ValueError` if the box has
    no edge pixels.
    """
    bin_count = _orientation_bin_count(orientation_step_deg)
    edges = edge_map(image, edge_threshold)
    height, width = edges.mask.shape
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0:
        raise ValueError("the template has no edge pixels; nothing to match")
    orientation_bins = _orientation_bins(edges.orientation_deg[rows, cols], orientation_step_deg,
                                         bin_count)
    order = np.argsort(orientation_bins, kind="stable")
    offsets = np.column_stack([(width - 1) / 2 - cols, (height - 1) / 2 - rows]).astype(np.float64)
    sorted_bins = orientation_bins[order]
    return Template(
        width=int(width),
        height=int(height),
        edge_count=int(cols.size),
        orientation_step_deg=float(orientation_step_deg),
        offsets=offsets[order],
        orientation_bins=sorted_bins,
        orientation_deg=edges.orientation_deg[rows, cols][order],
        bin_starts=np.searchsorted(sorted_bins, np.arange(bin_count + 1)).astype(np.int64),
    )


@dataclass(frozen=True)
class Match:
    """Where a template was found: its reference point (box centre) ``(x, y)`` at ``scale``.

    ``votes``: how many model edge pixels were found at this place, each counted at most once
    (see :func:`match_template`); ``score = votes / template.edge_count`` in ``[0, 1]``: the
    fraction of the model found.
    """

    x: float
    y: float
    scale: float
    votes: int
    score: float


def match_template(
    image: np.ndarray,
    template: Template,
    *,
    scales: Sequence[float] = (0.9, 0.95, 1.0, 1.05, 1.1),
    edge_threshold: float = DEFAULT_EDGE_THRESHOLD,
    min_score: float = 0.0,
    max_matches: int = 5,
    orientation_tolerance_bins: int = 1,
) -> list[Match]:
    """Find ``template`` in ``image`` with the Generalized Hough Transform (thesis Sec. 5.2.2).

    Voting: every image edge pixel of orientation bin ``b`` (bins of the template's
    ``orientation_step_deg``) takes every R-table entry of bins ``b - tol .. b + tol``
    (``tol = orientation_tolerance_bins``, wrapping) and, for every scale ``s``, votes for a
    reference point at ``pixel + s * offset`` rounded to the nearest pixel, in a
    ``(scale, y, x)`` accumulator; votes outside the image are dropped.

    Peaks: the accumulator is summed over 3x3 pixels (so that +-1 px rounding does not split
    a peak); its local maxima over ``(scale, y, x)`` are taken strongest first, a peak closer
    than half the template's smaller side to a stronger one being the same match (the
    strongest ``max(20, 4 * max_matches)`` distinct places are kept).

    Position: the vote-weighted centroid of the 3x3 window around the peak, each vote at its
    exact (unrounded) position, then re-centred on that centroid twice more (a window centred
    on a whole pixel is lopsided when the true centre lies between pixels; see
    :func:`_peak_votes`). The scale is the peak's, one of ``scales``.

    Score: each model edge pixel counts at most once -- as found when, with the reference
    point at the match, an image edge pixel lies in the 3x3 window around where the pixel
    should be and its gradient orientation is within 1.5 bins (6 degrees by default) of the
    model pixel's -- so ``score = votes / edge_count`` is the fraction of the model found, in
    ``[0, 1]``, whatever ``tol`` and edge thickness (plain vote counts would exceed
    ``edge_count``: two-pixel-thick edges and neighbouring bins vote several times for the
    same place). Comparing angles rather than bins keeps the score free of bin boundaries.
    Matches with ``score >= min_score`` come sorted by score (descending), at most
    ``max_matches``.

    ``tol = 1`` (default) lets image and model orientations differ by up to a bin and a
    half: with the 4-degree bins of :func:`build_template` a residual rotation of a few
    degrees costs few votes, and so do horizontal edges (90 and 270 deg are bin boundaries,
    as 4 does not divide 90). ``tol = 0`` casts a third of the votes (up to twice as fast);
    pair it with a bin width that divides 90 (e.g. 3, 5 or 6 degrees).
    """
    if orientation_tolerance_bins < 0:
        raise ValueError("orientation_tolerance_bins must not be negative")
    scale_values = np.asarray(list(scales), dtype=np.float64)
    if scale_values.size and not np.all(scale_values > 0):
        raise ValueError(f"scales must be positive, got {list(scales)}")
    edges = edge_map(image, edge_threshold)
    height, width = edges.mask.shape
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0 or scale_values.size == 0 or max_matches <= 0 or template.edge_count == 0:
        return []
    bin_count = template.bin_count
    image_bins = _orientation_bins(edges.orientation_deg[rows, cols],
                                   template.orientation_step_deg, bin_count)

    # Accumulator padded by the longest scaled offset: no per-vote bounds checks.
    margin = int(math.ceil(scale_values.max() * np.abs(template.offsets).max())) + 2
    padded_width, padded_height = width + 2 * margin, height + 2 * margin
    plane_size = padded_width * padded_height
    scale_count = scale_values.size
    rounded_offsets = np.rint(scale_values[:, None, None] * template.offsets[None]).astype(np.int64)
    offset_index = rounded_offsets[..., 1] * padded_width + rounded_offsets[..., 0]
    raw_votes = _ght_votes(rows, cols, image_bins, template, offset_index,
                           orientation_tolerance_bins, margin, padded_width, plane_size)
    raw_votes = raw_votes.reshape(scale_count, padded_height, padded_width)
    raw_votes = np.ascontiguousarray(raw_votes[:, margin:margin + height, margin:margin + width],
                                     dtype=np.float32)

    window = np.ones((3, 3), np.uint8)
    smoothed = np.empty_like(raw_votes)
    dilated = np.empty_like(raw_votes)
    for s in range(scale_count):  # a handful of scales
        smoothed[s] = cv2.boxFilter(raw_votes[s], -1, (3, 3), normalize=False,
                                    borderType=cv2.BORDER_CONSTANT)
        dilated[s] = cv2.dilate(smoothed[s], window, borderType=cv2.BORDER_CONSTANT,
                                borderValue=0)
    neighbourhood_max = dilated.copy()
    np.maximum(neighbourhood_max[1:], dilated[:-1], out=neighbourhood_max[1:])
    np.maximum(neighbourhood_max[:-1], dilated[1:], out=neighbourhood_max[:-1])
    peaks = np.flatnonzero((smoothed >= neighbourhood_max) & (smoothed > 0))
    if peaks.size == 0:
        return []
    peak_strength = smoothed.ravel()[peaks]
    if peaks.size > _GHT_PEAK_CANDIDATES:
        strongest = np.argpartition(-peak_strength, _GHT_PEAK_CANDIDATES - 1)
        peaks = peaks[strongest[:_GHT_PEAK_CANDIDATES]]
        peak_strength = peak_strength[strongest[:_GHT_PEAK_CANDIDATES]]
    order = np.lexsort((peaks, -peak_strength))
    peak_scale, peak_y, peak_x = np.unravel_index(peaks[order], smoothed.shape)

    # Distinct places, strongest first (a loop over at most a few hundred peaks).
    same_match_distance_sq = (0.5 * min(template.width, template.height)) ** 2
    wanted = max(_GHT_MIN_VERIFIED, 4 * max_matches)
    kept: list[int] = []
    for index in range(peaks.size):
        if kept:
            dx = peak_x[kept] - peak_x[index]
            dy = peak_y[kept] - peak_y[index]
            if np.any(dx * dx + dy * dy < same_match_distance_sq):
                continue
        kept.append(index)
        if len(kept) >= wanted:
            break
    kept_scale, kept_y, kept_x = peak_scale[kept], peak_y[kept], peak_x[kept]

    model_votes, centre_x, centre_y = _peak_votes(
        kept_scale, kept_y, kept_x, scale_values, rows, cols,
        edges.orientation_deg[rows, cols], template, height, width, margin,
    )

    matches = [
        Match(x=float(centre_x[i]), y=float(centre_y[i]), scale=float(scale_values[kept_scale[i]]),
              votes=int(model_votes[i]), score=float(model_votes[i] / template.edge_count))
        for i in range(len(kept))
    ]
    matches.sort(key=lambda match: -match.score)  # stable: ties keep accumulator order
    return [match for match in matches if match.score >= min_score][:max_matches]


def _ght_votes(
    rows: np.ndarray, cols: np.ndarray, image_bins: np.ndarray, template: Template,
    offset_index: np.ndarray, tolerance_bins: int, margin: int, padded_width: int,
    plane_size: int,
) -> np.ndarray:
    """The ``(scale, padded y * padded x)`` GHT accumulator: raw vote counts.

    ``offset_index[s, j]``: flat padded-plane offset of R-table entry ``j`` at scale ``s``.
    One scale at a time (an accumulator plane of a few MB stays in cache, which makes
    ``np.bincount`` several times faster than on all scales at once); votes of one entry
    sweep the plane in raster order. A loop over scales and orientation bins only.
    """
    bin_count = template.bin_count
    pixel_index = (rows.astype(np.int64) + margin) * padded_width + (cols.astype(np.int64) + margin)
    order = np.argsort(image_bins, kind="stable")  # raster order within each bin
    pixel_index = pixel_index[order]
    image_bin_starts = np.searchsorted(image_bins[order], np.arange(bin_count + 1))
    entries_of_bin = [np.arange(template.bin_starts[b], template.bin_starts[b + 1])
                      for b in range(bin_count)]
    voting = []  # (image pixels of bin b, R-table entries they use)
    for b in range(bin_count):
        pixels = pixel_index[image_bin_starts[b]:image_bin_starts[b + 1]]
        entries = np.concatenate([entries_of_bin[c] for c in
                                  _compatible_bins(b, tolerance_bins, bin_count)])
        if pixels.size and entries.size:
            voting.append((pixels, entries))

    scale_count = offset_index.shape[0]
    accumulator = np.zeros((scale_count, plane_size), np.int64)
    buffer = np.empty(_GHT_VOTE_CHUNK, np.int64)
    for s in range(scale_count):
        filled = 0
        for pixels, entries in voting:
            offsets = offset_index[s, entries]
            pixels_per_chunk = max(1, _GHT_VOTE_CHUNK // offsets.size)
            for start in range(0, pixels.size, pixels_per_chunk):
                chunk = pixels[start:start + pixels_per_chunk]
                vote_count = offsets.size * chunk.size
                if filled + vote_count > buffer.size:
                    accumulator[s] += np.bincount(buffer[:filled], minlength=plane_size)
                    filled = 0
                    if vote_count > buffer.size:
                        buffer = np.empty(vote_count, np.int64)
                np.add(offsets[:, None], chunk[None, :],
                       out=buffer[filled:filled + vote_count].reshape(offsets.size, chunk.size))
                filled += vote_count
        if filled:
            accumulator[s] += np.bincount(buffer[:filled], minlength=plane_size)
    return accumulator


def _peak_votes(
    peak_scale: np.ndarray, peak_y: np.ndarray, peak_x: np.ndarray, scale_values: np.ndarray,
    rows: np.ndarray, cols: np.ndarray, orientation_deg: np.ndarray, template: Template,
    height: int, width: int, margin: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model edge pixels found at each peak (each counted once) and the peak's sub-pixel centre.

    With the reference point at ``c``, model entry ``j`` at scale ``s`` predicts an edge pixel
    at ``c - s * offset_j``; it is found if an image edge pixel (``rows``, ``cols``,
    ``orientation_deg``) whose gradient orientation is within ``GHT_FOUND_ORIENTATION_BINS``
    bin widths of the entry's lies in the 3x3 window around that prediction (rounded): such
    pixels voted (through ``j`` or an entry of a neighbouring bin) into the 3x3 window of
    ``c``. Comparing angles, not bins, keeps the count free of bin boundaries and of the
    voting tolerance.

    The centre starts at the integer peak and moves, three times, to the centroid of those
    pixels' votes at their exact positions ``pixel + s * offset_j`` (the first move is the
    vote-weighted centroid of the peak's 3x3 window; the next ones re-centre the window,
    which removes the pull of a window centred up to half a pixel off the true centre).
    Returns the counts at the final centres and the centres ``x``, ``y``.
    """
    pad = margin + 8
    map_width = width + 2 * pad
    # Orientation of each edge pixel; far outside any tolerance where there is no edge.
    orientation_map = np.full((height + 2 * pad) * map_width, np.nan, np.float32)
    orientation_map[(rows + pad) * map_width + cols + pad] = orientation_deg
    entry_orientation = template.orientation_deg[None, :, None]
    tolerance = np.float32(GHT_FOUND_ORIENTATION_BINS * template.orientation_step_deg)

    step = np.array([-1, 0, 1])
    window_dx, window_dy = np.tile(step, 3), np.repeat(step, 3)
    window_offset = window_dy * map_width + window_dx  # (9,)
    scaled_offsets = scale_values[peak_scale][:, None, None] * template.offsets[None]
    centre_x, centre_y = peak_x.astype(np.float64), peak_y.astype(np.float64)
    for iteration in range(4):  # three moves, then the final count
        predicted_x = centre_x[:, None] - scaled_offsets[..., 0]  # (peaks, entries)
        predicted_y = centre_y[:, None] - scaled_offsets[..., 1]
        nearest_x, nearest_y = np.rint(predicted_x), np.rint(predicted_y)
        look = ((nearest_y.astype(np.int64) + pad) * map_width
                + nearest_x.astype(np.int64) + pad)
        # |scale * offset| <= margin - 2 and each move is at most 1.5 px: predictions stay
        # in the padded map. The clip is only a guard against out-of-bounds indexing.
        np.clip(look, map_width + 1, orientation_map.size - map_width - 2, out=look)
        difference = np.abs(orientation_map[look[..., None] + window_offset] - entry_orientation)
        with np.errstate(invalid="ignore"):  # NaN (no edge pixel) compares False
            voted = (difference <= tolerance) | (difference >= 360 - tolerance)  # (p, e, 9)
        votes_of_entry = voted.sum(axis=2)  # (peaks, entries)
        if iteration == 3:
            break
        vote_count = np.maximum(votes_of_entry.sum(axis=1), 1)
        centre_x = centre_x + ((voted @ window_dx).sum(axis=1) + (
            votes_of_entry * (nearest_x - predicted_x)).sum(axis=1)) / vote_count
        centre_y = centre_y + ((voted @ window_dy).sum(axis=1) + (
            votes_of_entry * (nearest_y - predicted_y)).sum(axis=1)) / vote_count
    return np.count_nonzero(votes_of_entry, axis=1), centre_x, centre_y
