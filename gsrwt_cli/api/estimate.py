"""Pan, tilt and roll from the image's own straight lines (thesis future work 1).

>>> estimate = estimate_pose(image, Intrinsics(500, 500, width=640, height=480))  # doctest: +SKIP
>>> estimate.pose.pan, estimate.confidence  # doctest: +SKIP

Steps (no I/O, nothing printed; arrays in, degrees out):

1. straight segments by OpenCV's LSD (:func:`detect_segments`), their end points undistorted
   when the camera has a lens (never the image);
2. each segment's interpretation plane ``n = r1 x r2`` through its end rays;
3. the Manhattan frame (three orthogonal directions) by a minimal-sample search: two segments
   give a direction ``v1 = n1 x n2``, a third gives ``v2 = v1 x n3``, ``v3 = v1 x v2``; each
   hypothesis is scored by a truncated quadratic of the segments' end-point distances, then
   the best two distinct ones are refined by robust Gauss-Newton over their inliers and, if
   the segments do not prefer one by a standard error, the more upright is kept
   (:func:`fit_manhattan_frame`);
4. the pose's frame: each direction fitted again by its own segments alone, and the
   orthogonal frame nearest the three, each weighted by how well its segments pin it and by
   how far from square the scene is found to be (:func:`reconcile_directions`);
5. the vertical (the direction nearest the image's up), the wall (the horizontal nearest the
   optical axis, so ``|pan| <= 45``) and the pose by the decomposition of pan, tilt and roll;
6. refusals a user can act on (:func:`_refusal`), judged on the frame of step 3 as the
   confidence is (both were calibrated on it): no clear man-made structure (the frame
   explains the segments hardly better than random frames, :func:`structure_ratio`), no
   vertical structure (fewer segments meet in its vertical than a direction needs to be
   found, or they gather hardly more than along a random direction,
   :func:`vertical_ratio`), a focal length the view does not pin down
   (:func:`focal_uncertainty`); the direction receding from the camera taken as unseen where
   its segments meet in it no more than chance would (:func:`false_alarms`: clutter near a
   vanishing point inside the image, through a longer lens); and the confidence, the
   calibrated chance of being within 2 degrees (:func:`confidence_of`), from how nearly a
   different frame fits as well, how far the focal length's uncertainty turns the pose and how
   far the frame's own segments, each direction's alone, point from its vertical and wall
   normal (:func:`frame_misfit`; where no edge recedes, its horizontal), lower for a wall seen
   frontally (:data:`UNSEEN_NORMAL_LOGIT`), times the chance that the direction taken as the
   vertical is up at all (:func:`upright_probability`: a prior that photos are taken about
   upright).

Unknown focal length: the clusters' vanishing points do not depend on it; two finite
orthogonal ones ``p1, p2`` give ``f^2 = -(p1 - c).(p2 - c)``, polished by the segments,
then settled where the frame refitted across 1.4 times either way fits them best, and
refused where another that fits about as well turns the pose (:func:`settle_focal`); the
frame is fitted again with that focal length. An approximate one (EXIF's, ``focal_spread``) is
refined: the focal length the segments fit best near it and the one given, averaged by how
sure each is (:func:`_refined_focal`).

Frames: the thesis's camera frame (X up, Y right, Z forward); pixels ``(col, row)`` with
pixel centres at integers. docs/CONVENTIONS.md ("What the estimator reports") has it all in full.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from ..base.messages import shown_above, shown_below
from ..geometry.camera import Intrinsics, Pose
from ..geometry.rotations import PoseError, cross_matrix, cross_rows, pose_from_rotation
from ..vision.edges import grey8

#: Segments shorter than this fraction of the image's diagonal are left out (noise, texture).
MIN_SEGMENT_FRACTION = 0.02
#: Fewer segments than this: nothing can be told.
MIN_SEGMENTS = 8
#: A direction is "found" when at least this many segments (and this fraction of them) meet in it
#: and in no other direction of the frame (:func:`distinct_support`).
MIN_DIRECTION_SEGMENTS = 5
MIN_DIRECTION_FRACTION = 0.04
#: A segment counts towards finding its direction only if its line turns at least this far
#: from the line to each other direction's vanishing point (:func:`distinct_support`).
DISTINCT_DEGREES = 10.0
#: The direction receding from the camera is found only where its segments meet in it more
#: than chance would make them: at most this many false alarms expected
#: (:func:`false_alarms`, a-contrario).
MAX_FALSE_ALARMS = 1.0
#: End-point distance (pixels at 640x480) within which a segment belongs to a direction.
INLIER_PX = 1.5
#: The diagonal, in pixels, of the image size the distance above is set at (640x480): a
#: larger image has it scaled (:func:`inlier_distance`).
REFERENCE_DIAGONAL = 800.0
#: Scale of the Cauchy weights of the refinement, as a fraction of the inlier distance.
CAUCHY_FRACTION = 0.25
#: Hypotheses of the minimal-sample search, and the segments they are drawn from (the longest).
HYPOTHESES = 600
SAMPLED_SEGMENTS = 120
#: A hypothesis with an axis this many degrees from all of the frame's is a rival frame.
RIVAL_DEGREES = 5.0
#: The best distinct hypotheses refined and compared (:func:`_most_upright_of_the_best`); a
#: score less than this many standard errors (of :data:`BOOTSTRAPS` resamples) below the
#: best one's is a tie, broken by the vertical nearest the image's.
TOP_FRAMES = 2
TIE_SIGMAS = 1.0
BOOTSTRAPS = 200
#: Tied frames whose verticals are this close are told apart by their score, not uprightness.
SAME_VERTICAL_DEGREES = 1.0
#: Segments (the longest) that score the hypotheses; all of them are refined.
SCORED_SEGMENTS = 200
#: At most this many segments (the longest) are fitted.
MAX_SEGMENTS = 500
#: LSD's own Gaussian down-scaling (OpenCV's default 0.8): 0.6 finds the long edges in
#: half the time.
LSD_SCALE = 0.6
#: Images are searched for segments at most this many pixels on their long side.
MAX_DETECTION_SIDE = 1280
#: Focal lengths (multiples of the long side) at which an unknown camera's frame is searched
#: first, with fewer hypotheses each.
FOCAL_GRID = tuple(0.4 * 1.25**k for k in range(10))
GRID_HYPOTHESES = 300
#: Focal lengths an image may be found to have, as multiples of its diagonal.
FOCAL_RANGE = (0.2, 10.0)
#: Vanishing points further than this many diagonals from the principal point are
#: "at infinity" for the focal length formula.
FINITE_VP_DIAGONALS = 8.0
#: :func:`reconcile_directions`: a direction's own segments that point more than this many
#: degrees from the frame's axis have found other segments (a cluster of clutter), not a
#: scene a little out of square; the scene's skew is sought between 0 and this. (The
#: hand-labelled directions of the York Urban training photos, each fitted alone, meet at 90
#: degrees give or take 0.6 at the median, 2.0 at the 90th percentile, over 149 pairs.)
MAX_SKEW_DEGREES = 3.0
#: :func:`reconcile_directions` trusts no direction closer than this variance (radians
#: squared: 0.001 degrees), so that segments with no noise at all (made, not photographed)
#: weigh finitely.
MIN_DIRECTION_VARIANCE = math.radians(0.001) ** 2
#: The skews :func:`reconcile_directions` weighs, in degrees: none, and 0.05 to
#: :data:`MAX_SKEW_DEGREES` in equal ratios.
SKEW_GRID_DEGREES = np.concatenate([[0.0], np.geomspace(0.05, MAX_SKEW_DEGREES, 36)])
#: Weights of :func:`confidence_of` (intercept, rival, focal degrees, misfit degrees), fitted
#: by ``benchmarks/calibrate_confidence.py`` on the York Urban training photos.
CONFIDENCE_WEIGHTS = (8.855, -7.212, -0.484, -0.807)
#: How far a camera's up is taken to be from the world's up: the standard deviation, in
#: degrees, of the angle between them (tilt and roll together) in the prior of
#: :func:`upright_probability`. Lines cannot tell which of a frame's three directions is up;
#: the one nearest the camera's up is taken, and it is the world's up as surely as the camera
#: is about upright. Robots and photographers hold cameras about upright (the York Urban
#: photos within 20 degrees, a facade shot from below 38): a broad prior, set from the photos
#: the tool is for, not fitted to any.
UPRIGHT_SPREAD_DEGREES = 25.0
#: Added to :func:`confidence_of`'s logit where the frontal wall's normal has no edges of
#: its own (a wall seen about frontally, its pan pinned by its horizontals' slight convergence
#: alone): such views are within 2 degrees less often than the three measures say. Fitted on
#: views made from the York Urban training photos by leaving out their receding edges
#: (``benchmarks/calibrate_confidence.py --frontal``): -0.46 over all 45, -0.40 and -0.50
#: over either half; the mean confidence of those accepted, 0.80 against 0.73 within 2
#: degrees, becomes 0.74 against 0.76.
UNSEEN_NORMAL_LOGIT = -0.46
#: ``gsrwt estimate`` and ``rectify --auto`` refuse estimates less confident than this: more
#: likely more than 2 degrees off than not.
DEFAULT_MIN_CONFIDENCE = 0.5
#: The null model of :func:`structure_ratio`: this many random orthogonal frames (seeded).
RANDOM_FRAMES = 128
#: A frame must explain this many times the segment length a random frame does (median),
#: else the image has no man-made structure to tell a pose by (:func:`structure_ratio`).
MIN_STRUCTURE_RATIO = 4.5
#: The frame's vertical must gather this many times the segment length a random direction
#: does (median), else the photo shows no vertical edges and its "vertical" is a guess
#: (:func:`vertical_ratio`). Set in the gap, on a log scale, between man-made scenes (5.4 at
#: the least of the York Urban training photos) and photos with straight edges but none
#: vertical (0.3 to 0.7: a lake at dusk with boats, an orange, given a focal length).
MIN_VERTICAL_RATIO = 2.0
#: With a focal length longer than this many times the image's long side, the frame's
#: structure is judged at this focal length too, and the lower ratio counts
#: (:func:`_structure_of`): the null model weakens as the focal length grows (every segment's
#: interpretation plane nearly holds the optical axis, so random frames explain ever less and
#: any two orientations in the image pass for structure: a painting and a butterfly passed at
#: 2.5). The York Urban photos, on which :data:`MIN_STRUCTURE_RATIO` was set, are at 1.05.
STRUCTURE_FOCAL_CAP = 1.25
#: The Laplace approximation of an estimated focal length's spread (:func:`focal_uncertainty`)
#: treats the segments as independent; on the York Urban training photos whose frame is right
#: (vertical within 2 degrees; a wrong frame is the confidence's ``rival`` part) the focal
#: lengths are this many times further off than it says (median of |log error| / sigma, over
#: the 0.674 of a normal distribution), so it is scaled by it.
FOCAL_SIGMA_SCALE = 2.9
#: An estimated focal length is refused when moving it by one standard deviation turns the
#: vertical or the wall by more than this many degrees (a pose this far off is wrong), or
#: when focal lengths further off that fit about as well do (:func:`settle_focal`).
MAX_FOCAL_DEGREES = 3.0
#: :func:`settle_focal` looks this many times the estimate either way (as far as
#: :func:`polish_focal` searches).
FOCAL_SEARCH_SPAN = 1.4

#: How far, as a fraction (a standard deviation of the log), an EXIF focal length may be off
#: the photo's: the millimetres are rounded, the sensor's size (or the 35 mm equivalent) is
#: nominal, and focusing moves the lens (the York Urban photos' EXIF is 4 % short of their
#: calibration). ``estimate_pose(..., focal_spread=...)`` weighs it against what the segments
#: say (:func:`_refined_focal`); 0.05 and 0.1 gave the same York results.
EXIF_FOCAL_SPREAD = 0.05

#: Which vertical plane is the wall (:func:`world_from_camera_of`).
WALL_CHOICES = ("frontal", "dominant")

#: Names of the three directions, in the order of :attr:`PoseEstimate.vanishing_points`.
DIRECTION_NAMES = ("vertical", "wall", "normal")

def remedy(focal_estimated: bool = False, guides: bool = True) -> str:
    """How a refusal ends: what would settle the pose (the focal length first where it was
    estimated, whose uncertainty is then one of the reasons; guides where the input takes
    them: a photo does, a video's frames do not,
    :func:`gsrwt_cli.batch.estimate_jobs.without_guides`)."""
    if guides:
        return f"give {'the focal length, ' if focal_estimated else ''}the pose, or guides " \
               f"(--verticals)"
    return f"give {'the focal length or ' if focal_estimated else ''}the pose"


@dataclass(frozen=True)
class PoseEstimate:
    """What :func:`estimate_pose` found in one image.

    ``pose``: the :class:`~gsrwt_cli.geometry.camera.Pose` (None when ``error`` says why not);
    ``focal``: the focal length in pixels used (given, or estimated when
    ``focal_estimated``); ``confidence``: the chance, 0 to 1, that the pose is within 2 degrees
    (:func:`confidence_of`); ``segments``:
    straight segments fitted; ``inliers``: those that meet in one of the three directions;
    ``directions``: how many of the three directions were found, each through segments no
    other explains (:func:`distinct_support`);
    ``vanishing_points``: ``(col, row)`` in ideal (undistorted) pixels of the vertical, the
    wall's horizontal and the wall's normal, None where at infinity; ``world_from_camera``:
    the rotation (rows: up, wall-right, into-wall in the camera frame); ``lines``: ``(N, 4)``
    segment end points ``col1, row1, col2, row2`` as detected; ``labels``: ``(N,)`` the
    direction of each (0, 1, 2 as in :data:`DIRECTION_NAMES`, -1 for none); ``structure``: how
    many times better than random frames the frame explains the segments
    (:func:`structure_ratio`); ``focal_uncertainty``: an estimated focal length's
    (:class:`FocalUncertainty`, None when given); ``rival``: :attr:`ManhattanFrame.rival`;
    ``misfit``: degrees between the frame's vertical or frontal wall's normal (whichever
    ``wall`` is reported; the wall's horizontal where no edge recedes) and the direction its
    own segments alone meet in (:func:`frame_misfit`); ``upright``: the probability that the
    frame's direction taken as the vertical is the world's up (:func:`upright_probability`);
    ``normal_seen``: whether the frontal wall's normal has edges of its own (not: a wall seen
    frontally, :data:`UNSEEN_NORMAL_LOGIT`).
    """

    pose: Pose | None
    focal: float | None
    focal_estimated: bool
    confidence: float
    segments: int
    inliers: int
    directions: int
    vanishing_points: tuple[tuple[float, float] | None, ...] = (None, None, None)
    world_from_camera: np.ndarray | None = field(default=None, repr=False)
    lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False)
    labels: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int), repr=False)
    error: str | None = None
    structure: float = 0.0
    focal_uncertainty: FocalUncertainty | None = None
    rival: float = 0.0
    misfit: float = 0.0
    upright: float = 1.0
    normal_seen: bool = True

    @property
    def ok(self) -> bool:
        return self.error is None


class EstimateError(ValueError):
    """The image cannot tell its pose (``estimate_pose`` returns these as ``error``)."""


# --------------------------------------------------------------------------------------------
# Segments and their interpretation planes
# --------------------------------------------------------------------------------------------


def detect_segments(image: np.ndarray, min_length: float | None = None) -> np.ndarray:
    """Straight segments by OpenCV's LSD: ``(N, 4)`` ``col1, row1, col2, row2``, longest first.

    Large images are searched at most :data:`MAX_DETECTION_SIDE` pixels on their long side
    (coordinates given back in the image's pixels). Segments shorter than ``min_length``
    (default :data:`MIN_SEGMENT_FRACTION` of the diagonal) are left out; at most
    :data:`MAX_SEGMENTS` are kept.
    """
    grey = grey8(np.asarray(image))
    height, width = grey.shape
    if min_length is None:
        min_length = max(8.0, MIN_SEGMENT_FRACTION * math.hypot(width, height))
    factor = min(1.0, MAX_DETECTION_SIDE / max(width, height))
    small = grey if factor == 1.0 else cv2.resize(
        grey, (max(1, round(width * factor)), max(1, round(height * factor))),
        interpolation=cv2.INTER_AREA)
    detector = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD, LSD_SCALE)
    found = detector.detect(small)[0]
    if found is None:
        return np.zeros((0, 4))
    lines = found.reshape(-1, 4).astype(np.float64)
    if factor != 1.0:
        sx, sy = width / small.shape[1], height / small.shape[0]
        lines = (lines + 0.5) * np.array([sx, sy, sx, sy]) - 0.5
    lengths = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    order = np.argsort(-lengths, kind="stable")
    order = order[lengths[order] >= min_length][:MAX_SEGMENTS]
    return lines[order]


def inlier_distance(width: int, height: int) -> float:
    """The end-point distance in pixels within which a segment of a ``width`` x ``height``
    image belongs to a direction: :data:`INLIER_PX` up to 640x480, in proportion to the
    diagonal above, so that a segment of the same share of a larger image is judged at the
    same angle. Not below: LSD's end points are no more precise in pixels in a smaller
    image, and a tighter distance there let a butterfly's wings pass for structure (on the
    York Urban photos shrunk to 320x240, 29 of 51 are refused as having no clear structure;
    docs/REAL_PHOTOS.md)."""
    return INLIER_PX * max(1.0, math.hypot(width, height) / REFERENCE_DIAGONAL)


def _usable_segments(lines: np.ndarray) -> np.ndarray:
    """Segments given as ``(N, 4)`` ``col1, row1, col2, row2``, those of no length or with a
    coordinate that is not finite left out: they have no direction (LSD gives none such)."""
    lines = np.asarray(lines, dtype=np.float64)
    if lines.ndim != 2 or lines.shape[1] != 4:
        raise ValueError(f"segments must be an (N, 4) array, got shape {lines.shape}")
    length = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    return lines[np.all(np.isfinite(lines), axis=1) & (length > 0)]


def interpretation_planes(
    lines: np.ndarray, camera_from_pixel: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals ``(N, 3)`` of the segments' interpretation planes
    (``n = r1 x r2``) and their half lengths ``(N,)`` in pixels.

    ``camera_from_pixel``: homogeneous ideal pixel ``(col, row, 1)`` to a ray in the thesis's
    camera frame (X up, Y right, Z forward).
    """
    ones = np.ones((len(lines), 1))
    r1 = np.hstack([lines[:, :2], ones]) @ camera_from_pixel.T
    r2 = np.hstack([lines[:, 2:], ones]) @ camera_from_pixel.T
    normals = cross_rows(r1, r2)
    norms = np.linalg.norm(normals, axis=1, keepdims=True)
    half = 0.5 * np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    return normals / np.where(norms > 0, norms, 1.0), half


