"""Radial distortion from the image's own straight lines (``--lens-from-lines``, issue 25
item 4): the plumb-line estimate of k1 of OpenCV's ``plumb_bob`` model, with the pose, behind
a gate that takes it only when the lines say so.

>>> found = lens_from_lines(image, Intrinsics(500, 500, width=640, height=480))  # doctest: +SKIP
>>> found.taken, found.k1, found.reason  # doctest: +SKIP

The model: ``x_d = x (1 + k1 r^2)`` in normalised coordinates ``x = (col - cx) / fx``,
``y = (row - cy) / fy`` (OpenCV's convention, k2 = p1 = p2 = k3 = 0). A wide angle's barrel
distortion is ``k1 < 0``.

How (:func:`lens_from_lines`; no I/O, nothing printed):

1. segments by OpenCV's LSD (:func:`~gsrwt_cli.api.estimate.detect_segments`), as the pose
   estimate finds them: a bent edge comes as several straight pieces;
2. a grid of k1 (:data:`K1_GRID`): at each, the pieces' end points undistorted (about the
   principal point, at the focal length known or first estimated), the Manhattan frame
   searched (:func:`~gsrwt_cli.api.estimate.fit_manhattan_frame`) and scored by how well
   the pieces meet in its vanishing points, measured in the photo's pixels;
3. at the best, a golden-section search of the segments' Cauchy cost (their negative
   log-likelihood: end-point distances from the line through their midpoint and their
   direction's vanishing point, in the photo's pixels), the inliers held and the frame
   refitted at each k1; the straight pieces of one bent edge point at one vanishing point
   only when the edge is straightened;
4. the gate (:func:`_gate`): k1's standard deviation (a Laplace approximation of that cost,
   widened by :data:`~gsrwt_cli.api.estimate.FOCAL_SIGMA_SCALE`, the same likelihood's
   measured optimism) at most :data:`MAX_K1_SIGMA`; k1 at least :data:`MIN_SIGMAS`
   standard deviations from 0; enough segments (:data:`MIN_LENS_SEGMENTS`), spread out
   from the centre (:data:`MIN_OUTER_SEGMENTS` beyond half of the half diagonal, where
   distortion shows); straightening lowering the segments' median residual by at least
   :data:`MIN_RESIDUAL_GAIN`; the lens moving the image's corner by at least
   :data:`MIN_SHIFT_PX`; and no fold of the model within the image. Otherwise the lens stays
   a pinhole and :attr:`LinesLens.reason` says why;
5. the pose estimated again with that lens (:func:`estimate_with_lens_from_lines`), as any
   other lens: the segments' end points undistorted, never the image.

Without a focal length, k1 is searched at the pinhole estimate's focal length ``f0`` (or the
image's long side when there is none) and converted exactly to the focal length the
straightened lines give, ``f1``: one radial term in pixels is the same lens when
``k1' = k1 (f1 / f0)^2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..base.messages import shown_above
from ..geometry.camera import Intrinsics
from ..geometry.lens import Lens
from .estimate import (
    CAUCHY_FRACTION,
    DEFAULT_MIN_CONFIDENCE,
    FOCAL_SIGMA_SCALE,
    GRID_HYPOTHESES,
    MIN_SEGMENTS,
    PoseEstimate,
    _camera_from_pixel,
    _refine,
    detect_segments,
    estimate_pose,
    fit_manhattan_frame,
    golden_minimum,
    inlier_distance,
    interpretation_planes,
)

#: The k1 searched first (normalised coordinates at the reference focal length): barrel
#: lenses to -0.5, pincushion to 0.3. In the lens check (:func:`lens_doubt`), at a focal
#: length ``f`` longer than the image's long side ``L``, the grid and the search's span are
#: ``(f / L)^2`` times these: k1 normalised at ``f`` bends the photo's pixels ``(L / f)^2``
#: times as little, and a focal length estimated through a lens nobody told us of can be
#: several times too long (OpenCV's right webcam, k1 -0.30 at 537 px: one photo's pinhole
#: estimate 2097 px, where the unscaled grid's -0.5 is its lens's -0.03; it was accepted
#: 32 degrees off).
K1_GRID = tuple(round(-0.5 + 0.05 * k, 2) for k in range(17))
#: The golden-section search around the grid's best: this far either way, these many steps.
K1_SPAN = 0.06
K1_ITERATIONS = 16
#: Without a focal length: k1 searched again at the focal length the straightened lines give,
#: at most this many times (until it moves less than :data:`SETTLED_LOG_FOCAL`, 0.2 %), by
#: ``--lens-from-lines`` and by the lens check (:func:`lens_doubt`).
ROUNDS = 3
SETTLED_LOG_FOCAL = 0.002
#: The step of the cost's curvature (:func:`_k1_sigma`).
K1_STEP = 0.01
#: The gate (module docstring). k1's standard deviation at most this (the estimate is then
#: within 0.02 at two standard deviations) ...
MAX_K1_SIGMA = 0.01
#: ... and k1 at least this many standard deviations from 0 (a pinhole is the simpler model:
#: it is kept unless the lines reject it, about 1 in 370 times under a normal law) ...
MIN_SIGMAS = 3.0
#: ... with at least this many segments meeting in the frame's directions ...
MIN_LENS_SEGMENTS = 20
#: ... of which this many with a midpoint beyond half the half diagonal from the principal
#: point (distortion grows with the cube of the radius: the centre tells nothing) ...
MIN_OUTER_SEGMENTS = 8
#: ... the median end-point residual of those segments at least this fraction lower with the
#: lens than without ...
MIN_RESIDUAL_GAIN = 0.10
#: ... and the lens moving the image's furthest corner by at least this many pixels.
MIN_SHIFT_PX = 1.0
#: :func:`lens_doubt`: a pose estimated without the lens the lines show is refused when the
#: pose estimated with it turns the vertical or the wall's normal by more than this. The
#: confidence is the chance of being within 2 degrees, and a pose is taken only when that is
#: the likelier (:data:`~gsrwt_cli.api.estimate.DEFAULT_MIN_CONFIDENCE`); the lens being
#: there (k1 :data:`MIN_SIGMAS` from 0), the straightened pose is the better model's, and a
#: pose more than 2 degrees from it is not likely within 2 of the truth. (Not fitted: on the
#: York Urban photos the lens, where significant, turns the pose by 1.05 degrees at most.)
MAX_LENS_TURN_DEGREES = 2.0


@dataclass(frozen=True)
class LinesLens:
    """What :func:`lens_from_lines` found: ``k1`` (normalised at ``focal``, the focal length
    it refers to; NaN when nothing was found) and its standard deviation ``sigma``;
    ``segments`` meeting in the frame's directions and ``outer`` of them away from the
    centre; the median end-point residual in pixels without (``residual_before``) and with
    (``residual_after``) the lens; ``shift_px``: how far the lens moves the image's furthest
    corner; ``reason``: why the lens was refused (None: taken)."""

    k1: float
    sigma: float
    focal: float
    segments: int = 0
    outer: int = 0
    residual_before: float = math.nan
    residual_after: float = math.nan
    shift_px: float = 0.0
    reason: str | None = None

    @property
    def taken(self) -> bool:
        return self.reason is None

    def lens(self) -> Lens | None:
        """The ``plumb_bob`` lens taken, or None (refused)."""
        return Lens("plumb_bob", (("k1", self.k1),)) if self.taken else None

    def at_focal(self, focal: float) -> LinesLens:
        """The same lens with k1 normalised at another focal length (``k1 (f / f0)^2``)."""
        return replace(self, k1=self.k1 * (focal / self.focal) ** 2,
                       sigma=self.sigma * (focal / self.focal) ** 2, focal=focal)

    def summary(self) -> str:
        """One line for a table: the estimate and its evidence, or why it was refused."""
        if math.isnan(self.k1):
            return f"refused: {self.reason}"
        found = (f"k1 {self.k1:+.4f} +- {self.sigma:.4f} from {self.segments} segments "
                 f"({self.outer} outer), residual {self.residual_before:.2f} -> "
                 f"{self.residual_after:.2f} px, corner moved {self.shift_px:.1f} px")
        return found if self.taken else f"refused: {self.reason} ({found})"


def undistort_k1(pixels: np.ndarray, centre: tuple[float, float], fx: float, fy: float,
                 k1: float) -> np.ndarray:
    """``(N, 2)`` distorted pixels to ideal ones for ``x_d = x (1 + k1 r^2)`` (Newton's method
    on the cubic ``r + k1 r^3 = r_d``); NaN where no ideal radius gives ``r_d`` (beyond the
    fold of a barrel lens, ``r_d > 2 / (3 sqrt(-3 k1))``)."""
    pixels = np.asarray(pixels, dtype=np.float64)
    x = (pixels[:, 0] - centre[0]) / fx
    y = (pixels[:, 1] - centre[1]) / fy
    distorted = np.hypot(x, y)
    if k1 == 0.0:
        return pixels.copy()
    radius = distorted.copy()  # Newton's steps from r_d approach the root from one side
    with np.errstate(all="ignore"):
        for _ in range(30):  # quadratic convergence: a few steps, unless near the fold
            value = radius * (1.0 + k1 * radius**2) - distorted
            slope = 1.0 + 3.0 * k1 * radius**2
            stepped = np.maximum(radius - value / np.where(slope > 1e-9, slope, 1e-9), 0.0)
            settled = np.all(np.abs(stepped - radius) <= 1e-12 * (1.0 + distorted))
            radius = stepped
            if settled:
                break
        good = (np.abs(radius * (1.0 + k1 * radius**2) - distorted) < 1e-7 * (1 + distorted)
                ) & (1.0 + 3.0 * k1 * radius**2 > 0)
        factor = np.where(distorted > 0, radius / np.where(distorted > 0, distorted, 1.0), 1.0)
        ideal = np.column_stack([centre[0] + fx * x * factor, centre[1] + fy * y * factor])
    ideal[~good] = np.nan
    return ideal


class _Search:
    """The segments and camera a k1 search works with: end points undistorted at any k1,
    their frame, their residuals in the photo's pixels."""

    def __init__(self, lines: np.ndarray, camera: Intrinsics, inlier_px: float) -> None:
        self.lines = lines
        self.camera = camera
        self.inlier_px = inlier_px
        self.centre = (camera.cx, camera.cy)
        self.camera_from_pixel = _camera_from_pixel(camera)
        self.pixel_from_camera = np.linalg.inv(self.camera_from_pixel)

    def ideal(self, k1: float) -> tuple[np.ndarray, np.ndarray]:
        """The segments' ideal end points ``(N, 4)`` (NaN beyond the fold) and, per end
        point ``(N, 2)``, how many photo pixels one ideal pixel is there (``r_d / r``)."""
        camera = self.camera
        points = self.lines.reshape(-1, 2)
        ideal = undistort_k1(points, self.centre, camera.fx, camera.fy, k1)
        offset = ideal - np.array(self.centre)
        radius_sq = (offset[:, 0] / camera.fx) ** 2 + (offset[:, 1] / camera.fy) ** 2
        return ideal.reshape(-1, 4), (1.0 + k1 * radius_sq).reshape(-1, 2)

    def planes(self, ideal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        finite = np.all(np.isfinite(ideal), axis=1)
        safe = np.where(finite[:, None], ideal, 0.0)
        normals, half = interpretation_planes(safe, self.camera_from_pixel)
        half = np.where(finite, half, 0.0)
        return normals, half

    def distances(self, ideal: np.ndarray, scale: np.ndarray, directions: np.ndarray
                  ) -> np.ndarray:
        """``(N, 3)``: each segment's end-point distance (photo pixels, about) from the line
        through its midpoint and each direction's vanishing point; inf beyond the fold."""
        points = self.pixel_from_camera @ directions  # homogeneous vanishing points
        mid = np.column_stack([(ideal[:, :2] + ideal[:, 2:]) / 2, np.ones(len(ideal))])
        out = np.empty((len(ideal), 3))
        for k in range(3):
            through = np.cross(mid, points[:, k])
            through /= np.maximum(np.hypot(through[:, 0], through[:, 1]), 1e-300)[:, None]
            first = np.abs(through[:, 0] * ideal[:, 0] + through[:, 1] * ideal[:, 1]
                           + through[:, 2])
            out[:, k] = first * scale.mean(axis=1)
        out[~np.isfinite(out)] = np.inf
        return out

    def grid_score(self, k1: float, seed: int = 0) -> tuple[float, np.ndarray, np.ndarray]:
        """The frame searched at ``k1``: its score (segments' length times a truncated
        quadratic of their photo-pixel distance), the directions and the labels."""
        ideal, scale = self.ideal(k1)
        normals, half = self.planes(ideal)
        frame = fit_manhattan_frame(normals, half, self.inlier_px, hypotheses=GRID_HYPOTHESES,
                                    seed=seed, upright=False)
        distance = self.distances(ideal, scale, frame.directions)
        nearest = distance.min(axis=1)
        lengths = np.hypot(self.lines[:, 2] - self.lines[:, 0],
                           self.lines[:, 3] - self.lines[:, 1])
        score = float((lengths * np.maximum(0.0, 1.0 - (nearest / self.inlier_px) ** 2)).sum())
        labels = np.where(nearest < self.inlier_px, distance.argmin(axis=1), -1)
        return score, frame.directions, labels

    def cost(self, k1: float, start: np.ndarray, labels: np.ndarray
             ) -> tuple[float, np.ndarray, np.ndarray]:
        """The Cauchy cost of the labelled segments at ``k1`` (the frame refitted from
        ``start`` with the labels held), the directions, and the labelled segments'
        distances in photo pixels."""
        ideal, scale = self.ideal(k1)
        normals, half = self.planes(ideal)
        held = np.where(half > 0, labels, -1)
        directions = _refine(normals, half, start, self.inlier_px, 4, held)
        distance = self.distances(ideal, scale, directions)
        used = labels >= 0
        own = distance[np.flatnonzero(used), labels[used]]
        own = np.where(np.isfinite(own), own, 10.0 * self.inlier_px)  # folded: far off
        cauchy = float(np.log1p((own / (CAUCHY_FRACTION * self.inlier_px)) ** 2).sum())
        return cauchy, directions, own


def lens_from_lines(image: np.ndarray, camera: Intrinsics, lines: np.ndarray | None = None,
                    *, wide: bool = False) -> LinesLens:
    """The plumb-line k1 of the camera that took ``image`` (module docstring), normalised at
    ``camera``'s focal lengths (its lens, if any, is ignored: this is for cameras without
    one); ``lines``: segments ``(N, 4)`` instead of detecting them; ``wide``: at a focal
    length longer than the image's long side, search the k1 that bend its pixels as much as
    :data:`K1_GRID` does at the long side (the lens check of a focal length that is itself
    in doubt, :func:`lens_doubt`). Never raises for an image that cannot tell: the result's
    ``reason`` says why."""
    height, width = np.asarray(image).shape[:2]
    detected = detect_segments(image) if lines is None else np.asarray(lines, dtype=np.float64)
    focal = camera.focal
    if len(detected) < MIN_SEGMENTS:
        return LinesLens(math.nan, math.inf, focal,
                         reason=f"too few straight segments: {len(detected)}")
    diagonal = math.hypot(width, height)
    inlier_px = inlier_distance(width, height)
    pinhole = Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, 0.0, width, height)
    search = _Search(detected, pinhole, inlier_px)
    widen = max(1.0, (focal / max(width, height)) ** 2) if wide else 1.0
    grid = [widen * k1 for k1 in K1_GRID]
    scored = [search.grid_score(k1) for k1 in grid]
    best = int(np.argmax([score for score, _, _ in scored]))
    _, start, labels = scored[best]
    if (labels >= 0).sum() < MIN_LENS_SEGMENTS:
        return LinesLens(math.nan, math.inf, focal, int((labels >= 0).sum()),
                         reason=f"too few segments meet in the scene's directions: "
                                f"{int((labels >= 0).sum())} (need {MIN_LENS_SEGMENTS})")
    span = widen * K1_SPAN
    k1 = golden_minimum(lambda k: search.cost(k, start, labels)[0], grid[best] - span,
                        grid[best] + span, K1_ITERATIONS)
    # the inliers again at the found k1, and the search polished once with them
    _, directions, _ = search.cost(k1, start, labels)
    ideal, scale = search.ideal(k1)
    distance = search.distances(ideal, scale, directions)
    nearest = distance.min(axis=1)
    labels = np.where(nearest < inlier_px, distance.argmin(axis=1), -1)
    k1 = golden_minimum(lambda k: search.cost(k, directions, labels)[0], k1 - span / 3,
                        k1 + span / 3, K1_ITERATIONS)
    sigma = _k1_sigma(search, k1, directions, labels)
    residual_after = float(np.median(search.cost(k1, directions, labels)[2]))
    residual_before = float(np.median(search.cost(0.0, directions, labels)[2]))
    middle = (detected[:, :2] + detected[:, 2:]) / 2 - np.array([camera.cx, camera.cy])
    reach = 0.25 * diagonal  # half of the half diagonal
    outer = int(((labels >= 0) & (np.hypot(*middle.T) > reach)).sum())
    corners = np.array([[0.0, 0.0], [width - 1.0, 0.0], [0.0, height - 1.0],
                        [width - 1.0, height - 1.0]])
    ideal_corners = undistort_k1(corners, (camera.cx, camera.cy), camera.fx, camera.fy, k1)
    shift = float(np.max(np.hypot(*(ideal_corners - corners).T)))
    found = LinesLens(k1, sigma, focal, int((labels >= 0).sum()), outer, residual_before,
                      residual_after, shift)
    return replace(found, reason=_gate(found))


