"""Door knob and peek window by the Generalized Hough Transform with one model (thesis Sec. 5.2.2).

The model (a :class:`Template`, the R-table of Ballard 1981) is every Sobel edge pixel
(:mod:`.edges`) of an example image cut out at frontal resolution; on frontal views one
fixed model serves every camera angle. Pixel coordinates and angles as in :mod:`.edges`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from .edges import (
    DEFAULT_EDGE_THRESHOLD,
    EdgeMap,
    bin_of_orientation,
    compatible_bins,
    edge_map,
    orientation_bin_count,
)

#: The high hysteresis threshold of :func:`~.edges.line_edges` with which ``gsrwt match`` finds
#: the edges of templates and views.
DEFAULT_MATCH_THRESHOLD = 25.0

#: ... and the Gaussian smoothing (sigma, pixels) of the gradient vector from which it takes
#: each edge pixel's orientation (``orientation_smoothing`` of :func:`~.edges.line_edges`):
#: on a faint edge the orientation of single pixels wanders by ten degrees and more, their
#: mean along the edge does not.
MATCH_ORIENTATION_SMOOTHING = 2.0

#: GHT R-table orientation bin width (degrees): wide enough that Sobel orientation noise on
#: anti-aliased curves rarely moves a pixel by more than one bin.
DEFAULT_GHT_ORIENTATION_STEP_DEG = 4.0

#: A model edge pixel is found where an image edge pixel's orientation is this many GHT bins
#: (6 degrees by default) or less away from its own.
GHT_FOUND_ORIENTATION_BINS = 1.5

#: At most this many accumulator peaks are considered, and this many (or ``4 * max_matches``
#: if more) distinct ones are verified, when matching a template.
_GHT_PEAK_CANDIDATES = 256
_GHT_MIN_VERIFIED = 20

#: Votes buffered per ``np.bincount`` call when filling the GHT accumulator (32 MB of int64).
_GHT_VOTE_CHUNK = 1 << 22



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


def build_template(
    image: np.ndarray,
    *,
    edge_threshold: float = DEFAULT_EDGE_THRESHOLD,
    orientation_step_deg: float = DEFAULT_GHT_ORIENTATION_STEP_DEG,
    edges: EdgeMap | None = None,
) -> Template:
    """The GHT model of a cut-out bounding box (e.g. 40x100 for a knob, 120x90 for a window).

    As in the thesis (Sec. 5.2.2) every edge pixel inside the box (:func:`edge_map`; the
    1-pixel rim of the cut-out is left out, its gradient would see beyond the box) is part of
    the model, the reference point is the box centre, and entries are indexed by gradient
    orientation in bins of ``orientation_step_deg``. ``edges``: the box's edge pixels from
    another edge stage (e.g. :func:`~.edges.line_edges`), instead of :func:`edge_map` with
    ``edge_threshold``. Raises :class:`ValueError` if the box has no edge pixels.
    """
    bin_count = orientation_bin_count(orientation_step_deg)
    if edges is None:
        edges = edge_map(image, edge_threshold)
    height, width = edges.mask.shape
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0:
        raise ValueError("the template has no edge pixels; nothing to match")
    orientation_bins = bin_of_orientation(edges.orientation_deg[rows, cols],
                                          orientation_step_deg, bin_count)
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
    edges: EdgeMap | None = None,
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

    ``edges``: the image's edge pixels from another edge stage (the template's should come
    from the same one), instead of :func:`edge_map` with ``edge_threshold``.
    """
    if orientation_tolerance_bins < 0:
        raise ValueError("orientation_tolerance_bins must not be negative")
    scale_values = np.asarray(list(scales), dtype=np.float64)
    if scale_values.size and not np.all(scale_values > 0):
        raise ValueError(f"scales must be positive, got {list(scales)}")
    if edges is None:
        edges = edge_map(image, edge_threshold)
    height, width = edges.mask.shape
    rows, cols = np.nonzero(edges.mask)
    if cols.size == 0 or scale_values.size == 0 or max_matches <= 0 or template.edge_count == 0:
        return []
    bin_count = template.bin_count
    image_bins = bin_of_orientation(edges.orientation_deg[rows, cols],
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
                                  compatible_bins(b, tolerance_bins, bin_count)])
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
