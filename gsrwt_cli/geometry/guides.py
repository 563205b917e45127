"""The pose from what a user shows by hand: the four corners of a rectangle on the wall, or
segments along the wall's vertical and horizontal edges (guided correction).

Pure numpy: points in, a pose out, no I/O. The frames are those of ``docs/CONVENTIONS.md``:
image points here are in the thesis's image frame (``x`` up, ``y`` right, origin at the
principal point, square pixels; :func:`image_points` converts pixels), the world is the
wall's (``X`` up, ``Y`` right, ``Z`` into the wall) and ``world_from_camera = Rx(pan)
Ry(tilt) Rz(roll)``.

A rectangle standing upright on the wall, with width ``w`` along ``Y`` and height ``h`` along
``X``, is imaged by the homography ``H = K [w r_Y, h r_X, t]`` from its own unit square,
``r_X``, ``r_Y`` the world's up and right axes in the camera (the first two rows of
``world_from_camera``) and ``K = diag(f, f, 1)`` (Eq. 3.1). So

- with the focal length, ``K^-1 h1`` and ``K^-1 h2`` are the right and up axes, and their
  lengths' ratio is the aspect ratio ``w / h``;
- without it, ``h1`` and ``h2`` are the vanishing points of the rectangle's horizontal and
  vertical sides, and their orthogonality gives ``f^2 = -(h1 . h2) / (h1_w h2_w)`` (Zhang and
  He's whiteboard rectification; ``f^2 = -(v1 - c).(v2 - c)`` for finite ones);
- with the aspect ratio instead, ``|K^-1 h1| = (w/h) |K^-1 h2|`` gives the focal length.

That closed form starts a Levenberg-Marquardt fit of the corners' reprojection error over
the pose, the rectangle's place and whichever of focal length and aspect ratio are unknown:
the least-squares pose. Its covariance, for :data:`NOMINAL_POINT_ERROR_PX` of error on each
corner, decides whether a view is oblique enough to tell the focal length.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .checks import ViewError
from .gsrwt import Matrix
from .rotations import Pose, PoseError, pose_from_rotation, rotation_from_rvec

#: ``--fit``: which of the wall's directions the output straightens (darktable's fit modes).
#: ``both``: the frontal view; ``vertical``: verticals vertical and parallel, the horizontal
#: perspective left as it was (pan set to 0: a photographer's keystone fix); ``horizontal``:
#: horizontals horizontal and parallel, the vertical perspective left as it was.
FIT_MODES = ("both", "vertical", "horizontal")

#: The error, in pixels, assumed on each clicked point when judging whether the focal length
#: or the aspect ratio can be told from the points.
NOMINAL_POINT_ERROR_PX = 1.0
#: A focal length (or aspect ratio) whose relative standard error, for
#: :data:`NOMINAL_POINT_ERROR_PX` on each point, is above this is not told: the view is too
#: frontal (or the rectangle too small).
MAX_RELATIVE_ERROR = 0.1

CORNER_NAMES = ("top-left", "top-right", "bottom-right", "bottom-left")


class GuideError(ViewError):
    """Guides that give no pose; ``field`` names the guide (``corners``, ``verticals``,
    ``horizontals``, ``aspect``, ``focal``, ``fit``) and the message says what is wrong."""


@dataclass(frozen=True)
class GuidedPose:
    """A pose from guides, with what else they told.

    ``world_from_camera``: the camera's full rotation relative to the wall the guides show;
    ``pose``: the pose to rectify with, after the ``fit`` mode (:func:`fitted_pose`);
    ``focal``: in pixels (``focal_estimated`` when the guides told it); ``aspect``: the
    rectangle's width over height (None without corners), ``aspect_estimated`` when told by
    the corners; ``rms_px``: the root mean square reprojection error of the points (0 when
    they determine the fit exactly); ``focal_relative_error``, ``aspect_relative_error``:
    their standard errors for :data:`NOMINAL_POINT_ERROR_PX` on each point (0 when given);
    ``pose_standard_error_deg``: those of pan, tilt and roll (corners only; the whole
    camera's pose, before the fit mode).
    """

    world_from_camera: Matrix
    pose: Pose
    focal: float
    focal_estimated: bool
    aspect: float | None
    aspect_estimated: bool
    rms_px: float
    focal_relative_error: float = 0.0
    aspect_relative_error: float = 0.0
    pose_standard_error_deg: tuple[float, float, float] | None = None


# --------------------------------------------------------------------------------------------
# Points and checks
# --------------------------------------------------------------------------------------------


def image_points(pixels: np.ndarray, cx: float, cy: float) -> np.ndarray:
    """Pixels ``(col, row)`` of a square-pixel pinhole to the thesis's image frame:
    ``x = cy - row``, ``y = col - cx`` (docs/CONVENTIONS.md)."""
    pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    return np.column_stack([cy - pixels[:, 1], pixels[:, 0] - cx])


def check_corners(corners: np.ndarray) -> np.ndarray:
    """Four pixels ``(col, row)`` of a convex quadrilateral in the order top-left, top-right,
    bottom-right, bottom-left (clockwise as displayed), as a float ``(4, 2)`` array.

    Raises :class:`GuideError` (field ``corners``) saying what is wrong.
    """
    points = np.asarray(corners, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) != 4:
        count = len(points) if points.ndim == 2 else points.size
        raise GuideError("corners", f"need 4 corners (top-left, top-right, bottom-right, "
                                    f"bottom-left), got {count}")
    if not np.all(np.isfinite(points)):
        raise GuideError("corners", "corners must be finite numbers")
    edges = np.roll(points, -1, axis=0) - points
    turns = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] \
        - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    scale = float(np.max(np.linalg.norm(edges, axis=1))) ** 2
    if scale == 0 or np.any(np.abs(turns) <= 1e-9 * scale):
        raise GuideError("corners", "three of the corners are on one line (or two are the "
                                    "same point): not a quadrilateral")
    if np.all(turns < 0):
        raise GuideError("corners", "the corners go counter-clockwise: give them top-left, "
                                    "top-right, bottom-right, bottom-left as displayed")
    if not np.all(turns > 0):
        raise GuideError("corners", "the corners are not a convex quadrilateral in the order "
                                    "top-left, top-right, bottom-right, bottom-left")
    return points


def check_segments(segments: np.ndarray, kind: str) -> np.ndarray:
    """Segments ``(N, 4)`` as ``x1, y1, x2, y2`` pixels, at least two and none of zero length;
    ``kind`` is ``verticals`` or ``horizontals`` (the field of the :class:`GuideError`)."""
    lines = np.asarray(segments, dtype=np.float64)
    if lines.ndim != 2 or lines.shape[1] != 4:
        raise GuideError(kind, "each segment is four numbers x1,y1,x2,y2")
    if len(lines) < 2:
        raise GuideError(kind, f"need two or more {kind[:-1]} segments to find their "
                               f"vanishing point, got {len(lines)}")
    if not np.all(np.isfinite(lines)):
        raise GuideError(kind, "segment ends must be finite numbers")
    if np.any(np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1]) == 0):
        raise GuideError(kind, "a segment has both ends at the same point")
    return lines


def fitted_pose(world_from_camera: Matrix, fit: str = "both") -> Pose:
    """The pose to rectify with for a ``fit`` mode (:data:`FIT_MODES`).

    ``both``: the camera's pose relative to the wall. ``vertical``: ``Rx(-pan) W``, the same
    camera relative to a wall turned about the vertical to face it, which is ``(0, tilt,
    roll)``: verticals come out vertical and parallel, horizontals converge as before.
    ``horizontal``: ``Ry(-b) W`` with ``b`` turning the wall about its horizontal ``Y`` axis
    to face the camera's forward axis: horizontals come out horizontal and parallel.
    """
    if fit not in FIT_MODES:
        raise GuideError("fit", f"fit must be one of {', '.join(FIT_MODES)}, got {fit!r}")
    try:
        pose = pose_from_rotation(world_from_camera)
        if fit == "vertical":
            return Pose(0.0, pose.tilt, pose.roll)
        if fit == "horizontal":
            forward = np.asarray(world_from_camera)[:, 2]
            b = math.atan2(forward[0], forward[2])
            c, s = math.cos(-b), math.sin(-b)
            turned = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]) @ world_from_camera
            pose = pose_from_rotation(turned)
            return Pose(pose.pan, 0.0, pose.roll)
        return pose
    except PoseError as error:
        raise GuideError("corners", f"the guides give no view of a wall in front of the "
                                    f"camera: {error}") from None


# --------------------------------------------------------------------------------------------
# Least squares
# --------------------------------------------------------------------------------------------


def _levenberg_marquardt(residuals: Callable[[np.ndarray], np.ndarray], start: np.ndarray,
                         iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Minimize ``|residuals(p)|^2`` from ``start``; the parameters and the Jacobian there
    (forward differences)."""
    params = np.array(start, dtype=np.float64)

    def jacobian(p: np.ndarray, r: np.ndarray) -> np.ndarray:
        columns = []
        for i in range(len(p)):
            step = 1e-7 * max(1.0, abs(p[i]))
            moved = p.copy()
            moved[i] += step
            columns.append((residuals(moved) - r) / step)
        return np.column_stack(columns)

    r = residuals(params)
    cost = float(r @ r)
    damping, done = 1e-3, False
    for _ in range(iterations):
        j = jacobian(params, r)
        normal = j.T @ j
        gradient = j.T @ r
        improved = False
        while damping < 1e12:
            try:
                step = np.linalg.solve(normal + damping * np.diag(np.diag(normal) + 1e-12),
                                       -gradient)
            except np.linalg.LinAlgError:
                damping *= 10
                continue
            trial = params + step
            trial_r = residuals(trial)
            trial_cost = float(trial_r @ trial_r)
            if np.isfinite(trial_cost) and trial_cost < cost:
                params, r, improved = trial, trial_r, True
                done = cost - trial_cost <= 1e-15 * max(cost, 1e-30) or \
                    np.max(np.abs(step)) < 1e-13
                cost = trial_cost
                damping = max(damping / 10, 1e-12)
                break
            damping *= 10
        if not improved or done or cost < 1e-24:
            break
    return params, jacobian(params, r)


def _covariance(j: np.ndarray) -> np.ndarray:
    """The free parameters' covariance for :data:`NOMINAL_POINT_ERROR_PX` on each
    coordinate: ``sigma^2 (J^T J)^-1`` (infinite where they are not determined)."""
    try:
        covariance = np.linalg.inv(j.T @ j) * NOMINAL_POINT_ERROR_PX ** 2
    except np.linalg.LinAlgError:
        covariance = np.full((j.shape[1], j.shape[1]), np.inf)
    return covariance


def _relative_errors(covariance: np.ndarray, names: Sequence[str]) -> dict[str, float]:
    """Standard errors of the free parameters (``log f``, ``log aspect``: relative errors)."""
    errors = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    return {name: float(error) for name, error in zip(names, errors)}


def _pose_errors(camera_from_world: Matrix, covariance: np.ndarray) -> tuple[float, ...]:
    """Standard errors of pan, tilt and roll (degrees) from the covariance of the rotation
    increment (its first three parameters), through the decomposition's Jacobian."""
    def angles(rvec: np.ndarray) -> np.ndarray:
        return np.array(list(pose_from_rotation((rotation_from_rvec(rvec) @ camera_from_world).T)))

    base = angles(np.zeros(3))
    step = 1e-7
    jacobian = np.column_stack([(angles(step * e) - base) / step for e in np.eye(3)])
    variances = np.diag(jacobian @ covariance[:3, :3] @ jacobian.T)
    return tuple(float(v) for v in np.sqrt(np.maximum(variances, 0.0)))


def _orthonormal(rows: np.ndarray) -> Matrix:
    """The rotation nearest to a 3x3 matrix (SVD)."""
    u, _, vt = np.linalg.svd(rows)
    rotation = u @ vt
    if np.linalg.det(rotation) < 0:
        rotation = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    return rotation


# --------------------------------------------------------------------------------------------
# Four corners
# --------------------------------------------------------------------------------------------

#: The unit square the homography maps from, ``(u right, v up)``: top-left, top-right,
#: bottom-right, bottom-left.
_UNIT_SQUARE = np.array([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]])