# --------------------------------------------------------------------------------------------
# The Manhattan frame
# --------------------------------------------------------------------------------------------


def _unit(vectors: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors / np.where(norms > 0, norms, 1.0)


def _least_of_three(distance: np.ndarray) -> np.ndarray:
    """``distance.min(axis=-1)`` of an array whose last axis holds three values (the three
    directions), element-wise: numpy reduces a length-3 axis several times slower."""
    return np.minimum(np.minimum(distance[..., 0], distance[..., 1]), distance[..., 2])


def _nearest_of_three(distance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(distance.argmin(axis=1), distance.min(axis=1))`` of an ``(N, 3)`` array, the first
    index among equals, as :func:`_least_of_three`."""
    least = _least_of_three(distance)
    index = np.where(distance[:, 0] == least, 0, np.where(distance[:, 1] == least, 1, 2))
    return index, least


def _outer_products(normals: np.ndarray) -> np.ndarray:
    """Each plane normal's ``n n^T``, flattened: ``(N, 9)``; a weighted sum over segments,
    ``sum w n n^T``, is then one product ``w @ outer``."""
    return (normals[:, :, None] * normals[:, None, :]).reshape(len(normals), 9)


def _rodrigues(omega: np.ndarray) -> np.ndarray:
    return cv2.Rodrigues(np.asarray(omega, dtype=np.float64).reshape(3, 1))[0]


@dataclass(frozen=True)
class ManhattanFrame:
    """Three orthonormal directions (the columns of ``directions``, camera frame) and the
    segments that meet in each (``labels``: 0, 1, 2, or -1). ``rival``: the best score of the
    hypotheses with an axis more than :data:`RIVAL_DEGREES` from all of the best
    hypothesis's, over its score (near 1: another frame explains the segments about as well).
    """

    directions: np.ndarray
    labels: np.ndarray
    score: float
    rival: float = 0.0

    def support(self) -> np.ndarray:
        return np.bincount(self.labels[self.labels >= 0], minlength=3)


def fit_manhattan_frame(
    normals: np.ndarray, half_lengths: np.ndarray, inlier_px: float = INLIER_PX,
    hypotheses: int = HYPOTHESES, seed: int = 0, upright: bool = True,
) -> ManhattanFrame:
    """The three orthogonal directions that most segments meet in (a Manhattan frame).

    Convention
    ----------
    ``normals``: ``(N, 3)`` unit interpretation-plane normals, longest segments first;
    ``half_lengths``: ``(N,)`` pixels. A segment meets direction ``v`` when its end points lie
    within ``inlier_px`` of the line through its midpoint and ``v``'s vanishing point,
    approximately ``half_length * |n.v| < inlier_px``.

    The search draws ``hypotheses`` minimal samples (seeded: the same image gives the same
    answer): ``v1 = n_i x n_j``, ``v2 = v1 x n_k``, ``v3 = v1 x v2``, scores each by
    ``sum(length * max(0, 1 - (d / inlier_px)^2))`` over the segments' best direction, then
    refines the best rotation by Gauss-Newton with Cauchy weights over the inliers,
    re-assigning them as it goes. With ``upright``, the best few distinct hypotheses are
    refined and, of those the segments do not significantly prefer one to another, the most
    upright is chosen (:func:`_most_upright_of_the_best`).
    """
    count = len(normals)
    rng = np.random.default_rng(seed)
    pool = min(count, SAMPLED_SEGMENTS)
    pooled = float(half_lengths[:pool].sum())
    if not pooled > 0:  # no segment of any length (all beyond a lens's fold, say)
        return ManhattanFrame(np.eye(3), -np.ones(count, dtype=int), 0.0)
    weights = half_lengths[:pool] / pooled
    picks = rng.choice(pool, size=(hypotheses, 3), p=weights)
    v1 = _unit(cross_rows(normals[picks[:, 0]], normals[picks[:, 1]]))
    v2 = _unit(cross_rows(v1, normals[picks[:, 2]]))
    v3 = cross_rows(v1, v2)
    good = (np.linalg.norm(v2, axis=1) > 0.5) & (picks[:, 0] != picks[:, 1])
    candidates = np.stack([v1, v2, v3], axis=2)[good]  # (H, 3, 3): columns are directions
    if len(candidates) == 0:
        return ManhattanFrame(np.eye(3), -np.ones(count, dtype=int), 0.0)
    scores = _scores(normals, half_lengths, candidates, inlier_px)
    best = candidates[int(np.argmax(scores))]
    # each candidate's axis furthest from all of the best one's, as the cosine of the angle
    nearest = np.abs(np.einsum("ji,hjk->hik", best, candidates)).max(axis=2).min(axis=1)
    other = nearest < math.cos(math.radians(RIVAL_DEGREES))
    rival = float(scores[other].max() / scores.max()) if other.any() and scores.max() > 0 else 0.0
    if upright:
        directions = _most_upright_of_the_best(normals, half_lengths, candidates, scores,
                                               inlier_px)
    else:
        directions = _refine(normals, half_lengths, best, inlier_px)
    labels, score = _labels(normals, half_lengths, directions, inlier_px)
    return ManhattanFrame(directions, labels, score, rival)


def _distinct_best(candidates: np.ndarray, scores: np.ndarray, count: int) -> list[int]:
    """Indices of the best-scoring ``count`` candidates each with an axis more than
    :data:`RIVAL_DEGREES` from all the axes of every better one (among the best 200)."""
    order = np.argsort(-scores, kind="stable")[:200]
    limit = math.cos(math.radians(RIVAL_DEGREES))
    open_ = np.ones(len(order), dtype=bool)
    chosen: list[int] = []
    while open_.any() and len(chosen) < count:
        first = order[int(np.argmax(open_))]
        chosen.append(int(first))
        nearest = np.abs(np.einsum("ji,hjk->hik", candidates[first], candidates[order]))
        open_ &= nearest.max(axis=2).min(axis=1) < limit
    return chosen


_BOOTSTRAP_WEIGHTS = np.random.default_rng(0).poisson(
    1.0, (BOOTSTRAPS, MAX_SEGMENTS)).astype(np.float32)


def _most_upright_of_the_best(normals: np.ndarray, half: np.ndarray, candidates: np.ndarray,
                              scores: np.ndarray, inlier_px: float) -> np.ndarray:
    """The frame chosen among the best distinct hypotheses (:data:`TOP_FRAMES`), each refined:
    of those whose score is not significantly below the best one's (by less than
    :data:`TIE_SIGMAS` standard errors of the difference, from :data:`BOOTSTRAPS` Poisson
    bootstrap resamples of the segments), the one whose vertical is nearest the image's
    vertical (the one-standard-error rule of model selection, with "most upright" for
    "simplest"). A photo is usually taken about level: when clutter (branches, kerbs) offers a
    frame about as good as the building's, the more upright is the building's; a frame the
    segments clearly prefer wins however tilted."""
    frames = [_refine(normals, half, candidates[k], inlier_px)
              for k in _distinct_best(candidates, scores, TOP_FRAMES)]
    if len(frames) == 1:
        return frames[0]
    distance = np.abs(np.einsum("ij,kjl->kil", normals, np.stack(frames)))  # (K, N, 3)
    distance = _least_of_three(distance) * (half / inlier_px)
    share = half * np.maximum(0.0, 1.0 - distance**2)  # (K, N): each segment's score
    totals = share.sum(axis=1)
    best = int(np.argmax(totals))
    weights = (_BOOTSTRAP_WEIGHTS if len(half) <= MAX_SEGMENTS else np.random.default_rng(0)
               .poisson(1.0, (BOOTSTRAPS, len(half))).astype(np.float32))
    resampled = weights[:, :len(half)] @ share.T.astype(np.float32)
    difference = resampled[:, best:best + 1] - resampled  # (B, K)
    error = difference.std(axis=0)
    tied = totals[best] - totals <= TIE_SIGMAS * error
    verticals = np.stack([frame[:, np.argmax(np.abs(frame[0]))] for frame in frames])
    most_upright = int(np.argmax(np.where(tied, np.abs(verticals[:, 0]), -1.0)))
    # of the tied frames with (about) that vertical, the first (the best hypothesis)
    same = tied & (np.abs(verticals @ verticals[most_upright])
                   > math.cos(math.radians(SAME_VERTICAL_DEGREES)))
    return frames[int(np.argmax(same))]


def _scores(normals: np.ndarray, half: np.ndarray, candidates: np.ndarray,
            inlier_px: float) -> np.ndarray:
    """Truncated-quadratic score of each candidate frame ``(H, 3, 3)`` over the longest
    :data:`SCORED_SEGMENTS` segments (float32: a ranking, refined in float64 after)."""
    count = min(len(normals), SCORED_SEGMENTS)
    scaled = (normals[:count] * (half[:count, None] / inlier_px)).astype(np.float32)
    weight = half[:count].astype(np.float32)
    scores = np.zeros(len(candidates))
    for start in range(0, len(candidates), 500):  # bounded memory: N x 500 x 3 at a time
        block = candidates[start:start + 500].astype(np.float32)
        flat = block.transpose(1, 0, 2).reshape(3, -1)  # (3, h*3)
        distance = _least_of_three(np.abs(scaled @ flat).reshape(count, len(block), 3))
        np.square(distance, out=distance)
        np.subtract(1.0, distance, out=distance)
        np.maximum(distance, 0.0, out=distance)
        scores[start:start + 500] = weight @ distance
    return scores


def _labels(normals: np.ndarray, half: np.ndarray, directions: np.ndarray,
            inlier_px: float) -> tuple[np.ndarray, float]:
    distance = np.abs(normals @ directions) * half[:, None] / inlier_px
    labels, nearest = _nearest_of_three(distance)
    score = float((half * np.maximum(0.0, 1.0 - nearest**2)).sum())
    return np.where(nearest < 1.0, labels, -1), score


def _random_frames(count: int, seed: int = 0) -> np.ndarray:
    """``count`` rotations ``(count, 3, 3)`` uniform over SO(3) (unit quaternions from a
    seeded normal distribution)."""
    q = _unit(np.random.default_rng(seed).normal(size=(count, 4)))
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1),
    ], axis=1)


_NULL_FRAMES = _random_frames(RANDOM_FRAMES)
#: The null frames' axes as directions ``(3 * RANDOM_FRAMES, 3)``, for :func:`vertical_ratio`.
_NULL_DIRECTIONS = _NULL_FRAMES.transpose(0, 2, 1).reshape(-1, 3)


def structure_ratio(normals: np.ndarray, half: np.ndarray, directions: np.ndarray,
                    inlier_px: float) -> float:
    """How much better the frame ``directions`` explains the segments than chance: its score
    (:func:`_scores`) over the median score of :data:`RANDOM_FRAMES` random orthogonal frames.

    A null model: any three orthogonal directions catch some segments, the more the shorter
    and more numerous they are (fur, leaves, gravel, fruit give hundreds of short, curved
    pieces). A man-made scene's frame catches its long straight edges: 4.4 to 18 times a random
    frame's share on the York Urban training photos; photos with no such structure 1.4 to 3.8.
    """
    frames = np.concatenate([directions[None], _NULL_FRAMES])
    scores = _scores(normals, half, frames, inlier_px)
    return float(scores[0] / max(np.median(scores[1:]), 1e-12))


def _structure_of(ideal: np.ndarray, camera: Intrinsics, normals: np.ndarray, half: np.ndarray,
                  directions: np.ndarray, inlier_px: float) -> float:
    """:func:`structure_ratio` of the frame ``directions`` found with ``camera``, and, when its
    focal length exceeds :data:`STRUCTURE_FOCAL_CAP` long sides, the lower of that and the
    ratio of a frame found at the cap (the segments ``ideal`` re-seen through it)."""
    structure = structure_ratio(normals, half, directions, inlier_px)
    side = float(max(camera.width or 0, camera.height or 0))
    if side and camera.focal > STRUCTURE_FOCAL_CAP * side:
        capped = STRUCTURE_FOCAL_CAP * side
        planes = interpretation_planes(ideal, _camera_from_pixel(
            Intrinsics(capped, capped, camera.cx, camera.cy)))
        frame = fit_manhattan_frame(*planes, inlier_px)
        structure = min(structure, structure_ratio(*planes, frame.directions, inlier_px))
    return structure


def vertical_ratio(normals: np.ndarray, half: np.ndarray, vertical: np.ndarray,
                   inlier_px: float) -> float:
    """How much better the segments support the frame's ``vertical`` (a unit direction in the
    camera frame) than chance: its truncated-quadratic score alone (as :func:`_scores`, over the
    same longest segments) over the median score of the null frames' axes, each alone.

    :func:`structure_ratio` judges the frame as a whole, and with a focal length given a photo
    whose straight edges run in one or two horizontal directions only (a lake's shore and its
    boats, the rim of a fruit) can pass it; its frame's vertical is then whatever direction
    completes the frame, caught by no edge. A pose needs its vertical seen."""
    count = min(len(normals), SCORED_SEGMENTS)
    scaled = normals[:count] * (half[:count, None] / inlier_px)
    directions = np.vstack([vertical, _NULL_DIRECTIONS])
    scores = half[:count] @ np.maximum(0.0, 1.0 - (scaled @ directions.T) ** 2)
    return float(scores[0] / max(np.median(scores[1:]), 1e-12))


def _refine(normals: np.ndarray, half: np.ndarray, directions: np.ndarray,
            inlier_px: float, iterations: int = 8,
            fixed_labels: np.ndarray | None = None) -> np.ndarray:
    """Gauss-Newton on the rotation: residual ``half * n.v_k`` (about the end-point distance
    in pixels) of each inlier, Cauchy-weighted, the rotation updated as ``exp([w]x) R``.
    Inliers are re-assigned each iteration, unless ``fixed_labels`` gives them.

    The residual's derivative is ``s (v x n)``, so the normal equations gather per direction:
    ``J^T W J = sum_k [v_k]x M_k [v_k]x^T`` and ``J^T W r = sum_k [v_k]x M_k v_k`` with
    ``M_k = sum c s^2 n n^T`` over direction ``k``'s inliers (``c`` Cauchy weights), each
    ``M_k`` one product of the weights with the segments' outer products ``n n^T``."""
    left, _, right = np.linalg.svd(directions)
    directions = left @ right
    outer = _outer_products(normals)
    squared = half**2
    if fixed_labels is not None:
        labels, inliers = np.maximum(fixed_labels, 0), fixed_labels >= 0
        if inliers.sum() < 3:
            return directions
    for iteration in range(iterations):
        distance = np.abs(normals @ directions) * half[:, None]
        if fixed_labels is None:
            gate = inlier_px * (2.0 if iteration < 2 else 1.0)
            labels, nearest = _nearest_of_three(distance)
            inliers = nearest < gate
            if inliers.sum() < 3:
                break
        else:
            nearest = distance[np.arange(len(labels)), labels]
        weight = np.where(inliers, squared / (1.0 + (nearest / (CAUCHY_FRACTION * inlier_px))
                                                 ** 2), 0.0)
        by_direction = (labels[:, None] == np.arange(3)) * weight[:, None]  # (N, 3)
        moments = (by_direction.T @ outer).reshape(3, 3, 3)  # M_k
        turns = cross_matrix(directions.T)  # [v_k]x, (3, 3, 3)
        normal_matrix = (turns @ moments @ turns.transpose(0, 2, 1)).sum(axis=0)
        gradient = (turns @ (moments @ directions.T[:, :, None])).sum(axis=0)[:, 0]
        damping = 1e-6 * np.trace(normal_matrix) + 1e-12
        step = np.linalg.solve(normal_matrix + damping * np.eye(3), -gradient)
        directions = _rodrigues(step) @ directions
        if np.linalg.norm(step) < 1e-9:
            break
    return directions


