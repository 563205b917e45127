"""Camera poses as other tools give them: pan/tilt/roll, rotation matrices, Rodrigues vectors
(OpenCV ``solvePnP``) and quaternions (ROS tf), converted both ways.

Pure numpy: arrays and numbers in, arrays and numbers out, no I/O, no OpenCV. Angles are
degrees at every public edge (pan, tilt, roll); a Rodrigues vector's length is radians, as
OpenCV's. The frames are those of ``docs/CONVENTIONS.md``; see
``docs/POSES.md`` for a picture.

Frames
------
- **Thesis camera**: X up, Y right, Z forward (the optical axis).
- **Thesis world** (the wall's frame): X up, Y right, Z into the wall; the camera sits at the
  origin and the wall is the plane ``Z = Zc``.
- ``world_from_camera = Rx(pan) @ Ry(tilt) @ Rz(roll)`` (:func:`rotation_from_pose`): its
  columns are the camera's up, right and forward axes in the world; its transpose at roll 0
  is :func:`gsrwt_cli.geometry.gsrwt.camera_from_world` (Eq. 3.8), whose rows are the same axes.
  ``pan > 0`` turns the camera left, ``tilt > 0`` up, ``roll > 0`` leans its top to the right
  (the scene then appears turned counter-clockwise in the image).
- **OpenCV camera**: x right, y down, z forward. **OpenCV wall** (a chessboard's object frame
  seen from its front): x right, y down, z into the wall, the wall the plane ``z = 0``.
- ``R = camera_from_wall`` in OpenCV frames is what ``solvePnP`` returns as ``rvec``
  (``cv2.Rodrigues(rvec)[0] == R``) and a ROS tf lookup of the wall in the camera's optical
  frame returns as a quaternion. ``p_camera = R @ p_wall + tvec``.
- OpenCV -> thesis, for camera and wall alike: ``C = [[0,-1,0],[1,0,0],[0,0,1]]``
  (``X = -y, Y = x, Z = z``), and ``world_from_camera = C @ R.T @ C.T``.

The wall is in front of the camera
----------------------------------
The roll only turns the camera about its optical axis, so the forward axis in the world is the
third column of ``Rx(pan) Ry(tilt)``: ``(sin tilt, -sin pan cos tilt, cos pan cos tilt)``.
The optical axis meets the wall in front of the camera exactly when that axis points into the
wall, ``world_from_camera[2, 2] = cos(pan) cos(tilt) > 0``. The same entry is ``R[2, 2]`` in
OpenCV's frames (``C`` leaves the z axes alone), the forward component of the wall's z axis.
It is also exactly the condition under which the decomposition (:func:`pose_from_rotation`)
lands in the pose's domain: ``W[2, 2] > 0`` makes ``|W[0, 2]| < 1`` (a unit column), so
``|tilt| < 90``, and then ``cos(pan) = W[2, 2] / cos(tilt) > 0``, so ``|pan| < 90``;
conversely every pan and tilt strictly between -90 and 90 gives ``cos(pan) cos(tilt) > 0``.
``W[2, 2] <= 0`` (the wall behind the camera, or edge-on at 0) is a :class:`PoseError`.

Over 400 lines: three representations of a rotation, each converted both ways, with the
checks that keep them honest.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..base.messages import quote
from .checks import ViewError, as_number
from .gsrwt import camera_from_world, interception

Matrix = NDArray[np.float64]
Vector = NDArray[np.float64]

#: OpenCV frame -> thesis frame, for camera and wall alike: ``X = -y, Y = x, Z = z``.
THESIS_FROM_OPENCV: Matrix = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
THESIS_FROM_OPENCV.setflags(write=False)

#: A 3x3 matrix is a rotation when ``max |M^T M - I| <= ROTATION_TOLERANCE`` and ``det M > 0``.
#: Every matrix this module builds is orthonormal to about 1e-15; the slack is for matrices
#: printed with about seven significant digits.
ROTATION_TOLERANCE = 1e-6

#: A quaternion is normalized (quietly) when ``|qw² + qx² + qy² + qz² - 1| <=`` this, and
#: refused otherwise. This is ROS tf2's ``QUATERNION_NORMALIZATION_TOLERANCE`` (10e-3 on the
#: squared norm): it accepts quaternions rounded to three or more decimals and refuses the
#: mistakes a far-off norm betrays (a column in the wrong place, a zero quaternion, degrees).
QUATERNION_NORM_SQUARED_TOLERANCE = 1e-2


class PoseError(ValueError):
    """A rotation or translation that is no camera pose facing a wall; the message says why."""


@dataclass(frozen=True)
class Pose:
    """Where a camera looks, relative to the wall: ``pan``, ``tilt``, ``roll`` in degrees.

    ``pan > 0`` turns left, ``tilt > 0`` tilts up (Sec. 3.2), both strictly between -90
    and 90. ``roll`` turns the camera about its optical axis after them (docs/CONVENTIONS.md):
    ``world_from_camera = Rx(pan) Ry(tilt) Rz(roll)``; ``roll > 0`` leans the camera's top to
    the right (seen from behind it), so the scene appears turned counter-clockwise.
    """

    pan: float
    tilt: float
    roll: float = 0.0

    def __post_init__(self) -> None:
        for name in ("pan", "tilt", "roll"):
            object.__setattr__(self, name, as_number(name, getattr(self, name)))
        for name in ("pan", "tilt"):
            value = getattr(self, name)
            if abs(value) >= 90.0:
                raise ViewError(
                    name,
                    f"{name} must be strictly between -90 and 90 degrees (the camera cannot see "
                    f"the wall otherwise), got {value:g}",
                )
        if abs(self.roll) > 180.0:
            raise ViewError("roll", f"roll must be within -180 and 180 degrees, got "
                            f"{self.roll:g}")

    def __iter__(self) -> Iterator[float]:
        """``pan, tilt, roll = pose``."""
        return iter((self.pan, self.tilt, self.roll))

    def camera_from_world(self) -> Matrix:
        """The rotation whose rows are the camera's axes in the wall's frame (Eq. 3.8, then
        the roll about the optical axis): ``(Rx(pan) Ry(tilt) Rz(roll))^T``."""
        return self.unrolled_from_rolled().T @ camera_from_world(self.pan, self.tilt)

    def unrolled_from_rolled(self) -> Matrix:
        """``Rz(roll)``: directions of the rolled camera in the camera at the same pan and
        tilt without roll (thesis frame, X up, Y right). In the image frame (x up, y right)
        the same matrix turns the rolled camera's image points into the unrolled one's."""
        if self.roll == 0:
            return np.eye(3)
        angle = math.radians(self.roll)
        c, s = math.cos(angle), math.sin(angle)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    @property
    def theta_deg(self) -> float:
        """The angle between image plane and wall (Eq. 4.15): no focal length needed."""
        return interception(self.pan, self.tilt)[0]

    @property
    def foreshortening(self) -> float:
        """``cos theta = cos alpha cos beta`` (Eq. 4.15)."""
        return interception(self.pan, self.tilt)[1]


# --------------------------------------------------------------------------------------------
# Validation helpers
# --------------------------------------------------------------------------------------------


def _finite_number(name: str, value: float, what: str = "a number of degrees") -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"{name} must be {what}, got {quote(value)}") from exc
    if not math.isfinite(number):
        raise PoseError(f"{name} must be finite, got {number!r}")
    return number


def _vector3(name: str, values: ArrayLike) -> Vector:
    """A finite 3-vector from ``(3,)``, ``(3, 1)`` or ``(1, 3)`` (OpenCV returns ``(3, 1)``)."""
    try:
        vector = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"{name} must be three numbers, got {quote(values)}") from exc
    if vector.size != 3 or vector.ndim > 2:
        raise PoseError(f"{name} must be three numbers, got shape {vector.shape}")
    vector = vector.reshape(3)
    if not np.all(np.isfinite(vector)):
        raise PoseError(f"{name} must be finite, got {vector.tolist()}")
    return vector


def _rotation(name: str, matrix: ArrayLike) -> Matrix:
    """``matrix`` as a float 3x3 array, refused unless it is a rotation (orthonormal, det +1)."""
    try:
        m = np.asarray(matrix, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PoseError(f"{name} must be a 3x3 rotation matrix, got {quote(matrix)}") from exc
    if m.shape != (3, 3):
        raise PoseError(f"{name} must be a 3x3 rotation matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise PoseError(f"{name} must be finite")
    error = float(np.max(np.abs(m.T @ m - np.eye(3))))
    if error > ROTATION_TOLERANCE:
        raise PoseError(
            f"{name} is not a rotation: its columns are not orthonormal "
            f"(max |M^T M - I| = {error:.3g} > {ROTATION_TOLERANCE:g})"
        )
    if np.linalg.det(m) <= 0:
        raise PoseError(f"{name} is not a rotation: it is a reflection (determinant -1)")
    return m


def _plain(value: float) -> float:
    """A Python float without a negative zero (tables print ``-0`` otherwise)."""
    return float(value) + 0.0


# --------------------------------------------------------------------------------------------
# Pan, tilt, roll <-> world_from_camera
# --------------------------------------------------------------------------------------------


def _rx(angle_rad: float) -> Matrix:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(angle_rad: float) -> Matrix:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(angle_rad: float) -> Matrix:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_pose(pan: float, tilt: float, roll: float = 0.0) -> Matrix:
    """``world_from_camera = Rx(pan) @ Ry(tilt) @ Rz(roll)`` in the thesis frames.

    Degrees in. Columns: the camera's up, right and forward axes in the world (X up, Y right,
    Z into the wall). At ``roll = 0`` it is exactly the transpose of
    :func:`gsrwt_cli.geometry.gsrwt.camera_from_world` (Eq. 3.8). Any finite angles are accepted
    (it is a formula); only pan and tilt strictly within (-90, 90) keep the wall in front.
    """
    alpha = math.radians(_finite_number("pan", pan))
    beta = math.radians(_finite_number("tilt", tilt))
    rho = math.radians(_finite_number("roll", roll))
    return _rx(alpha) @ _ry(beta) @ _rz(rho)


def pose_from_rotation(world_from_camera: ArrayLike) -> Pose:
    """Pan, tilt and roll in degrees of a ``world_from_camera`` rotation.

    ``tilt = asin(W[0,2])``, ``pan = atan2(-W[1,2], W[2,2])``, and ``roll`` from
    ``(Rx(pan) Ry(tilt))^T W = Rz(roll)``: ``roll = atan2(M[1,0], M[0,0])``. Unique whenever
    the wall is in front, ``W[2,2] = cos(pan) cos(tilt) > 0`` (see the module's docstring).

    Raises :class:`PoseError` when ``W`` is not a rotation (within :data:`ROTATION_TOLERANCE`)
    or the wall is not in front of the camera.
    """
    w = _rotation("world_from_camera", world_from_camera)
    forward_into_wall = w[2, 2]
    if not forward_into_wall > 0:
        raise PoseError(
            "the wall is not in front of the camera: its optical axis points "
            + ("along the wall" if forward_into_wall == 0 else "away from the wall")
            + f" (cos(pan)·cos(tilt) = world_from_camera[2,2] = camera_from_wall[2,2] = "
            f"{forward_into_wall:.6g}, must be > 0)"
        )
    beta = math.asin(min(1.0, max(-1.0, float(w[0, 2]))))
    alpha = math.atan2(-float(w[1, 2]), float(w[2, 2]))
    rolled = (_rx(alpha) @ _ry(beta)).T @ w
    rho = math.atan2(float(rolled[1, 0]), float(rolled[0, 0]))
    pan, tilt, roll = math.degrees(alpha), math.degrees(beta), math.degrees(rho)
    if not (abs(pan) < 90.0 and abs(tilt) < 90.0):  # W[2,2] > 0 within rounding of 90 degrees
        raise PoseError(
            f"the wall is edge-on to the camera (pan {pan:.12g}, tilt {tilt:.12g}): "
            "both must be strictly between -90 and 90 degrees"
        )
    return Pose(_plain(pan), _plain(tilt), _plain(roll))


# --------------------------------------------------------------------------------------------
# OpenCV frames <-> thesis frames
# --------------------------------------------------------------------------------------------


def world_from_camera_from_opencv(camera_from_wall: ArrayLike) -> Matrix:
    """The thesis ``world_from_camera`` of OpenCV's ``R = camera_from_wall``: ``C R^T C^T``.

    ``C`` = :data:`THESIS_FROM_OPENCV`. ``R`` maps OpenCV wall coordinates (x right, y down,
    z into the wall) to OpenCV camera coordinates (x right, y down, z forward); ``R^T`` maps
    camera to wall, and ``C`` on both sides re-expresses both frames in the thesis's axes.
    """
    r = _rotation("camera_from_wall", camera_from_wall)
    return THESIS_FROM_OPENCV @ r.T @ THESIS_FROM_OPENCV.T


def opencv_from_world_from_camera(world_from_camera: ArrayLike) -> Matrix:
    """OpenCV's ``R = camera_from_wall`` of a thesis ``world_from_camera``: ``C^T W^T C``.

    The inverse of :func:`world_from_camera_from_opencv`. This is the rotation OpenCV's
    functions (``projectPoints``, ``initUndistortRectifyMap``) take in their own frames.
    """
    w = _rotation("world_from_camera", world_from_camera)
    return THESIS_FROM_OPENCV.T @ w.T @ THESIS_FROM_OPENCV


#: ROS body frame (REP 103: x forward, y left, z up) -> thesis frame (X up, Y right, Z forward),
#: for a body and its world alike: ``X = z, Y = -y, Z = x``.
THESIS_FROM_ROS_BODY: Matrix = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
THESIS_FROM_ROS_BODY.setflags(write=False)


def world_from_camera_from_ros_body(world_from_body: ArrayLike) -> Matrix:
    """The thesis ``world_from_camera`` of a body's orientation in ROS's body axes: ``M R M^T``.

    ``world_from_body`` maps vectors of a body frame in ROS's convention (REP 103: x forward,
    y left, z up; an ``Imu``'s frame, a ``camera_link``) to a gravity-aligned world frame in
    the same convention (x forward, into the wall; y left; z up), as a ``sensor_msgs/Imu``
    orientation does (REP 145). ``M`` = :data:`THESIS_FROM_ROS_BODY` re-expresses both in
    the thesis's axes. The body's x axis is the optical axis: the identity is a camera facing
    the wall squarely; a yaw by ``a`` (about z, up, to the left) is pan ``a``, a pitch by
    ``b`` (about y, left: positive looks down) is tilt ``-b``, a roll by ``r`` (about x:
    positive lifts the left side) is roll ``r`` (the top leans right).
    """
    r = _rotation("world_from_body", world_from_body)
    return THESIS_FROM_ROS_BODY @ r @ THESIS_FROM_ROS_BODY.T


# --------------------------------------------------------------------------------------------
# Rodrigues vectors and quaternions <-> rotation matrices (numpy, no OpenCV)
# --------------------------------------------------------------------------------------------


def cross_matrix(v: ArrayLike) -> np.ndarray:
    """``[v]_x``, the matrix with ``[v]_x @ u == cross(v, u)``; of vectors ``(..., 3)``, the
    matrices ``(..., 3, 3)``."""
    v = np.asarray(v, dtype=np.float64)
    matrix = np.zeros(v.shape + (3,))
    matrix[..., 0, 1], matrix[..., 0, 2] = -v[..., 2], v[..., 1]
    matrix[..., 1, 0], matrix[..., 1, 2] = v[..., 2], -v[..., 0]
    matrix[..., 2, 0], matrix[..., 2, 1] = -v[..., 1], v[..., 0]
    return matrix


def cross_rows(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """``np.cross(a, b)`` of vectors along the last axis (broadcast), the same products and
    differences written out: numpy's own moves axes about, several times slower on the
    short arrays of an estimate."""
    a, b = np.asarray(a), np.asarray(b)
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def rotation_from_rvec(rvec: ArrayLike) -> Matrix:
    """The rotation of a Rodrigues vector, as ``cv2.Rodrigues(rvec)[0]`` computes it.

    ``rvec = theta · k`` (``k`` the unit axis, ``theta = |rvec|`` radians, turning
    counter-clockwise about ``k`` seen from its tip). Rodrigues' formula with ``A = [rvec]_x``:
    ``R = I + (sin theta / theta) A + ((1 - cos theta) / theta²) A²``, the coefficients
    computed as ``sinc`` terms (``(1 - cos t)/t² = ½ (sin(t/2)/(t/2))²``) so that small and
    zero angles need no special case. Shapes ``(3,)``, ``(3, 1)`` and ``(1, 3)`` are accepted.
    """
    r = _vector3("rvec", rvec)
    theta = float(np.linalg.norm(r))
    a = cross_matrix(r)
    sin_over_theta = float(np.sinc(theta / math.pi))  # numpy's sinc(x) = sin(pi x)/(pi x)
    half = float(np.sinc(theta / (2.0 * math.pi)))
    one_minus_cos_over_theta2 = 0.5 * half * half
    return np.eye(3) + sin_over_theta * a + one_minus_cos_over_theta2 * (a @ a)


def quaternion_from_rotation(rotation: ArrayLike) -> tuple[float, float, float, float]:
    """The unit quaternion ``(qw, qx, qy, qz)`` of a rotation (Hamilton, scalar first).

    ``q = (cos(theta/2), sin(theta/2) k)`` for a turn by ``theta`` about the unit axis ``k``;
    ``q`` and ``-q`` are the same rotation, and the one returned has ``qw >= 0`` (when
    ``qw == 0``, a half turn, its first non-zero vector component is positive). Shepperd's
    method: take the square root of the largest of ``1 + trace``, ``1 + 2 R[i,i] - trace``,
    which is at least 1, and the other components from the off-diagonal sums and
    differences, so every rotation, half turns included, is computed without cancellation:

    - ``4 qw² = 1 + trace``, ``4 qw qx = R21 - R12``, ``4 qw qy = R02 - R20``,
      ``4 qw qz = R10 - R01``
    - ``4 qx² = 1 + R00 - R11 - R22``, ``4 qx qy = R01 + R10``, ``4 qx qz = R02 + R20``
    - ``4 qy² = 1 - R00 + R11 - R22``, ``4 qy qz = R12 + R21``
    - ``4 qz² = 1 - R00 - R11 + R22``.
    """
    m = _rotation("rotation", rotation)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    candidates = [1.0 + trace, 1.0 + 2 * m[0, 0] - trace, 1.0 + 2 * m[1, 1] - trace,
                  1.0 + 2 * m[2, 2] - trace]
    largest = int(np.argmax(candidates))
    root = math.sqrt(candidates[largest])  # 2 |q_largest|
    quarter = 0.5 / root  # 1 / (4 |q_largest|)
    if largest == 0:
        q = [0.5 * root, (m[2, 1] - m[1, 2]) * quarter, (m[0, 2] - m[2, 0]) * quarter,
             (m[1, 0] - m[0, 1]) * quarter]
    elif largest == 1:
        q = [(m[2, 1] - m[1, 2]) * quarter, 0.5 * root, (m[0, 1] + m[1, 0]) * quarter,
             (m[0, 2] + m[2, 0]) * quarter]
    elif largest == 2:
        q = [(m[0, 2] - m[2, 0]) * quarter, (m[0, 1] + m[1, 0]) * quarter, 0.5 * root,
             (m[1, 2] + m[2, 1]) * quarter]
    else:
        q = [(m[1, 0] - m[0, 1]) * quarter, (m[0, 2] + m[2, 0]) * quarter,
             (m[1, 2] + m[2, 1]) * quarter, 0.5 * root]
    unit = np.array(q, dtype=np.float64)
    unit /= np.linalg.norm(unit)
    return _canonical_quaternion(unit)


def _canonical_quaternion(q: Vector) -> tuple[float, float, float, float]:
    """Of ``q`` and ``-q``, the one with ``qw > 0`` (or, at ``qw == 0``, first non-zero > 0)."""
    for component in q:
        if component != 0:
            if component < 0:
                q = -q
            break
    qw, qx, qy, qz = (_plain(c) for c in q)
    return qw, qx, qy, qz


def unit_quaternion(qw: float, qx: float, qy: float, qz: float) -> Vector:
    """``(qw, qx, qy, qz)`` divided by its norm; refused unless the norm is about 1.

    A quaternion whose squared norm is within :data:`QUATERNION_NORM_SQUARED_TOLERANCE` of 1
    (rounded printouts) is normalized; any other (zero, or far from unit length: likely a
    misplaced column) raises :class:`PoseError`.
    """
    q = np.array([_finite_number(name, value, "a number") for name, value in
                  zip(("qw", "qx", "qy", "qz"), (qw, qx, qy, qz))])
    norm_squared = float(q @ q)
    if abs(norm_squared - 1.0) > QUATERNION_NORM_SQUARED_TOLERANCE:
        raise PoseError(
            f"the quaternion (qw, qx, qy, qz) = ({qw:g}, {qx:g}, {qy:g}, {qz:g}) is not a unit "
            f"quaternion: its norm is {math.sqrt(norm_squared):.6g} (qw²+qx²+qy²+qz² must be "
            f"within {QUATERNION_NORM_SQUARED_TOLERANCE:g} of 1; check the columns' order)"
        )
    return q / math.sqrt(norm_squared)


def rotation_from_quaternion(qw: float, qx: float, qy: float, qz: float) -> Matrix:
    """The rotation of a quaternion ``(qw, qx, qy, qz)`` (Hamilton, scalar first).

    ``p' = q p q*``, i.e. for a unit ``q``::

        [[1 - 2(y² + z²), 2(xy - wz),     2(xz + wy)],
         [2(xy + wz),     1 - 2(x² + z²), 2(yz - wx)],
         [2(xz - wy),     2(yz + wx),     1 - 2(x² + y²)]]

    ``q`` is normalized first (see :func:`unit_quaternion`); ``q`` and ``-q`` give the same
    matrix. Note the order: ROS messages, Eigen's ``coeffs()`` and SciPy list ``(x, y, z, w)``.
    """
    w, x, y, z = unit_quaternion(qw, qx, qy, qz)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def rvec_from_rotation(rotation: ArrayLike) -> Vector:
    """The Rodrigues vector ``theta · k`` of a rotation, ``theta`` in ``[0, pi]``, shape ``(3,)``.

    Through the quaternion (:func:`quaternion_from_rotation`, ``qw >= 0``):
    ``theta = 2 atan2(|q_xyz|, qw)`` and ``k = q_xyz / |q_xyz|``, which is accurate for tiny
    angles and for half turns alike (``arccos((trace - 1)/2)`` is not). It agrees with
    ``cv2.Rodrigues(R)[0]`` except at exactly ``theta = pi``, where ``k`` and ``-k`` are the
    same rotation and either may come back.
    """
    qw, qx, qy, qz = quaternion_from_rotation(rotation)
    vector = np.array([qx, qy, qz])
    sin_half = float(np.linalg.norm(vector))
    if sin_half == 0.0:
        return np.zeros(3)
    theta = 2.0 * math.atan2(sin_half, qw)
    return vector * (theta / sin_half) + 0.0


# --------------------------------------------------------------------------------------------
# Poses from OpenCV's rvec/tvec and from quaternions, and back
# --------------------------------------------------------------------------------------------


def pose_from_rvec(rvec: ArrayLike) -> Pose:
    """Pan, tilt, roll (degrees) of ``solvePnP``'s ``rvec``: ``camera_from_wall`` in OpenCV's
    frames (wall x right, y down, z into the wall; camera x right, y down, z forward).

    ``R = rotation_from_rvec(rvec)``, ``world_from_camera = C R^T C^T``, then
    :func:`pose_from_rotation`. Raises :class:`PoseError` for a non-finite
    vector or when the wall is behind the camera (``R[2,2] <= 0``).

    Hand-worked: a camera facing the wall squarely has ``R = I``, ``rvec = 0`` and pan = tilt
    = roll = 0. Turned left by 30 degrees about the vertical (pan = 30), it has
    ``world_from_camera = Rx(30°)``, so ``R = C^T Rx(30°)^T C``. ``Rx(30°)^T`` turns by -30°
    about the thesis X (up) axis, which is ``-y`` in OpenCV's frames, and a turn by -30° about
    ``-y`` is a turn by +30° about ``+y`` (down): ``rvec = (0, pi/6, 0) = (0, 0.5235988, 0)``,
    ``R = [[cos 30, 0, sin 30], [0, 1, 0], [-sin 30, 0, cos 30]]``. Check: the wall's normal
    ``R @ (0, 0, 1) = (0.5, 0, 0.866)`` leans to the camera's right (+x), as it must when the
    camera has turned to the left. Likewise tilt ``b`` gives ``rvec = (-b, 0, 0)`` and roll
    ``r`` gives ``rvec = (0, 0, -r)`` (radians).
    """
    return pose_from_rotation(world_from_camera_from_opencv(rotation_from_rvec(rvec)))


def rvec_from_pose(pan: float, tilt: float, roll: float = 0.0) -> Vector:
    """``solvePnP``'s ``rvec`` (OpenCV frames, ``camera_from_wall``) of a pose in degrees.

    The inverse of :func:`pose_from_rvec`: ``R = C^T W^T C`` with
    ``W = rotation_from_pose(pan, tilt, roll)``, then :func:`rvec_from_rotation`. Shape
    ``(3,)``; radians, length in ``[0, pi]``.
    """
    return rvec_from_rotation(opencv_from_world_from_camera(rotation_from_pose(pan, tilt, roll)))


def pose_from_quaternion(qw: float, qx: float, qy: float, qz: float) -> Pose:
    """Pan, tilt, roll (degrees) of a quaternion of ``camera_from_wall`` in OpenCV's frames.

    The same rotation as ``rvec`` (:func:`pose_from_rvec`), as a Hamilton quaternion, scalar
    first: for ROS, the wall's orientation in the camera's optical frame (x right, y down,
    z forward), i.e. tf's transform from the wall frame to the camera's optical frame. A
    tool that gives the camera's orientation in the wall frame gives the inverse: pass the
    conjugate ``(qw, -qx, -qy, -qz)``. ``q`` and ``-q`` give the same pose. Quaternions off
    unit length by rounding are normalized, others refused (:func:`unit_quaternion`).

    Hand-worked: pan = 30 is a turn by 30° about OpenCV's ``+y`` (see :func:`pose_from_rvec`),
    ``q = (cos 15°, 0, sin 15°, 0) = (0.9659258, 0, 0.2588190, 0)``.
    """
    camera_from_wall = rotation_from_quaternion(qw, qx, qy, qz)
    return pose_from_rotation(world_from_camera_from_opencv(camera_from_wall))


def quaternion_from_pose(
    pan: float, tilt: float, roll: float = 0.0
) -> tuple[float, float, float, float]:
    """The unit quaternion ``(qw, qx, qy, qz)`` of ``camera_from_wall`` (OpenCV frames) of a
    pose in degrees, with ``qw >= 0``; the inverse of :func:`pose_from_quaternion`."""
    world_from_camera = rotation_from_pose(pan, tilt, roll)
    return quaternion_from_rotation(opencv_from_world_from_camera(world_from_camera))


def distance_from_tvec(rvec: ArrayLike, tvec: ArrayLike) -> float:
    """The camera's distance to the wall along the wall's normal (the thesis's ``Zc``).

    ``solvePnP``'s ``tvec`` is the wall frame's origin (the board's first corner) in camera
    coordinates: ``p_camera = R @ p_wall + tvec`` with ``R = rotation_from_rvec(rvec)``, in
    the units of the object points given to ``solvePnP`` (a square's size, millimetres...).
    The camera centre (``p_camera = 0``) in the wall frame is ``c = -R^T tvec``; the wall is
    the plane ``z = 0`` of that frame, its z axis pointing into the wall, away from a camera
    in front of it, so the distance is ``-c_z = (R^T tvec)_z = R[:, 2] · tvec``.

    ``tvec_z`` alone is the depth of the wall origin along the optical axis: the distance
    only when the camera faces the wall squarely. Hand-worked: panned by 30 degrees
    (``rvec = (0, pi/6, 0)``) at 2 units from the wall, with the optical axis through the
    wall origin, the camera centre is ``c = (2 tan 30°, 0, -2)`` and
    ``tvec = -R c = (0, 0, 2 / cos 30°) = (0, 0, 2.3094)``; the distance is
    ``R[:, 2] · tvec = (sin 30°, 0, cos 30°) · (0, 0, 2.3094) = 2``.

    Raises :class:`PoseError` when the camera is not in front of the wall (distance <= 0:
    on the plane, or behind it, on the side its z axis points to). The orientation is not
    checked here: :func:`pose_from_rvec` refuses a wall behind the camera.
    """
    r = rotation_from_rvec(rvec)
    t = _vector3("tvec", tvec)
    distance = float(r[:, 2] @ t)
    if not distance > 0:
        raise PoseError(
            f"the camera is not in front of the wall: its distance along the wall's normal, "
            f"(R^T tvec)_z, is {distance:.6g} (must be > 0; the wall's z axis points into it)"
        )
    return distance