def _homography(source: np.ndarray, target: np.ndarray) -> Matrix:
    """The homography of four point pairs (direct linear transform, exact for four)."""
    rows = []
    for (u, v), (x, y) in zip(source, target):
        rows.append([u, v, 1, 0, 0, 0, -x * u, -x * v, -x])
        rows.append([0, 0, 0, u, v, 1, -y * u, -y * v, -y])
    return np.linalg.svd(np.array(rows))[2][-1].reshape(3, 3)


def _focal_from_homography(h: Matrix, aspect: float | None) -> float | None:
    """The focal length the rectangle's homography (from its unit square, in image-frame
    coordinates) implies: from the orthogonality of its sides, or with ``aspect`` from their
    lengths' ratio. None where it implies none (a frontal view, vanishing points at infinity)."""
    h1, h2 = h[:, 0], h[:, 1]
    if aspect is None:
        denominator = h1[2] * h2[2]
        numerator = -(h1[0] * h2[0] + h1[1] * h2[1])
    else:
        numerator = h1[0] ** 2 + h1[1] ** 2 - aspect ** 2 * (h2[0] ** 2 + h2[1] ** 2)
        denominator = aspect ** 2 * h2[2] ** 2 - h1[2] ** 2
    if denominator == 0 or not numerator / denominator > 0:
        return None
    focal = math.sqrt(numerator / denominator)
    return focal if math.isfinite(focal) else None