def reconcile_directions(normals: np.ndarray, half: np.ndarray, directions: np.ndarray,
                         inlier_px: float, iterations: int = 3) -> np.ndarray:
    """The orthogonal frame nearest the three directions each fitted by its own segments alone,
    each trusted as far as its segments pin it down and the scene is square (thesis future
    work 1: the pose from the image's lines).

    :func:`_refine` fits the three directions together, so where the scene's directions are
    not quite orthogonal as seen (walls a little out of square, edges off plumb, a camera
    model a little off) the direction with the most and longest segments wins and drags the
    others: the vertical turned by the wall's horizontals. The truth of the York Urban photos
    is made the other way (docs/REAL_PHOTOS.md): each direction fitted alone, then
    orthogonalised. Here:

    1. each direction ``v_k`` is fitted alone, the eigenvector of least eigenvalue of
       ``M_k = sum c s^2 n n^T`` over the segments nearest it within twice ``inlier_px``
       (``s`` half lengths, ``n`` plane normals, ``c`` Cauchy weights of the end-point
       distance ``s |n.v_k|``, :data:`CAUCHY_FRACTION`), the segments re-selected
       ``iterations`` times; one that leaves the frame's axis by more than
       :data:`MAX_SKEW_DEGREES`, or has fewer than :data:`MIN_DIRECTION_SEGMENTS` segments,
       is left out;
    2. its variance across ``v_k``, along each of ``M_k``'s other eigenvectors, is that of a
       least-squares direction, ``sigma_k^2 / lambda`` (``sigma_k^2`` the weighted mean squared
       end-point distance): pinned across a direction whose segments run through one part of
       the image, loose along it;
    3. the scene's skew ``tau`` (one angle for the photo, each direction's own departure from
       square, :data:`SKEW_GRID_DEGREES`) and the rotation ``R`` are found together by maximum
       likelihood: ``R`` minimises ``sum d^T (C + tau^2)^-1 d`` (``d``: ``R e_k - v_k`` across
       ``v_k``) by Gauss-Newton from ``directions``, ``tau`` the best of the grid given the
       misses ``d``, four times over. Where the directions meet at 90 degrees within their
       noise (a render) ``tau`` is 0 and the segments share the frame by how well they pin
       it, as :func:`_refine`; where well-pinned directions disagree, ``tau`` grows and the
       directions share the difference more evenly, as the truth does.
    """
    fitted = directions.copy()
    gate = 2.0 * inlier_px
    alone: list[_Alone] = []
    outer = _outer_products(normals)
    for iteration in range(iterations + 1):
        distance = np.abs(normals @ fitted) * half[:, None]
        nearest, residual = _nearest_of_three(distance)
        own = (nearest[:, None] == np.arange(3)) & (residual < gate)[:, None]  # (N, 3)
        cauchy = 1.0 / (1.0 + (residual / (CAUCHY_FRACTION * inlier_px)) ** 2)
        # each direction's sum c s^2 n n^T, and its eigenvectors, all three at once
        all_values, all_vectors = np.linalg.eigh(
            ((own * (cauchy * half**2)[:, None]).T @ outer).reshape(3, 3, 3))
        counts = own.sum(axis=0)
        for k in range(3):
            values, vectors = all_values[k], all_vectors[k]
            if counts[k] < MIN_DIRECTION_SEGMENTS:
                fitted[:, k] = directions[:, k]
                continue
            if abs(vectors[:, 0] @ directions[:, k]) < math.cos(math.radians(MAX_SKEW_DEGREES)):
                fitted[:, k] = directions[:, k]  # it found other segments, not a skew
                continue
            fitted[:, k] = vectors[:, 0] * np.sign(vectors[:, 0] @ fitted[:, k] or 1.0)
            if iteration == iterations:  # the last pass weighs the directions it settled on
                c = cauchy[own[:, k]]
                spread = (c @ residual[own[:, k]] ** 2) / max(c.sum() - 2.0, 1.0)
                alone.append(_Alone(k, fitted[:, k].copy(), vectors[:, 1:].T, np.maximum(
                    spread / np.maximum(values[1:], 1e-12), MIN_DIRECTION_VARIANCE)))
    if len(alone) < 2:
        return directions
    skew_variances = np.radians(SKEW_GRID_DEGREES) ** 2
    rotation, skew_variance = directions.copy(), 0.0
    noise = np.concatenate([a.variances for a in alone])
    total = noise[None, :] + skew_variances[:, None]
    for _ in range(4):
        rotation = _nearest_rotation(rotation, alone, skew_variance)
        misses = np.concatenate([a.across @ (a.axis_of(rotation) - a.direction)
                                 for a in alone])
        likeliest = float(skew_variances[
            np.argmin((misses**2 / total + np.log(total)).sum(axis=1))])
        if likeliest == skew_variance:
            return rotation
        skew_variance = likeliest
    return _nearest_rotation(rotation, alone, skew_variance)


