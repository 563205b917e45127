"""Measures of the pose estimator on real photos with a known orientation (York Urban DB).

Pure functions, no I/O: the runner is ``benchmarks/bench_real_photos.py``, and
``tests/api/test_real_photo_eval.py`` checks these functions on the data's own values.

The measures are those of the data's README (``../shared/data/york-urban-train/README.md``):

- **vertical**: the angle between the estimated and the true world-up direction (as
  directions: an estimate upside down is 180 degrees off);
- **wall**: the angle between the estimated wall normal and the nearer of the two true
  horizontals (``wall`` and ``side``), as lines (a normal and its opposite are the same line);
- an image with no estimate counts :data:`NO_ESTIMATE_DEG` (90 degrees) on both;
- over the images: median, 90th percentile (numpy's default, linear interpolation) and worst.

The truth is given as unit vectors in OpenCV's camera frame (x right, y down, z forward). An
estimate is gsrwt's pan, tilt and roll (docs/CONVENTIONS.md): ``world_from_camera = W =
Rx(pan) Ry(tilt) Rz(roll)`` in the thesis's frames (camera X up, Y right, Z forward; world X
up, Y right, Z into the wall). The rows of ``W`` are the world's axes seen from the camera:
row 0 is up, row 1 the wall's right, row 2 the wall's normal (into the wall). OpenCV's camera
axes are the thesis's with ``x = Y``, ``y = -X``, ``z = Z``. This module builds ``W`` itself
from those formulas, not with gsrwt's code, so that it measures that code rather than
repeating it; the test checks it against the data's own pan, tilt and roll.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Vector = NDArray[np.float64]

#: An image with no estimate (refused, failed) counts this error on both measures.
NO_ESTIMATE_DEG = 90.0
#: An estimate with status ok and more than this many degrees off on either measure is
#: "confidently wrong" (issue 23: the count to bring to zero).
CONFIDENTLY_WRONG_DEG = 3.0
#: The confidence is to mean the probability of being within this many degrees (both measures).
WITHIN_DEG = 2.0
#: Edges of the confidence bins of the calibration table (the last bin includes 1).
CONFIDENCE_EDGES: tuple[float, ...] = (0.0, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)


class SceneDirections(NamedTuple):
    """World up, the wall's normal (into the wall) and the wall's horizontal, as unit vectors
    in OpenCV's camera frame (x right, y down, z forward)."""

    up: Vector
    wall: Vector
    side: Vector


class ImageErrors(NamedTuple):
    """One image's errors in degrees (:data:`NO_ESTIMATE_DEG` when it has no estimate)."""

    vertical: float
    wall: float


class Summary(NamedTuple):
    """Median, 90th percentile and worst of a set of errors (degrees)."""

    median: float
    p90: float
    worst: float


class CalibrationBin(NamedTuple):
    """Estimates whose confidence is in ``[low, high)`` (``[low, high]`` for the last bin):
    how many, their mean confidence, and the fraction within :data:`WITHIN_DEG` on both
    measures (NaN for an empty bin)."""

    low: float
    high: float
    count: int
    mean_confidence: float
    fraction_within: float


def _unit(vector: ArrayLike) -> Vector:
    v = np.asarray(vector, dtype=np.float64).reshape(3)
    return v / np.linalg.norm(v)


def world_from_camera(pan: float, tilt: float, roll: float) -> NDArray[np.float64]:
    """``W = Rx(pan) Ry(tilt) Rz(roll)`` (degrees in, thesis frames; docs/CONVENTIONS.md,
    "Pan, tilt, roll and the rotation")."""
    a, b, r = (math.radians(x) for x in (pan, tilt, roll))
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    return rx @ ry @ rz


def opencv_from_thesis_camera(vector: ArrayLike) -> Vector:
    """A thesis camera-frame vector ``(X up, Y right, Z forward)`` in OpenCV's camera frame:
    ``(x, y, z) = (Y, -X, Z)``."""
    v = np.asarray(vector, dtype=np.float64)
    return np.array([v[1], -v[0], v[2]])


def directions_from_pose(pan: float, tilt: float, roll: float) -> SceneDirections:
    """The scene directions of a gsrwt pose, in OpenCV's camera frame: the rows of
    ``world_from_camera`` (world X up, Z into the wall, Y the wall's right)."""
    w = world_from_camera(pan, tilt, roll)
    return SceneDirections(*(opencv_from_thesis_camera(w[i]) for i in (0, 2, 1)))


def angle_between(a: ArrayLike, b: ArrayLike) -> float:
    """The angle between two directions in degrees (0-180), computed with ``atan2`` of the
    cross product's norm and the dot product (accurate near 0 and 180)."""
    u, v = _unit(a), _unit(b)
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v)))


def angle_between_lines(a: ArrayLike, b: ArrayLike) -> float:
    """The angle between two lines through the origin in degrees (0-90): a direction and its
    opposite are the same line."""
    angle = angle_between(a, b)
    return min(angle, 180.0 - angle)