def _corners_model(params: np.ndarray, rotation0: Matrix, focal: float | None,
                   aspect: float | None) -> np.ndarray:
    """Image-frame points of the rectangle's corners (TL, TR, BR, BL; height 1, centred at
    ``t``) for ``params = [rotation increment (3), t (3), log f?, log aspect?]``."""
    rotation = rotation_from_rvec(params[:3]) @ rotation0  # camera_from_world
    t = params[3:6]
    index = 6
    if focal is None:
        focal = math.exp(params[index])
        index += 1
    if aspect is None:
        aspect = math.exp(params[index])
    half = aspect / 2
    world = np.array([[0.5, -half, 0.0], [0.5, half, 0.0], [-0.5, half, 0.0],
                      [-0.5, -half, 0.0]])
    camera = world @ rotation.T + t
    return focal * camera[:, :2] / camera[:, 2:3]


def pose_from_corners(corners: np.ndarray, focal: float | None = None,
                      aspect: float | None = None, fit: str = "both") -> GuidedPose:
    """The pose from the image-frame points of a rectangle's corners (top-left, top-right,
    bottom-right, bottom-left as it stands on the wall), with the focal length and the
    aspect ratio (width over height) when known.

    Without the focal length it is told by the corners (or by them and ``aspect``) where the
    view is oblique enough; otherwise :class:`GuideError` says so. See the module's docstring.
    """
    points = np.asarray(corners, dtype=np.float64).reshape(4, 2)
    if aspect is not None and not (math.isfinite(aspect) and aspect > 0):
        raise GuideError("aspect", f"the aspect ratio must be a positive number, got {aspect}")
    h = _homography(_UNIT_SQUARE, points)
    focal_given = focal is not None
    start_focal = focal if focal_given else _focal_from_homography(h, aspect)
    if start_focal is None:
        raise _frontal_error(aspect is not None)
    k_inverse = np.diag([1 / start_focal, 1 / start_focal, 1.0])
    right, up, corner = (k_inverse @ h).T
    if corner[2] < 0:
        right, up, corner = -right, -up, -corner
    height_scale = 1.0 / np.linalg.norm(up)
    start_aspect = float(np.linalg.norm(right) * height_scale)
    axes = np.array([up / np.linalg.norm(up), right / np.linalg.norm(right), np.zeros(3)])
    axes[2] = np.cross(axes[0], axes[1])
    camera_from_world = _orthonormal(axes.T)
    bottom_left = corner * height_scale
    centre = bottom_left + camera_from_world @ np.array([0.5, start_aspect / 2, 0.0])
    start = [0.0, 0.0, 0.0, *centre]
    names = ["r1", "r2", "r3", "t1", "t2", "t3"]
    if not focal_given:
        start.append(math.log(start_focal))
        names.append("focal")
    if aspect is None:
        start.append(math.log(start_aspect))
        names.append("aspect")
    fixed_focal = focal if focal_given else None

    def residuals(p: np.ndarray) -> np.ndarray:
        return (_corners_model(p, camera_from_world, fixed_focal, aspect) - points).ravel()

    params, jacobian = _levenberg_marquardt(residuals, np.array(start))
    covariance = _covariance(jacobian)
    errors = _relative_errors(covariance, names)
    rotation = rotation_from_rvec(params[:3]) @ camera_from_world
    index = 6
    found_focal = float(focal) if focal_given else math.exp(params[index])
    index += 0 if focal_given else 1
    found_aspect = float(aspect) if aspect is not None else math.exp(params[index])
    if not focal_given and not errors["focal"] <= MAX_RELATIVE_ERROR:
        raise _frontal_error(aspect is not None, errors["focal"])
    if aspect is None and not errors["aspect"] <= MAX_RELATIVE_ERROR:
        raise GuideError("aspect", f"the corners tell the aspect ratio only to ±"
                         f"{_percent(errors['aspect'])} for {NOMINAL_POINT_ERROR_PX:g} px of "
                         "error on each corner; give --aspect")
    world_from_camera = rotation.T
    r = residuals(params)
    return GuidedPose(world_from_camera, fitted_pose(world_from_camera, fit), found_focal,
                      not focal_given, found_aspect, aspect is None,
                      float(math.sqrt(np.mean(r.reshape(4, 2) ** 2) * 2)),
                      errors.get("focal", 0.0), errors.get("aspect", 0.0),
                      _pose_errors(rotation, covariance)
                      if np.all(np.isfinite(covariance)) else None)