@dataclass(frozen=True)
class _Alone:
    """A direction fitted by its own segments (:func:`reconcile_directions`): the frame's
    column ``column``, the ``direction`` found, the two unit vectors ``across`` it (rows) and
    its least-squares ``variances`` along them (radians squared)."""

    column: int
    direction: np.ndarray
    across: np.ndarray
    variances: np.ndarray

    def axis_of(self, rotation: np.ndarray) -> np.ndarray:
        """The rotation's column for this direction, turned to point the same way."""
        axis = rotation[:, self.column]
        return axis * np.sign(axis @ self.direction or 1.0)


def _nearest_rotation(rotation: np.ndarray, alone: list[_Alone],
                      skew_variance: float) -> np.ndarray:
    """Gauss-Newton from ``rotation`` (``exp([w]x) R``) on ``sum d^T (C + tau^2)^-1 d``, ``d``
    each direction's miss across itself (:func:`reconcile_directions`)."""
    for _ in range(3):
        normal_matrix, gradient = np.zeros((3, 3)), np.zeros(3)
        for a in alone:
            d = a.axis_of(rotation)
            residual = a.across @ (d - a.direction)
            jacobian = -a.across @ cross_matrix(d)  # d(w x d)/dw = -[d]x
            weighted = jacobian.T / (a.variances + skew_variance)
            normal_matrix += weighted @ jacobian
            gradient += weighted @ residual
        step = np.linalg.solve(normal_matrix + 1e-9 * np.trace(normal_matrix) * np.eye(3),
                               -gradient)
        rotation = _rodrigues(step) @ rotation
        if np.linalg.norm(step) < 1e-9:
            break
    return rotation


def _image_cost(lines: np.ndarray, pixel_from_camera: np.ndarray, directions: np.ndarray,
                labels: np.ndarray, inlier_px: float) -> float:
    """Cauchy cost of the segments of ``labels``: the distance in pixels of each segment's end
    point from the line through its midpoint and its direction's vanishing point."""
    inliers = labels >= 0
    segments = lines[inliers]
    points = (pixel_from_camera @ directions[:, labels[inliers]]).T  # homogeneous VPs
    mid = np.column_stack([(segments[:, :2] + segments[:, 2:]) / 2, np.ones(len(segments))])
    through = cross_rows(mid, points)
    through /= np.maximum(np.hypot(through[:, 0], through[:, 1]), 1e-300)[:, None]
    distance = np.abs(through[:, 0] * segments[:, 0] + through[:, 1] * segments[:, 1]
                      + through[:, 2])
    return float(np.log1p((distance / (CAUCHY_FRACTION * inlier_px)) ** 2).sum())