def image_errors(estimate: SceneDirections | None, truth: SceneDirections) -> ImageErrors:
    """The README's two errors of one image: vertical (directions) and wall normal against the
    nearer true horizontal (lines); :data:`NO_ESTIMATE_DEG` on both without an estimate."""
    if estimate is None:
        return ImageErrors(NO_ESTIMATE_DEG, NO_ESTIMATE_DEG)
    wall = min(angle_between_lines(estimate.wall, truth.wall),
               angle_between_lines(estimate.wall, truth.side))
    return ImageErrors(angle_between(estimate.up, truth.up), wall)


def rotation_from_rvec(rvec: ArrayLike) -> NDArray[np.float64]:
    """The rotation of a Rodrigues vector (OpenCV's ``rvec``: axis times angle in radians), by
    Rodrigues' formula ``I + sin(t) K + (1 - cos(t)) K^2``."""
    r = np.asarray(rvec, dtype=np.float64).reshape(3)
    angle = float(np.linalg.norm(r))
    if angle == 0.0:
        return np.eye(3)
    k = r / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def board_errors(estimate: SceneDirections | None, rvec: ArrayLike) -> ImageErrors:
    """The two errors of a photo of a flat target whose pose (``rvec``: the target's frame in
    OpenCV's camera frame, as ``cv2.solvePnP`` gives it) is known, its plane taken as the wall:
    vertical, the angle between the estimated up and the nearer of the target's two in-plane
    axes (as lines: a board has no up of its own); wall, between the estimated wall normal and
    the target's normal (as lines). :data:`NO_ESTIMATE_DEG` on both without an estimate."""
    if estimate is None:
        return ImageErrors(NO_ESTIMATE_DEG, NO_ESTIMATE_DEG)
    axes = rotation_from_rvec(rvec).T  # rows: the target's x, y and normal
    vertical = min(angle_between_lines(estimate.up, axes[0]),
                   angle_between_lines(estimate.up, axes[1]))
    return ImageErrors(vertical, angle_between_lines(estimate.wall, axes[2]))


def along_direction(lines: ArrayLike, camera_matrix: ArrayLike, direction: ArrayLike,
                    tolerance_px: float) -> NDArray[np.bool_]:
    """Which segments ``(N, 4)`` (``x1, y1, x2, y2`` pixels) run along the scene direction
    ``direction`` (OpenCV camera frame) as the pinhole ``camera_matrix`` sees it: both end
    points within about ``tolerance_px`` of the line through the segment's midpoint and the
    direction's vanishing point (half the length times the sine of the angle between the
    segment's interpretation plane and the direction)."""
    segments = np.asarray(lines, dtype=np.float64).reshape(-1, 4)
    inverse = np.linalg.inv(np.asarray(camera_matrix, dtype=np.float64))
    ones = np.ones((len(segments), 1))
    first = np.hstack([segments[:, :2], ones]) @ inverse.T
    second = np.hstack([segments[:, 2:], ones]) @ inverse.T
    normals = np.cross(first, second)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    half = 0.5 * np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    return np.abs(normals @ _unit(direction)) * half < tolerance_px


def summarize(errors: Iterable[float]) -> Summary:
    """Median, 90th percentile (numpy's linear interpolation) and worst."""
    values = np.asarray(list(errors), dtype=np.float64)
    if values.size == 0:
        return Summary(math.nan, math.nan, math.nan)
    return Summary(float(np.median(values)), float(np.percentile(values, 90)),
                   float(values.max()))


def is_within(errors: ImageErrors, limit: float = WITHIN_DEG) -> bool:
    """Both errors at most ``limit`` degrees."""
    return errors.vertical <= limit and errors.wall <= limit


def is_confidently_wrong(ok: bool, errors: ImageErrors,
                         limit: float = CONFIDENTLY_WRONG_DEG) -> bool:
    """An estimate reported ``ok`` that is more than ``limit`` degrees off on either measure."""
    return ok and (errors.vertical > limit or errors.wall > limit)


def relative_error(estimated: float, true: float) -> float:
    """``|estimated - true| / true``."""
    return abs(estimated - true) / true


def calibration_bins(confidences: Sequence[float], within: Sequence[bool],
                     edges: Sequence[float] = CONFIDENCE_EDGES) -> list[CalibrationBin]:
    """The reliability table of the confidence: per bin of confidence, how many estimates and
    which fraction of them is within :data:`WITHIN_DEG` on both measures. A calibrated
    confidence has ``fraction_within`` close to ``mean_confidence`` in every bin."""
    confidence = np.asarray(confidences, dtype=np.float64)
    hit = np.asarray(within, dtype=bool)
    if confidence.shape != hit.shape:
        raise ValueError(f"{confidence.size} confidences but {hit.size} within flags")
    bins = []
    for index, (low, high) in enumerate(zip(edges[:-1], edges[1:])):
        last = index == len(edges) - 2
        member = (confidence >= low) & ((confidence <= high) if last else (confidence < high))
        count = int(member.sum())
        bins.append(CalibrationBin(
            float(low), float(high), count,
            float(confidence[member].mean()) if count else math.nan,
            float(hit[member].mean()) if count else math.nan))
    return bins