def _percent(relative: float) -> str:
    if not math.isfinite(relative):
        return "infinity"
    return f"{100 * relative:.0f} %" if relative >= 0.1 else f"{100 * relative:.2g} %"


def _frontal_error(aspect_given: bool, relative: float | None = None,
                   field: str = "corners") -> GuideError:
    """The view is too frontal to tell the focal length; what to give instead."""
    spread = "" if relative is None else (
        f" (±{_percent(relative)} for {NOMINAL_POINT_ERROR_PX:g} px of error on each point)")
    instead = ("give --focal" if aspect_given or field != "corners"
               else "give --focal or --aspect")
    return GuideError(field, f"the view is too frontal to tell the focal length{spread}; "
                             f"{instead}")


# --------------------------------------------------------------------------------------------
# Guide segments
# --------------------------------------------------------------------------------------------


def segment_lines(segments: np.ndarray) -> np.ndarray:
    """Homogeneous lines ``(N, 3)`` through image-frame segments ``(N, 4)`` (``x1, y1, x2,
    y2``), unit normals: ``l = p1 x p2`` scaled so that ``l0^2 + l1^2 = 1``."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    ones = np.ones(len(segments))
    lines = np.cross(np.column_stack([segments[:, :2], ones]),
                     np.column_stack([segments[:, 2:], ones]))
    return lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]


def vanishing_point(segments: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """The least-squares meeting point of image-frame segments' lines, homogeneous ``(x, y,
    w)`` with unit norm in coordinates divided by ``scale`` (``w = 0``: at infinity). The
    smallest right singular vector of the lines' stack (segment ends in either order)."""
    lines = segment_lines(np.asarray(segments, dtype=np.float64) / scale)
    point = np.linalg.svd(lines)[2][-1]
    return point * np.array([scale, scale, 1.0])