def _gate(found: LinesLens) -> str | None:
    """Why the lens ``found`` is not taken (module docstring, step 4), or None."""
    if found.segments < MIN_LENS_SEGMENTS:
        return (f"too few segments meet in the scene's directions: {found.segments} "
                f"(need {MIN_LENS_SEGMENTS})")
    if found.outer < MIN_OUTER_SEGMENTS:
        return (f"too few segments away from the centre: {found.outer} (need "
                f"{MIN_OUTER_SEGMENTS}), where distortion would show")
    if not math.isfinite(found.shift_px):
        return f"k1 {found.k1:+.3f} folds back within the image"
    if not found.sigma <= MAX_K1_SIGMA:
        return (f"the lines do not pin k1 down: +-{shown_above(found.sigma, 3)} (at "
                f"most {MAX_K1_SIGMA:g} taken)")
    if abs(found.k1) < MIN_SIGMAS * found.sigma:
        return (f"no significant distortion: k1 {found.k1:+.4f} is within "
                f"{MIN_SIGMAS:g} standard deviations ({found.sigma:.4f}) of 0")
    if not found.residual_after <= (1.0 - MIN_RESIDUAL_GAIN) * found.residual_before:
        return (f"straightening hardly helps: residual {found.residual_before:.2f} -> "
                f"{found.residual_after:.2f} px (need {MIN_RESIDUAL_GAIN:.0%} lower)")
    if found.shift_px < MIN_SHIFT_PX:
        return (f"too little to matter: k1 {found.k1:+.4f} moves the corners "
                f"{found.shift_px:.2f} px")
    return None