def _vanishing_line_distances(lines: np.ndarray, pixel_from_camera: np.ndarray,
                              directions: np.ndarray) -> np.ndarray:
    """``(N, 3)``: each segment's end-point distance, in pixels, from the line through its
    midpoint and each direction's vanishing point (whatever the focal length)."""
    points = pixel_from_camera @ directions  # (3, 3): the homogeneous VPs, as columns
    mid = np.column_stack([(lines[:, :2] + lines[:, 2:]) / 2, np.ones(len(lines))])
    distances = np.empty((len(lines), 3))
    for k in range(3):
        through = cross_rows(mid, points[:, k])
        through /= np.maximum(np.hypot(through[:, 0], through[:, 1]), 1e-300)[:, None]
        distances[:, k] = np.abs(through[:, 0] * lines[:, 0] + through[:, 1] * lines[:, 1]
                                 + through[:, 2])
    return distances


def image_score(lines: np.ndarray, pixel_from_camera: np.ndarray, directions: np.ndarray,
                inlier_px: float) -> float:
    """The frame's score measured in the image, comparable between focal lengths:
    ``sum(length * max(0, 1 - (d / inlier_px)^2))`` with ``d`` each segment's end-point
    distance from the line through its midpoint and the nearest of the three vanishing
    points (:func:`_vanishing_line_distances`)."""
    best = _vanishing_line_distances(lines, pixel_from_camera, directions).min(axis=1)
    lengths = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    return float((lengths * np.maximum(0.0, 1.0 - (best / inlier_px) ** 2)).sum())


def _truncated_cost(lines: np.ndarray, pixel_from_camera: np.ndarray, directions: np.ndarray,
                    inlier_px: float) -> float:
    """The Cauchy cost of :func:`_image_cost` over every segment, each given to its nearest
    direction and costing at most what one at ``inlier_px`` does (an outlier's): comparable
    between frames whatever segments each takes for its inliers."""
    best = _vanishing_line_distances(lines, pixel_from_camera, directions).min(axis=1)
    return float(np.log1p((np.minimum(best, inlier_px) / (CAUCHY_FRACTION * inlier_px)) ** 2
                          ).sum())


#: What :func:`_focal_cost` gives: the frame fitted, and the cost (and refined directions) as
#: a function of the log focal length.
_FittedCost = tuple[ManhattanFrame, Callable[[float], tuple[float, np.ndarray]]]


def _focal_cost(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float
                ) -> _FittedCost | None:
    """The frame fitted at ``focal`` and the cost of its segments as a function of the log
    focal length: the refined frame's Cauchy cost (:func:`_image_cost`, the segments'
    negative log-likelihood under Cauchy noise) with the inliers held fixed, and the refined
    directions. None when fewer than two directions are found."""
    def planes(f: float) -> tuple[np.ndarray, np.ndarray]:
        camera = Intrinsics(f, f, centre[0], centre[1])
        return interpretation_planes(ideal, _camera_from_pixel(camera))

    normals, half = planes(focal)
    frame = fit_manhattan_frame(normals, half, inlier_px, upright=False)
    if (frame.support() >= MIN_DIRECTION_SEGMENTS).sum() < 2:
        return None
    start = frame.directions

    def cost(log_focal: float) -> tuple[float, np.ndarray]:
        f = math.exp(log_focal)
        normals_f, half_f = planes(f)
        directions = _refine(normals_f, half_f, start, inlier_px, 4, frame.labels)
        pixel_from_camera = np.linalg.inv(_camera_from_pixel(Intrinsics(f, f, *centre)))
        return (_image_cost(ideal, pixel_from_camera, directions, frame.labels, inlier_px),
                directions)

    return frame, cost


def polish_focal(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float,
                 span: float = 1.4, iterations: int = 14) -> float:
    """The focal length within ``span`` times ``focal`` at which the segments fit a Manhattan
    frame best: a golden-section search of the refined Cauchy cost, the inliers held fixed.

    The vanishing-point formula (:func:`focal_from_vanishing_points`) uses two clusters; this
    weighs every segment of all three, which matters when one vanishing point is far away.
    """
    fitted = _focal_cost(ideal, centre, focal, inlier_px)
    if fitted is None:
        return focal

    def cost(log_focal: float) -> float:
        return fitted[1](log_focal)[0]

    return math.exp(golden_minimum(cost, math.log(focal / span), math.log(focal * span),
                                   iterations))


def golden_minimum(cost: Callable[[float], float], low: float, high: float,
                   iterations: int) -> float:
    """Where ``cost`` is least within ``[low, high]``: a golden-section search of
    ``iterations`` steps (each narrows the bracket to 0.618 of itself), its middle."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = high - ratio * (high - low), low + ratio * (high - low)
    cost_a, cost_b = cost(a), cost(b)
    for _ in range(iterations):
        if cost_a < cost_b:
            high, b, cost_b = b, a, cost_a
            a = high - ratio * (high - low)
            cost_a = cost(a)
        else:
            low, a, cost_a = a, b, cost_b
            b = low + ratio * (high - low)
            cost_b = cost(b)
    return (low + high) / 2.0


@dataclass(frozen=True)
class FocalUncertainty:
    """How well an image tells its focal length: ``sigma`` the standard deviation of the log
    focal length (a Laplace approximation: the curvature of the segments' Cauchy negative
    log-likelihood, :func:`_focal_cost`, times :data:`FOCAL_SIGMA_SCALE`), and ``degrees`` how
    far the vertical or the wall's normal turns when the focal length moves by ``sigma``
    either way (the frame refitted, its inliers kept)."""

    sigma: float
    degrees: float
    #: The focal lengths ``(low, high)`` in pixels within :data:`FOCAL_SEARCH_SPAN` of the
    #: estimate that fit the segments about as well (:func:`settle_focal`), and how
    #: far the pose turns across them; None and 0 where not searched (a focal length given
    #: or refined from EXIF).
    other_focals: tuple[float, float] | None = None
    other_degrees: float = 0.0


def focal_uncertainty(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float,
                      step: float = 0.05, fitted: _FittedCost | None = None
                      ) -> FocalUncertainty:
    """The uncertainty of an estimated focal length and what it does to the pose
    (:class:`FocalUncertainty`); infinite when the cost does not curve up around ``focal``.
    ``fitted``: :func:`_focal_cost` at ``focal``, when already taken."""
    fitted = fitted or _focal_cost(ideal, centre, focal, inlier_px)
    if fitted is None:
        return FocalUncertainty(math.inf, math.inf)
    cost = fitted[1]
    log_focal = math.log(focal)
    (low, _), (middle, at), (high, _) = (cost(log_focal + d) for d in (-step, 0.0, step))
    curvature = (low + high - 2.0 * middle) / step**2
    if not curvature > 0:
        return FocalUncertainty(math.inf, math.inf)
    sigma = FOCAL_SIGMA_SCALE / math.sqrt(curvature)
    if not sigma < 1.0:  # e times either way: nothing pinned (and no camera to try there)
        return FocalUncertainty(sigma, math.inf)
    reference, order = world_from_camera_of(at)
    degrees = max(_pose_turn(reference, _rotation_of(cost(log_focal + sign * sigma)[1], *order))
                  for sign in (-1.0, 1.0))
    return FocalUncertainty(sigma, degrees)


def _pose_turn(reference: np.ndarray, moved: np.ndarray) -> float:
    """Degrees the vertical or the wall's normal (rows 0 and 2 of two ``world_from_camera``
    rotations, as lines) turns from ``reference`` to ``moved``, whichever turns more."""
    cosine = min(1.0, float(np.abs((reference[[0, 2]] * moved[[0, 2]]).sum(axis=1)).min()))
    return math.degrees(math.acos(cosine))


def _refitted(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float,
              start: np.ndarray) -> tuple[float, np.ndarray]:
    """The frame refitted at ``focal`` from ``start``, taking the segments that fit it there
    (:func:`_refine`), and its cost over every segment (:func:`_truncated_cost`)."""
    camera_from_pixel = _camera_from_pixel(Intrinsics(focal, focal, centre[0], centre[1]))
    directions = _refine(*interpretation_planes(ideal, camera_from_pixel), start, inlier_px)
    return (_truncated_cost(ideal, np.linalg.inv(camera_from_pixel), directions, inlier_px),
            directions)


def _focal_scan(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float,
                start: np.ndarray, steps: int) -> tuple[float, np.ndarray,
                                                        list[tuple[float, float, np.ndarray]]]:
    """:func:`_refitted` at ``focal`` (its cost and directions), and at ``steps`` focal
    lengths spread evenly in log within :data:`FOCAL_SEARCH_SPAN` times it either way, each
    from its neighbour nearer ``focal``: ``(focal length, cost, directions)``."""
    least, here = _refitted(ideal, centre, focal, inlier_px, start)
    offsets = np.linspace(-1.0, 1.0, steps) * math.log(FOCAL_SEARCH_SPAN)
    scanned = []
    for side in (offsets[offsets > 0], offsets[offsets < 0][::-1]):  # outwards from focal
        directions = here
        for offset in side:
            other = focal * math.exp(offset)
            value, directions = _refitted(ideal, centre, other, inlier_px, directions)
            scanned.append((other, value, directions))
    return least, here, scanned


def settle_focal(ideal: np.ndarray, centre: np.ndarray, focal: float, inlier_px: float,
                 steps: int = 13) -> tuple[float, FocalUncertainty]:
    """An estimated ``focal`` checked against the focal lengths further off: the one the
    segments fit best, and its :func:`focal_uncertainty` with the focal lengths that fit
    about as well (``other_focals``, ``other_degrees``).

    The estimate is polished with the inliers of the frame fitted there held
    (:func:`polish_focal`), and the local curvature tells how sharply that cost rises, not
    whether it falls again further off. Refitted where it is taken, a frame can fit the
    segments better at another focal length (York Urban photos whose estimate was 10 to 48 %
    off fit better within 2 % of their calibration), or as well at one that turns the pose:
    a page seen about frontally, with no edge receding from it, fits focal lengths 25 %
    apart about equally (its tilt traded against the focal length), and the curvature at
    either says 4 %. So the frame is refitted at ``steps`` focal lengths within
    :data:`FOCAL_SEARCH_SPAN` times ``focal`` either way (:func:`_focal_scan`), its cost
    taken over every segment. Where one fits better, the best is narrowed down
    (:func:`golden_minimum` within a step either way) and taken instead, and the scan
    repeated from there (once). Focal lengths whose cost exceeds the estimate's by less than
    ``FOCAL_SIGMA_SCALE ** 2 / 2`` (what a quadratic of the curvature behind ``sigma``
    rises at one ``sigma``) fit about as well; the pose's largest turn across them (the
    vertical and the wall's normal, as lines) is ``other_degrees``."""
    fitted = _focal_cost(ideal, centre, focal, inlier_px)
    if fitted is None:
        return focal, FocalUncertainty(math.inf, math.inf)
    least, here, scanned = _focal_scan(ideal, centre, focal, inlier_px,
                                       fitted[0].directions, steps)
    best, value, directions = min(scanned, key=lambda row: row[1])
    if value < least:
        step = 2.0 * math.log(FOCAL_SEARCH_SPAN) / (steps - 1)
        focal = math.exp(golden_minimum(
            lambda log_focal: _refitted(ideal, centre, math.exp(log_focal), inlier_px,
                                        directions)[0],
            math.log(best) - step, math.log(best) + step, 8))
        fitted = _focal_cost(ideal, centre, focal, inlier_px)
        if fitted is None:
            return focal, FocalUncertainty(math.inf, math.inf)
        least, here, scanned = _focal_scan(ideal, centre, focal, inlier_px,
                                           fitted[0].directions, steps)
    local = focal_uncertainty(ideal, centre, focal, inlier_px, fitted=fitted)
    if not math.isfinite(local.degrees):
        return focal, local
    reference, order = world_from_camera_of(here)
    fitting, degrees = [focal], 0.0
    for other, value, directions in scanned:
        if value - least < 0.5 * FOCAL_SIGMA_SCALE**2:
            fitting.append(other)
            degrees = max(degrees, _pose_turn(reference, _rotation_of(directions, *order)))
    return focal, replace(local, other_focals=(min(fitting), max(fitting)),
                          other_degrees=degrees)