def _direction(normals: np.ndarray) -> np.ndarray:
    """The unit direction orthogonal to all ``normals`` in the least-squares sense."""
    return np.linalg.svd(normals)[2][-1]


def _interpretation_normals(segments: np.ndarray, focal: float) -> np.ndarray:
    """Unit normals of the planes through the camera centre and each segment (camera frame,
    ``X`` up, ``Y`` right, ``Z`` forward): ``r1 x r2`` (docs/CONVENTIONS.md)."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    ones = np.full(len(segments), focal)
    normals = np.cross(np.column_stack([segments[:, :2], ones]),
                       np.column_stack([segments[:, 2:], ones]))
    return normals / np.linalg.norm(normals, axis=1)[:, None]


def _focal_from_segments(verticals: np.ndarray, horizontals: np.ndarray) -> float | None:
    """``f^2 = -(v1 . v2) / (w1 w2)`` of the two vanishing points; None where they give none."""
    scale = float(np.max(np.abs(np.concatenate([verticals, horizontals])))) or 1.0
    v1 = vanishing_point(verticals, scale)
    v2 = vanishing_point(horizontals, scale)
    denominator = v1[2] * v2[2]
    numerator = -(v1[0] * v2[0] + v1[1] * v2[1])
    if denominator == 0 or not numerator / denominator > 0:
        return None
    return math.sqrt(numerator / denominator)


def pose_from_segments(verticals: np.ndarray | None, horizontals: np.ndarray | None,
                       focal: float | None = None, fit: str = "both") -> GuidedPose:
    """The pose from image-frame segments ``(N, 4)`` along the wall's vertical and horizontal
    edges (two or more of a kind; ends in either order).

    Verticals alone give tilt and roll (``fit vertical``), horizontals alone pan and roll
    (``fit horizontal``), both the whole pose; the focal length, when not given, from their
    two vanishing points where both are finite and the view oblique enough.
    """
    if fit not in FIT_MODES:
        raise GuideError("fit", f"fit must be one of {', '.join(FIT_MODES)}, got {fit!r}")
    needed = {"both": ("verticals", "horizontals"), "vertical": ("verticals",),
              "horizontal": ("horizontals",)}[fit]
    given = {"verticals": verticals, "horizontals": horizontals}
    for kind in needed:
        if given[kind] is None:
            other = {"verticals": "horizontal", "horizontals": "vertical"}[kind]
            raise GuideError(kind, f"--fit {fit} needs two or more {kind} (or corners); "
                                   f"with {other}s alone give --fit {other}")
    focal_given = focal is not None
    relative = 0.0
    if not focal_given:
        if verticals is None or horizontals is None:
            raise GuideError(needed[0], "the focal length cannot be told from guides of one "
                                        "kind; give --focal, or verticals and horizontals both")
        focal = _focal_from_segments(verticals, horizontals)
        if focal is None:
            raise _frontal_error(False, field="verticals")
        relative = _segments_focal_error(verticals, horizontals, focal)
        if not relative <= MAX_RELATIVE_ERROR:
            raise _frontal_error(False, relative, "verticals")
    up = right = None
    if verticals is not None:
        up = _refine_direction(verticals, _direction(_interpretation_normals(verticals, focal)),
                               focal)
        up = up if up[0] >= 0 else -up  # the image is roughly upright: up is up
    if horizontals is not None:
        right = _refine_direction(
            horizontals, _direction(_interpretation_normals(horizontals, focal)), focal)
        right = right if right[1] >= 0 else -right
    if up is not None and right is not None:
        assert verticals is not None and horizontals is not None
        world_from_camera = _rotation_from_directions(verticals, horizontals, up, right, focal)
    elif up is not None:  # tilt and roll: Rx(pan) leaves the first row alone
        tilt = math.degrees(math.asin(max(-1.0, min(1.0, up[2]))))
        roll = math.degrees(math.atan2(-up[1], up[0]))
        world_from_camera = _pose_rotation(0.0, tilt, roll)
    else:  # pan and roll: W = Ry(b) Rx(pan) Rz(roll) leaves the second row as Rx Rz's
        assert right is not None
        pan = math.degrees(math.asin(max(-1.0, min(1.0, -right[2]))))
        roll = math.degrees(math.atan2(right[0], right[1]))
        world_from_camera = _pose_rotation(pan, 0.0, roll)
    return GuidedPose(world_from_camera, fitted_pose(world_from_camera, fit), float(focal),
                      not focal_given, None, False, 0.0, relative, 0.0)


def _pose_rotation(pan: float, tilt: float, roll: float) -> Matrix:
    from .rotations import rotation_from_pose

    return rotation_from_pose(pan, tilt, roll)


def _end_distances(segments: np.ndarray, direction: np.ndarray, focal: float) -> np.ndarray:
    """How far (pixels) each segment's first end lies from the line through the segment's
    midpoint and the vanishing point of ``direction`` (camera frame; the point
    ``(f d_X, f d_Y, d_Z)``, at infinity included): the geometric error of a vanishing
    point, the same at both ends."""
    vanishing = np.array([focal * direction[0], focal * direction[1], direction[2]])
    middles = (segments[:, :2] + segments[:, 2:]) / 2
    lines = np.cross(np.column_stack([middles, np.ones(len(segments))]), vanishing)
    lines = lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]
    return lines[:, 0] * segments[:, 0] + lines[:, 1] * segments[:, 1] + lines[:, 2]


def _refine_direction(segments: np.ndarray, start: np.ndarray, focal: float) -> np.ndarray:
    """The direction whose vanishing point the segments meet in, least squares of
    :func:`_end_distances` from ``start`` (over the plane tangent to it)."""
    start = start / np.linalg.norm(start)
    basis = np.linalg.svd(start[None, :])[2][1:]  # two unit vectors orthogonal to start

    def direction(p: np.ndarray) -> np.ndarray:
        moved = start + p @ basis
        return moved / np.linalg.norm(moved)

    params, _ = _levenberg_marquardt(lambda p: _end_distances(segments, direction(p), focal),
                                     np.zeros(2))
    return direction(params)


def _rotation_from_directions(verticals: np.ndarray, horizontals: np.ndarray,
                              up: np.ndarray, right: np.ndarray, focal: float) -> Matrix:
    """The rotation whose up and right axes (rows of ``world_from_camera``) the vertical and
    horizontal segments meet in, least squares of :func:`_end_distances`, from ``up`` and
    ``right`` (made orthogonal)."""
    axes = np.array([up, right, np.cross(up, right)])
    camera_from_world = _orthonormal(axes.T)

    def residuals(p: np.ndarray) -> np.ndarray:
        rotation = rotation_from_rvec(p) @ camera_from_world
        return np.concatenate([_end_distances(verticals, rotation[:, 0], focal),
                               _end_distances(horizontals, rotation[:, 1], focal)])

    params, _ = _levenberg_marquardt(residuals, np.zeros(3))
    return (rotation_from_rvec(params) @ camera_from_world).T


def _segments_focal_error(verticals: np.ndarray, horizontals: np.ndarray,
                          focal: float) -> float:
    """The relative standard error of the segments' focal length for
    :data:`NOMINAL_POINT_ERROR_PX` of error across each segment at each end (linear)."""
    squares = 0.0
    for which in (0, 1):
        segments = np.array(verticals if which == 0 else horizontals, dtype=np.float64)
        for i in range(len(segments)):
            d = segments[i, 2:] - segments[i, :2]
            normal = np.array([-d[1], d[0]]) / np.hypot(*d)
            for end in (0, 2):
                moved = segments.copy()
                moved[i, end:end + 2] += 1e-3 * normal
                pair = (moved, horizontals) if which == 0 else (verticals, moved)
                found = _focal_from_segments(*pair)
                if found is None:
                    return math.inf
                squares += ((found - focal) / 1e-3 * NOMINAL_POINT_ERROR_PX / focal) ** 2
    return math.sqrt(squares)