def _k1_sigma(search: _Search, k1: float, directions: np.ndarray, labels: np.ndarray) -> float:
    """k1's standard deviation, as least squares would give it: ``s sqrt(2 / H)`` with ``H``
    the curvature of the segments' summed squared distances in k1 (central differences of
    :data:`K1_STEP`; the frame refitted at each, so the pose's own freedom is accounted for)
    and ``s`` their robust spread (median distance over 0.674, the median of a normal
    law's absolute values), widened by :data:`~gsrwt_cli.api.estimate.FOCAL_SIGMA_SCALE`
    (segments are not independent: several pieces of one edge, LSD's errors along an edge;
    measured for the focal length of the same cost).

    k1 minimises the segments' Cauchy cost, not their squares, and where a few segments
    near the inlier distance still move the squares more than the rest, their sum can bend
    down at that k1 (OpenCV's left webcam given its focal length alone: ``left05``, k1
    -0.23, residual 0.44 -> 0.14 px, the squares least at -0.20). There the Laplace
    approximation of the Cauchy cost itself is taken (its negative log-likelihood: ``1 /
    sqrt(H)``, widened the same way, as for an estimated focal length); inf where neither
    curves up."""
    (low, low_distances), (middle, distances), (high, high_distances) = (
        search.cost(k1 + d, directions, labels)[::2] for d in (-K1_STEP, 0.0, K1_STEP))
    curvature = float((low_distances**2).sum() + (high_distances**2).sum()
                      - 2.0 * (distances**2).sum()) / K1_STEP**2
    if curvature > 0:
        spread = float(np.median(distances)) / 0.674
        return FOCAL_SIGMA_SCALE * spread * math.sqrt(2.0 / curvature)
    cauchy_curvature = (low + high - 2.0 * middle) / K1_STEP**2
    if not cauchy_curvature > 0:
        return math.inf
    return FOCAL_SIGMA_SCALE / math.sqrt(cauchy_curvature)