# --------------------------------------------------------------------------------------------
# Vanishing points, the focal length, the wall and the pose
# --------------------------------------------------------------------------------------------


def cluster_vanishing_point(lines: np.ndarray, centre: np.ndarray, scale: float) -> np.ndarray:
    """The homogeneous point ``(col, row, w)`` nearest, in least squares, to all the segments'
    lines (weighted by length): the smallest right singular vector of their stacked lines, in
    pixels centred on ``centre`` and divided by ``scale`` for conditioning."""
    ones = np.ones((len(lines), 1))
    p1 = np.hstack([(lines[:, :2] - centre) / scale, ones])
    p2 = np.hstack([(lines[:, 2:] - centre) / scale, ones])
    homogeneous = cross_rows(p1, p2)
    homogeneous /= np.linalg.norm(homogeneous[:, :2], axis=1, keepdims=True)
    lengths = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    point = np.linalg.svd(homogeneous * np.sqrt(lengths)[:, None])[2][-1]
    return np.array([point[0] * scale + centre[0] * point[2],
                     point[1] * scale + centre[1] * point[2], point[2]])


def focal_from_vanishing_points(
    points: list[np.ndarray], centre: np.ndarray, diagonal: float
) -> float | None:
    """``f = sqrt(-(p1 - c).(p2 - c))`` from the best-conditioned pair of
    finite vanishing points (homogeneous pixels) of orthogonal directions; None if none gives
    a focal length within :data:`FOCAL_RANGE` diagonals."""
    finite = []
    for point in points:
        if point is None or abs(point[2]) < 1e-12:
            continue
        offset = point[:2] / point[2] - centre
        if np.linalg.norm(offset) < FINITE_VP_DIAGONALS * diagonal:
            finite.append(offset)
    best: tuple[float, float] | None = None
    for i in range(len(finite)):
        for j in range(i + 1, len(finite)):
            square = -float(finite[i] @ finite[j])
            if square <= 0:
                continue
            focal = math.sqrt(square)
            if not FOCAL_RANGE[0] * diagonal <= focal <= FOCAL_RANGE[1] * diagonal:
                continue
            spread = max(np.linalg.norm(finite[i]), np.linalg.norm(finite[j])) / focal
            if best is None or spread < best[0]:
                best = (spread, focal)
    return None if best is None else best[1]


def world_from_camera_of(
    directions: np.ndarray, support: np.ndarray | None = None, wall: str = "frontal"
) -> tuple[np.ndarray, tuple[int, int, int]]:
    """The rotation (rows: up, wall-right, into-wall in the camera frame) of a Manhattan frame.

    The vertical is the direction nearest the camera's up axis (X), turned to point up. The
    wall (``wall="frontal"``, the default) is the vertical plane most frontal to the
    camera: its normal is the horizontal direction nearest the optical axis (Z), turned into
    the wall, so ``|pan| <= 45``; wall-right is ``into x up``. ``wall="dominant"``: the
    vertical plane with the more horizontal edges instead (``support``: the segments' length
    per direction), whatever its pan: a facade photographed at 55 degrees, not the sliver of
    the building's end. Returns the rotation and which columns of ``directions`` became
    (vertical, wall horizontal, normal).
    """
    vertical = int(np.argmax(np.abs(directions[0])))
    others = [k for k in range(3) if k != vertical]
    normal = max(others, key=lambda k: abs(directions[2, k]))
    along = others[0] if others[1] == normal else others[1]
    if wall == "dominant" and support is not None and support[normal] > support[along]:
        normal, along = along, normal
    return _rotation_of(directions, vertical, along, normal), (vertical, along, normal)


def _rotation_of(directions: np.ndarray, vertical: int, along: int, normal: int) -> np.ndarray:
    """Rows up, wall-right (``into x up``), into-wall from three columns of ``directions``."""
    up = directions[:, vertical] * np.sign(directions[0, vertical] or 1.0)
    into = directions[:, normal] * np.sign(directions[2, normal] or 1.0)
    right = cross_rows(into, up)
    u, _, vt = np.linalg.svd(np.vstack([up, right, into]))
    return u @ vt


def distinct_support(lines: np.ndarray, pixel_from_camera: np.ndarray, directions: np.ndarray,
                     labels: np.ndarray, inlier_px: float,
                     degrees: float = DISTINCT_DEGREES) -> np.ndarray:
    """How many of each direction's segments (``labels``) tell it apart from the frame's
    other two: ``(3,)`` counts, of the columns of ``directions``.

    The frame is fitted to every segment within ``inlier_px`` of a direction; a direction is
    *found* through the segments that could only be its own. A segment is left out of the
    count
    - when its line passes within ``degrees`` of another direction's vanishing point, as seen
      from its middle: it fits that direction about as well. Tree trunks above a point on the
      horizon meet the vertical and a direction receding towards that point alike, as do the
      near-parallel edges of painted bands; ``degrees`` (10) is about the angle the inlier
      distance allows the shortest segment kept (2 % of the diagonal, 16 px at 640x480), so
      only a segment no inlier test could give to the other direction counts;
    - when its own direction's vanishing point lies inside it (by more than ``inlier_px``
      from either end): the image of a line running in a direction ends at that direction's
      vanishing point (the pinhole image of ``P + t d`` as ``t`` grows) and never passes
      it. Lines drawn through a point of a flat picture do.

    ``lines``: ``(N, 4)`` ideal pixels; ``pixel_from_camera``: the camera's ``K`` in the
    thesis's frame (the inverse of :func:`_camera_from_pixel`).
    """
    start, end = lines[:, :2], lines[:, 2:]
    length = np.hypot(*(end - start).T)
    along = (end - start) / np.where(length > 0, length, 1.0)[:, None]
    middle = 0.5 * (start + end)
    points = (pixel_from_camera @ directions).T  # (3, 3): each vanishing point, homogeneous
    toward = points[None, :, :2] - middle[:, None, :] * points[None, :, 2:]  # (N, 3, 2)
    norms = np.linalg.norm(toward, axis=2)
    cosine = np.abs(np.einsum("nkc,nc->nk", toward, along)) / np.where(norms > 0, norms, 1.0)
    cosine = np.where(norms > 0, cosine, 1.0)
    own = np.maximum(labels, 0)
    counted = labels >= 0
    limit = math.cos(math.radians(degrees))
    for k in range(3):
        counted &= (own == k) | (cosine[:, k] < limit)
    # where each segment's own vanishing point falls along it (finite points only)
    point = points[own]
    finite = np.abs(point[:, 2]) * 1e6 > np.linalg.norm(point[:, :2], axis=1)
    reach = np.einsum("nc,nc->n", point[:, :2] / np.where(finite, point[:, 2], 1.0)[:, None]
                      - start, along)
    counted &= ~(finite & (reach > inlier_px) & (reach < length - inlier_px))
    return np.bincount(own[counted], minlength=3)


def _log_at_least(chances: np.ndarray, count: int) -> float:
    """``log10`` of the probability that at least ``count`` of independent events of
    ``chances`` happen (the tail of their Poisson-binomial distribution, by recursion over
    the events)."""
    distribution = np.zeros(len(chances) + 1)
    distribution[0] = 1.0
    for chance in chances:
        distribution[1:] = distribution[1:] * (1.0 - chance) + distribution[:-1] * chance
        distribution[0] *= 1.0 - chance
    return math.log10(max(float(distribution[count:].sum()), 1e-300))


def false_alarms(lines: np.ndarray, pixel_from_camera: np.ndarray, directions: np.ndarray,
                 column: int, inlier_px: float) -> float:
    """``log10`` of how many directions met by as many segments chance alone would show:
    the number of false alarms of the direction ``directions[:, column]`` (the a-contrario
    test of Desolneux, Moisan and Morel, with which Almansa, Desolneux and Vamech find
    vanishing points with no a priori information).

    Under the null hypothesis the segments the frame's other two directions do not take run
    in random directions, each independently. Segment ``i`` then meets a given direction (its
    end points within ``inlier_px`` of the line through its middle and the vanishing point,
    in the image) with probability ``p_i = 2 asin(inlier_px / l_i) / pi``, ``l_i`` its half
    length: the angle its line may turn about its middle. ``k`` of them are seen to meet
    in it, and in no other direction (:func:`distinct_support`, the end-point distance taken
    in the image, where the sphere's is lenient by the focal length over the distance to a
    vanishing point inside the image). The number of false alarms is :data:`HYPOTHESES`
    (the frames the search tried) times the chance that at least ``k`` of them meet in it.
    Short pieces of clutter near a vanishing point inside the image, a long focal length's
    or a flat picture's, meet there about as often as chance would make them; a building's
    receding edges do not (all but one of the York Urban photos' normals: at most
    ``10**-4.6``; the one, whose garden paths meet where its edges do, ``10**0.2``).
    """
    distance = _vanishing_line_distances(lines, pixel_from_camera, directions)
    labels = np.where(distance.min(axis=1) < inlier_px, distance.argmin(axis=1), -1)
    count = int(distinct_support(lines, pixel_from_camera, directions, labels,
                                 inlier_px)[column])
    free = (labels < 0) | (labels == column)
    half = 0.5 * np.hypot(lines[free, 2] - lines[free, 0], lines[free, 3] - lines[free, 1])
    chances = np.minimum(1.0, 2.0 * np.arcsin(np.minimum(1.0, inlier_px / np.maximum(
        half, 1e-9))) / math.pi)
    return math.log10(HYPOTHESES) + _log_at_least(chances, count)