def _straightened_pose(image: np.ndarray, detected: np.ndarray, centre: tuple[float, float],
                       focal: float, k1: float, wall: str = "frontal") -> PoseEstimate:
    """The pose with no focal length known (:func:`~gsrwt_cli.api.estimate.estimate_pose`)
    from the ``detected`` segments' end points undistorted by ``k1`` about ``centre`` at
    ``focal`` (those beyond the lens's fold left out); its ``lines`` are the kept segments
    as detected."""
    ideal = undistort_k1(detected.reshape(-1, 2), centre, focal, focal, k1).reshape(-1, 4)
    keep = np.all(np.isfinite(ideal), axis=1)
    estimate = estimate_pose(image, None, principal_point=centre, lines=ideal[keep], wall=wall)
    return replace(estimate, lines=detected[keep])


def estimate_with_lens_from_lines(
    image: np.ndarray, camera: Intrinsics | None = None, *,
    principal_point: tuple[float, float] | None = None, wall: str = "frontal",
) -> tuple[PoseEstimate, LinesLens]:
    """The pose estimate of ``image`` (:func:`~gsrwt_cli.api.estimate.estimate_pose`) with
    k1 estimated from its lines first (:func:`lens_from_lines`): with the lens when the gate
    takes it, else exactly the pinhole estimate. ``camera``: intrinsics without a lens, or
    None when the focal length is unknown (then searched at the pinhole estimate's, or the
    long side's, and k1 converted to the focal length estimated with the lens). The
    :class:`LinesLens` returned is normalised at the estimate's focal length."""
    image = np.asarray(image)
    height, width = image.shape[:2]
    detected = detect_segments(image)
    pinhole = estimate_pose(image, camera, principal_point=principal_point, lines=detected,
                            wall=wall)
    if camera is not None:
        reference = Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew,
                               width, height)
    else:
        cx, cy = principal_point or ((width - 1) / 2.0, (height - 1) / 2.0)
        f0 = pinhole.focal or float(max(width, height))
        reference = Intrinsics(f0, f0, cx, cy, width=width, height=height)
    found = lens_from_lines(image, reference, detected)
    if not found.taken:
        return pinhole, found
    if camera is not None:
        with_lens = Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew,
                               width, height, found.lens())
        return estimate_pose(image, with_lens, lines=detected, wall=wall), found
    estimate = pinhole
    for _ in range(ROUNDS):  # k1 at the focal length the straightened lines give, again
        estimate = _straightened_pose(image, detected, (reference.cx, reference.cy),
                                      reference.focal, found.k1, wall)
        if estimate.focal is None:  # no focal length with the lens: k1 means nothing alone
            return pinhole, replace(found, reason=f"no pose with the lens: {estimate.error}")
        if abs(math.log(estimate.focal / reference.focal)) < SETTLED_LOG_FOCAL:
            break
        reference = Intrinsics(estimate.focal, estimate.focal, reference.cx, reference.cy,
                               width=width, height=height)
        found = lens_from_lines(image, reference, detected)
        if not found.taken:
            return pinhole, found
    return estimate, found.at_focal(estimate.focal)


def lens_doubt(image: np.ndarray, estimate: PoseEstimate,
               principal_point: tuple[float, float] | None = None,
               lines: np.ndarray | None = None, found: LinesLens | None = None,
               camera: Intrinsics | None = None) -> str | None:
    """Why a pose estimated with no camera at all (``estimate_pose(image, None)``, its focal
    length estimated, no lens), or with a ``camera`` whose focal length is only EXIF's or
    was given alone (its lens unknown), cannot be trusted because the image's lines show a
    lens, or None.

    An uncalibrated wide angle bends the edges away from the centre; the pinhole estimate
    then takes bent pieces for directions of their own and the focal length from vanishing
    points that are not there (OpenCV's chessboard photos, k1 -0.27 and -0.30: 10 of 26
    accepted more than 3 degrees off; the same photos undistorted are right). So k1 is
    estimated from the lines at the estimate's focal length (:func:`lens_from_lines`, its
    grid ``wide`` when that focal length is longer than the long side) and, where it is
    :data:`MIN_SIGMAS` standard deviations or more from 0 (whether or not its gate would
    take it as a lens), the pose is estimated again from the straightened segments; with no
    camera, k1 is then searched again at the focal length they give, as long as it moves
    and stays significant, at most :data:`ROUNDS` times (a lens makes the pinhole focal
    length too long, and k1 searched there comes out short: a render through k1 -0.2 at
    800 px, 949 px and k1 -0.17 at first, was accepted 3.1 degrees off; searched again,
    -0.185 and refused). The pinhole pose is doubted when that one turns its vertical or its
    wall's normal by more than :data:`MAX_LENS_TURN_DEGREES` (each against the nearest of
    the other frame's axes, as lines), or cannot be told (refused, or below
    :data:`~gsrwt_cli.api.estimate.DEFAULT_MIN_CONFIDENCE`). With a ``camera`` the focal
    length stays the estimate's and the pose is estimated again with that lens: a
    photographer's EXIF says nothing of the lens, and an action camera's or a webcam's bends
    (the chessboard photos given their focal length alone: 17 of 26 accepted 3.4 to 24
    degrees off; with the lines' lens, most within 2.6). ``found``: that k1, when already
    searched (used if at the estimate's focal length, and that no longer than the long
    side)."""
    if not estimate.ok or estimate.focal is None or estimate.world_from_camera is None:
        return None
    image = np.asarray(image)
    height, width = image.shape[:2]
    if camera is not None:
        principal_point = (camera.cx, camera.cy)
    cx, cy = principal_point or ((width - 1) / 2.0, (height - 1) / 2.0)
    focal = estimate.focal
    detected = detect_segments(image) if lines is None else lines
    if found is None or found.focal != focal or focal > max(width, height):
        found = lens_from_lines(image, Intrinsics(focal, focal, cx, cy, width=width,
                                                  height=height), detected, wide=True)
    if not (math.isfinite(found.k1) and abs(found.k1) >= MIN_SIGMAS * found.sigma):
        return None
    if camera is not None:
        straightened = estimate_pose(image, Intrinsics(
            focal, focal, cx, cy, 0.0, width, height,
            Lens("plumb_bob", (("k1", found.k1),))), lines=detected)
    else:
        for round_ in range(ROUNDS):  # k1 again at the focal length the lines then give
            straightened = _straightened_pose(image, detected, (cx, cy), focal, found.k1)
            if (round_ == ROUNDS - 1 or straightened.focal is None
                    or straightened.confidence < DEFAULT_MIN_CONFIDENCE
                    or abs(math.log(straightened.focal / focal)) < SETTLED_LOG_FOCAL):
                break  # the message names the k1 this pose was straightened with
            again = lens_from_lines(image, Intrinsics(
                straightened.focal, straightened.focal, cx, cy, width=width, height=height),
                detected, wide=True)
            if not (math.isfinite(again.k1) and abs(again.k1) >= MIN_SIGMAS * again.sigma):
                break
            focal, found = straightened.focal, again
    bends = (f"the straight edges bend (the lines show a lens: k1 {found.k1:+.3f} +- "
             f"{found.sigma:.3f})")
    if not straightened.ok or straightened.confidence < DEFAULT_MIN_CONFIDENCE:
        return (f"{bends} and no pose holds with it; give the camera's calibration "
                "(--camera)")
    assert straightened.world_from_camera is not None
    cosines = np.abs(estimate.world_from_camera[[0, 2]] @ straightened.world_from_camera.T)
    turn = math.degrees(math.acos(min(1.0, float(cosines.max(axis=1).min()))))
    if turn > MAX_LENS_TURN_DEGREES:
        return (f"{bends} and straightened they turn the pose by {shown_above(turn, 2)} deg; "
                "give the camera's calibration (--camera)")
    return None


def checked_for_a_lens(image: np.ndarray, estimate: PoseEstimate,
                       principal_point: tuple[float, float] | None = None,
                       min_confidence: float = DEFAULT_MIN_CONFIDENCE,
                       found: LinesLens | None = None,
                       camera: Intrinsics | None = None) -> PoseEstimate:
    """``estimate``, made with no camera at all (or with ``camera``, a focal length from
    EXIF or given alone, and no lens), as it stands, or refused with :func:`lens_doubt`'s
    reason (no pose, confidence 0) when it would be taken (no error, confidence at least
    ``min_confidence``) and the lines doubt it (``found``: their k1, when already
    searched)."""
    if not estimate.ok or estimate.confidence < min_confidence:
        return estimate
    doubt = lens_doubt(image, estimate, principal_point, estimate.lines, found, camera)
    if doubt is None:
        return estimate
    return replace(estimate, pose=None, world_from_camera=None, confidence=0.0,
                   vanishing_points=(None, None, None), error=doubt)