def frame_misfit(normals: np.ndarray, half: np.ndarray, directions: np.ndarray,
                 labels: np.ndarray, axes: tuple[int, ...]) -> float:
    """How far, in degrees, the segments of each of ``axes`` (columns of ``directions``), taken
    alone, point from the frame's axis: the largest angle between an axis and the
    least-squares direction of its own segments.

    The frame is orthogonal; the scene's edges, or the camera's model (principal point, focal
    length, lens), may not be, and then the frame's vertical and wall normal are a compromise
    between directions that disagree, off by about as much as they disagree (on the York
    Urban photos the labelled segments' own directions are 1.5 to 2.8 degrees from orthogonal
    where the frame is furthest from the truth). Each axis's direction is the one nearest, in
    least squares of the refinement's residual ``s * n.v`` (:func:`_refine`, about the
    end-point distance in pixels), to its segments' interpretation planes: the eigenvector of
    ``sum s^2 n n^T`` with the least eigenvalue (``s`` half lengths, ``n`` plane normals).
    The segments are the frame's inliers (within ``inlier_px``), so no outlier weighs; the
    refinement's Cauchy weights are left out, as taken at the frame they would pull each
    direction towards it (weighted so, the misfit told the York photos' errors less well).
    Axes with fewer than :data:`MIN_DIRECTION_SEGMENTS` segments, which cannot tell a
    direction, count 0.

    :func:`estimate_pose` weighs the vertical and the frontal wall's normal (the horizontal
    nearest the optical axis, whose vanishing point is nearest the image and best pinned
    down by its segments); the other horizontal, its vanishing point usually far outside the
    image, is fitted loosely by its own segments (on the York Urban training photos up to 8
    degrees off where the pose is within 2 degrees), and weighing it too made the confidence
    worse (docs/REAL_PHOTOS.md). Where no edge recedes from the camera (fewer than
    :data:`MIN_DIRECTION_SEGMENTS` segments meet in the normal and in no other direction,
    :func:`distinct_support`: a wall seen about frontally) the wall's
    horizontal alone pins the pan, and it is weighed instead; where the normal's segments
    meet in it no more than chance would (:func:`false_alarms`), all three are weighed."""
    misfit = 0.0
    for k in axes:
        own = labels == k
        if own.sum() < MIN_DIRECTION_SEGMENTS:
            continue
        n, s = normals[own], half[own]
        alone = np.linalg.eigh((n * (s**2)[:, None]).T @ n)[1][:, 0]
        cosine = min(1.0, abs(float(alone @ directions[:, k])))
        misfit = max(misfit, math.degrees(math.acos(cosine)))
    return misfit


def confidence_of(rival: float, focal_degrees: float = 0.0, misfit: float = 0.0,
                  upright: float = 1.0, normal_seen: bool = True) -> float:
    """The probability that the pose is within 2 degrees of the truth (vertical and wall
    normal): that the frame's vertical is the world's up (``upright``,
    :func:`upright_probability`) times that the pose is within 2 degrees if it is,
    ``1 / (1 + exp(-(w0 + w1 * rival + w2 * focal_degrees + w3 * misfit)))`` with the
    weights :data:`CONFIDENCE_WEIGHTS` fitted on real photos
    (``benchmarks/calibrate_confidence.py``; their verticals all plainly up, ``upright`` at
    least 0.97). ``rival``: :attr:`ManhattanFrame.rival`; ``focal_degrees``: how far an
    estimated focal length's standard deviation turns the pose (:class:`FocalUncertainty`; 0
    when given); ``misfit``: how far the vertical's and the wall normal's own segments point
    from them (:func:`frame_misfit`, degrees); ``normal_seen``: False for a wall seen frontally,
    whose logit is lower by :data:`UNSEEN_NORMAL_LOGIT`."""
    w0, w1, w2, w3 = CONFIDENCE_WEIGHTS
    logit = w0 + w1 * rival + w2 * focal_degrees + w3 * misfit
    if not normal_seen:
        logit += UNSEEN_NORMAL_LOGIT
    return upright * float(1.0 / (1.0 + math.exp(-logit)))


def upright_probability(directions: np.ndarray) -> float:
    """The probability that the direction of the frame ``directions`` (columns, thesis camera
    frame) nearest the camera's up (X) is the world's up, the one :func:`world_from_camera_of`
    takes as the vertical: under a Gaussian prior of :data:`UPRIGHT_SPREAD_DEGREES` on the
    angle ``a`` between the camera's up and the world's, each direction weighs
    ``exp(-a^2 / 2 s^2)`` (``a`` its angle from the camera's up, as a line) and the nearest
    one's share is returned. About 1 for a photo taken about upright (the next direction is
    70 degrees or more from the camera's up), 0.5 where two directions are equally upright
    (a frame rolled 45 degrees): the lines cannot tell which is up, and the photo's being
    upright can only tell as far as one of them is plainly the more upright."""
    angles = np.degrees(np.arccos(np.minimum(np.abs(directions[0]), 1.0)))
    # each over the nearest one's weight: the nearest weighs 1 however small the spread
    weights = np.exp(-0.5 * (angles**2 - angles.min() ** 2) / UPRIGHT_SPREAD_DEGREES**2)
    return float(1.0 / weights.sum())


def confidence_features(estimate: PoseEstimate) -> np.ndarray:
    """What :func:`confidence_of` weighs, of an estimate: ``rival``, ``focal_degrees``,
    ``misfit``."""
    uncertainty = estimate.focal_uncertainty
    return np.array([estimate.rival, 0.0 if uncertainty is None else uncertainty.degrees,
                     estimate.misfit])


def _camera_from_pixel(intrinsics: Intrinsics) -> np.ndarray:
    """Homogeneous ideal pixel to a camera-frame ray (``K^-1`` in the thesis's frame)."""
    focal = intrinsics.focal
    return np.diag([1.0 / focal, 1.0 / focal, 1.0]) @ intrinsics.image_from_pixel()


def _failure(reason: str, lines: np.ndarray, segments: int, directions: int = 0,
             focal: float | None = None, estimated: bool = False,
             labels: np.ndarray | None = None, structure: float = 0.0,
             uncertainty: FocalUncertainty | None = None) -> PoseEstimate:
    return PoseEstimate(
        None, focal, estimated, 0.0, segments, 0 if labels is None else int((labels >= 0).sum()),
        directions, lines=lines,
        labels=-np.ones(len(lines), dtype=int) if labels is None else labels, error=reason,
        structure=structure, focal_uncertainty=uncertainty)


def estimate_pose(
    image: np.ndarray,
    camera: Intrinsics | None = None,
    *,
    principal_point: tuple[float, float] | None = None,
    lines: np.ndarray | None = None,
    wall: str = "frontal",
    focal_spread: float = 0.0,
) -> PoseEstimate:
    """Pan, tilt and roll of the camera that took ``image``, from its straight lines.

    Convention
    ----------
    ``image``: decoded pixels (grey or BGR[A], any depth), ``(H, W[, C])``. ``camera``: its
    intrinsics (size, if given, must match; lens distortion is removed from the segments' end
    points), or None when the focal length is unknown: it is then estimated from two finite
    orthogonal vanishing points, with the principal point
    ``principal_point`` or the image's centre. ``lines``: segments ``(N, 4)`` to use instead
    of detecting them (tests). ``wall``: ``frontal`` (``|pan| <= 45``) or ``dominant``
    (:func:`world_from_camera_of`). ``focal_spread``: how far the camera's focal length may
    be off, as a fraction (0: exactly known; :data:`EXIF_FOCAL_SPREAD` for an EXIF one): the
    segments then refine it where they pin it (:func:`_refined_focal`; a camera with a lens
    or non-square pixels is taken as given), and ``focal_estimated`` is set. Never raises for
    an image that cannot tell its pose: the result's ``error`` says why (``only 1 of 3
    directions found, 14 segments (each needs 5 that meet in it and in no other); give the
    pose``).
    """
    if wall not in WALL_CHOICES:
        raise ValueError(f"wall must be one of {', '.join(WALL_CHOICES)}, got {wall!r}")
    height, width = np.asarray(image).shape[:2]
    if camera is not None and camera.width is not None and (
            (camera.width, camera.height) != (width, height)):
        raise ValueError(f"the camera is {camera.width}x{camera.height} pixels but the image "
                         f"is {width}x{height}")
    detected = detect_segments(image) if lines is None else _usable_segments(lines)
    segments = len(detected)
    if segments < MIN_SEGMENTS:
        return _failure(f"too few straight segments: {segments} (need {MIN_SEGMENTS}); "
                        f"{remedy()}", detected, segments)
    diagonal = math.hypot(width, height)
    inlier_px = inlier_distance(width, height)
    ideal = detected
    if camera is not None:
        camera = Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew,
                            width, height, camera.lens)
        if camera.lens is not None:
            ideal = camera.ideal_pixels(detected.reshape(-1, 2)).reshape(-1, 4)
            reached = np.all(np.isfinite(ideal), axis=1)  # none beyond the lens's fold
            detected, ideal = detected[reached], ideal[reached]
        elif focal_spread > 0 and camera.fx == camera.fy and camera.skew == 0:
            camera, uncertainty = _refined_focal(ideal, camera, focal_spread, inlier_px)
            return _estimate_known_focal(detected, ideal, camera, inlier_px, segments, True,
                                         wall, uncertainty)
        return _estimate_known_focal(detected, ideal, camera, inlier_px, segments, False, wall)
    if principal_point is None:
        principal_point = ((width - 1) / 2.0, (height - 1) / 2.0)
    centre = np.array(principal_point, dtype=np.float64)
    focal = _focal_of(ideal, centre, diagonal, max(width, height), inlier_px)
    if focal is None:
        # no structure (fur, grass, a painting) says more than "no focal length": the frame
        # at a usual focal length (the long side) is judged as any other
        side = float(max(width, height))
        normals, half = interpretation_planes(
            ideal, _camera_from_pixel(Intrinsics(side, side, centre[0], centre[1])))
        frame = fit_manhattan_frame(normals, half, inlier_px, upright=False)
        structure = structure_ratio(normals, half, frame.directions, inlier_px)
        # the frame found at a stand-in focal length is the view's only roughly: it can
        # tell a vertical no edge runs along, not how many edges meet in it
        up = world_from_camera_of(frame.directions)[1][0]
        refusal = _refusal(structure, None, vertical_ratio(
            normals, half, frame.directions[:, up], inlier_px))
        if refusal is not None:
            return _failure(refusal, detected, segments, estimated=True, structure=structure)
        return _failure(
            "cannot tell the focal length: no two finite vanishing points of orthogonal "
            f"directions ({segments} segments); give the focal length", detected, segments,
            estimated=True)
    focal, uncertainty = settle_focal(ideal, centre, focal, inlier_px)
    trial = Intrinsics(focal, focal, centre[0], centre[1], width=width, height=height)
    return _estimate_known_focal(detected, ideal, trial, inlier_px, segments, True, wall,
                                 uncertainty)


def _refined_focal(ideal: np.ndarray, camera: Intrinsics, spread: float, inlier_px: float
                   ) -> tuple[Intrinsics, FocalUncertainty]:
    """An approximate focal length (``camera``'s, off by about ``spread`` as a fraction)
    refined by the segments: the focal length they fit best near it (:func:`polish_focal`)
    with its uncertainty (:func:`focal_uncertainty`), and the given one, averaged in log by
    their inverse variances (the posterior of a normal prior and a normal likelihood). Where
    the segments do not pin it (the fit's cost does not curve around it, or hardly: a
    standard deviation of a factor e or more) the given one stands, trusted as a given one is.
    The uncertainty returned is the posterior's, its turn of the pose scaled to it."""
    given = camera.focal
    centre = np.array([camera.cx, camera.cy], dtype=np.float64)
    prior = 1.0 / spread**2
    found = polish_focal(ideal, centre, given, inlier_px)
    measured = focal_uncertainty(ideal, centre, found, inlier_px)
    if not (math.isfinite(measured.degrees) and measured.sigma > 0):
        return camera, FocalUncertainty(spread, 0.0)  # nothing to refine it by
    likelihood = 1.0 / measured.sigma**2
    focal = math.exp((likelihood * math.log(found) + prior * math.log(given))
                     / (likelihood + prior))
    sigma = 1.0 / math.sqrt(likelihood + prior)
    refined = Intrinsics(focal, focal, camera.cx, camera.cy, width=camera.width,
                         height=camera.height)
    return refined, FocalUncertainty(sigma, measured.degrees * sigma / measured.sigma)


def _focal_of(ideal: np.ndarray, centre: np.ndarray, diagonal: float, side: float,
              inlier_px: float) -> float | None:
    """The focal length of an image whose camera is unknown.

    The frame is searched at :data:`FOCAL_GRID` focal lengths (multiples of the long side);
    at the best, the clusters' vanishing points must include two finite orthogonal ones
    (``f^2 = -(p1 - c).(p2 - c)``, else None: the image cannot tell), and the better of that
    and the grid's value is polished by :func:`polish_focal` until it settles.
    """
    def fitted(f: float) -> tuple[ManhattanFrame, float, float]:
        camera = Intrinsics(f, f, centre[0], centre[1])
        normals, half = interpretation_planes(ideal, _camera_from_pixel(camera))
        frame = fit_manhattan_frame(normals, half, inlier_px, hypotheses=GRID_HYPOTHESES,
                                    upright=False)
        pixel_from_camera = np.linalg.inv(_camera_from_pixel(camera))
        return frame, f, image_score(ideal, pixel_from_camera, frame.directions, inlier_px)

    frame, focal, score = max((fitted(side * factor) for factor in FOCAL_GRID),
                              key=lambda candidate: candidate[2])
    points = [cluster_vanishing_point(ideal[frame.labels == k], centre, diagonal)
              if (frame.labels == k).sum() >= MIN_DIRECTION_SEGMENTS else None for k in range(3)]
    from_points = focal_from_vanishing_points(points, centre, diagonal)
    if from_points is None:
        return None
    if fitted(from_points)[2] > score:
        focal = from_points
    for _ in range(4):  # each polish re-fits the frame (its inliers) at the new focal length
        polished = polish_focal(ideal, centre, focal, inlier_px)
        done, focal = abs(math.log(polished / focal)) < 0.005, polished
        if done:
            break
    return focal


def _refusal(structure: float, uncertainty: FocalUncertainty | None,
             vertical: float = math.inf, vertical_segments: tuple[int, int] | None = None
             ) -> str | None:
    """Why a frame cannot be trusted, in words a user understands, or None; ``vertical``:
    :func:`vertical_ratio`; ``vertical_segments``: the segments that meet in the frame's
    vertical and in no other of its directions (:func:`distinct_support`) and how many a
    direction needs to be found (:data:`MIN_DIRECTION_SEGMENTS`)."""
    if structure < MIN_STRUCTURE_RATIO:
        # with a focal length given the null model is judged there: a cabin's photo, 4.47
        # times at its own estimate, fits 4.5 to 4.8 times at 400 to 640 px
        return (f"no clear man-made structure: the straight segments fit three orthogonal "
                f"directions only {shown_below(structure)} times as well as random ones do "
                f"(need {MIN_STRUCTURE_RATIO:g}); {remedy(uncertainty is not None)}")
    if vertical_segments is not None and vertical_segments[0] < vertical_segments[1]:
        count = vertical_segments[0]
        runs = ("no segment runs" if count == 0 else
                "only 1 segment runs" if count == 1 else f"only {count} segments run")
        return (f"no vertical structure: {runs} along the vertical found and no other "
                f"direction (need {vertical_segments[1]}); {remedy()}")
    if vertical < MIN_VERTICAL_RATIO:
        return (f"no vertical structure: the segments along the vertical found fit it only "
                f"{shown_below(vertical)} times as well as a random direction (need "
                f"{MIN_VERTICAL_RATIO:g}); {remedy()}")
    if uncertainty is not None and not uncertainty.degrees <= MAX_FOCAL_DEGREES:
        if math.isinf(uncertainty.degrees):
            return ("focal length not determinable from this view: the segments do not pin "
                    "it down; give the focal length")
        return (f"focal length not determinable from this view: +-"
                f"{100 * math.expm1(uncertainty.sigma):.0f} % turns the pose by "
                f"{shown_above(uncertainty.degrees)} deg; give the focal length")
    if uncertainty is not None and uncertainty.other_degrees > MAX_FOCAL_DEGREES:
        low, high = uncertainty.other_focals or (math.nan, math.nan)
        return (f"focal length not determinable from this view: {low:.0f} to {high:.0f} px "
                f"fit the lines about as well and turn the pose by "
                f"{shown_above(uncertainty.other_degrees)} deg; give the focal length")
    return None


def _estimate_known_focal(detected: np.ndarray, ideal: np.ndarray, camera: Intrinsics,
                          inlier_px: float, segments: int, estimated: bool,
                          wall: str, uncertainty: FocalUncertainty | None = None
                          ) -> PoseEstimate:
    """The frame, wall and pose with a known camera (:func:`estimate_pose`'s main path);
    ``uncertainty``: the estimated focal length's (None when given)."""
    normals, half = interpretation_planes(ideal, _camera_from_pixel(camera))
    frame = fit_manhattan_frame(normals, half, inlier_px)
    pixel_from_camera = np.linalg.inv(_camera_from_pixel(camera))
    support = distinct_support(ideal, pixel_from_camera, frame.directions, frame.labels,
                               inlier_px)
    needed = max(MIN_DIRECTION_SEGMENTS, math.ceil(MIN_DIRECTION_FRACTION * segments))
    found = int((support >= needed).sum())
    structure = _structure_of(ideal, camera, normals, half, frame.directions, inlier_px)

    def too_few(found: int, and_why: str = "") -> PoseEstimate:
        return _failure(f"only {found} of 3 directions found, {segments} segments (each "
                        f"needs {needed} that meet in it and in no other{and_why}); "
                        f"{remedy()}", detected, segments, found, camera.focal, estimated,
                        frame.labels, structure, uncertainty)

    if found < 2:
        return too_few(found)
    # the vertical and the frontal wall's normal whichever wall is reported: the refusals
    # and the confidence are the rotation's, not its naming's
    frontal = world_from_camera_of(frame.directions)[1]
    vertical = vertical_ratio(normals, half, frame.directions[:, frontal[0]], inlier_px)
    refusal = _refusal(structure, uncertainty, vertical, (int(support[frontal[0]]), needed))
    if refusal is not None:
        return _failure(refusal, detected, segments, found, camera.focal, estimated,
                        frame.labels, structure, uncertainty)
    # the normal's vanishing point may lie inside the image, where clutter meets by chance
    chance_normal = bool(support[frontal[2]] >= MIN_DIRECTION_SEGMENTS) and false_alarms(
        ideal, pixel_from_camera, frame.directions, frontal[2], inlier_px) > math.log10(
        MAX_FALSE_ALARMS)
    if chance_normal:
        support = np.where(np.arange(3) == frontal[2], 0, support)
        found = int((support >= needed).sum())
        if found < 2:
            return too_few(found, ", and those meeting in the direction receding from the "
                                  "camera no more than chance would")
    # the refusals and the confidence judge the frame fitted as a whole (they were
    # calibrated on it); the pose is the one nearest each direction's own segments
    directions = reconcile_directions(normals, half, frame.directions, inlier_px)
    try:
        lengths = np.bincount(frame.labels[frame.labels >= 0],
                              weights=half[frame.labels >= 0], minlength=3)
        world_from_camera, order = world_from_camera_of(directions, lengths, wall)
        pose = pose_from_rotation(world_from_camera)
    except (PoseError, ValueError) as error:
        return _failure(f"no pose: {error}; give the pose", detected, segments, found,
                        camera.focal, estimated, frame.labels)
    # the directions that pin the pose: the vertical and the frontal wall's normal, or where
    # no edge recedes from the camera (a wall seen frontally) the wall's horizontal instead
    normal_seen = bool(support[frontal[2]] >= MIN_DIRECTION_SEGMENTS)
    # a normal found by chance still turned the frame it was fitted with: all three weigh
    misfit = frame_misfit(normals, half, frame.directions, frame.labels,
                          frontal if chance_normal else
                          (frontal[0], frontal[2] if normal_seen else frontal[1]))
    points: list[tuple[float, float] | None] = []
    relabel = -np.ones(len(frame.labels), dtype=int)
    for name_index, k in enumerate(order):
        relabel[frame.labels == k] = name_index
        point = pixel_from_camera @ directions[:, k]
        if abs(point[2]) * 1e9 <= np.linalg.norm(point[:2]):
            points.append(None)
        else:
            points.append((float(point[0] / point[2]), float(point[1] / point[2])))
    upright = upright_probability(frame.directions)
    return PoseEstimate(
        pose, camera.focal, estimated,
        confidence_of(frame.rival, 0.0 if uncertainty is None else uncertainty.degrees,
                      misfit, upright, normal_seen), segments,
        int((frame.labels >= 0).sum()), found, tuple(points), world_from_camera, detected,
        relabel, structure=structure, focal_uncertainty=uncertainty, rival=frame.rival,
        misfit=misfit, upright=upright, normal_seen=normal_seen,
    )
