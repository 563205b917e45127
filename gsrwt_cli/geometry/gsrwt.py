"""The GS-RWT itself: transform matrices, point and line mapping, parameters from pan and tilt.

Pure mathematics: arrays in, arrays out, no I/O. Angles are degrees at every public edge.

Convention (thesis Sec. 3.2; docs/CONVENTIONS.md)
--------------------------------------------
- Image frame: ``x`` up, ``y`` right, origin at the principal point, pixels.
  Points are ``(N, 2)`` arrays of ``(x, y)``; homogeneous vectors are ``(x, y, 1)``.
- Camera frame: ``Z`` forward, ``X`` up, ``Y`` right. The wall is the plane ``Z = Zc`` of the
  camera frame at pan = tilt = 0.
- Pan ``alpha > 0`` turns the camera to the left, tilt ``beta > 0`` tilts it up.
- A 3x3 matrix ``r`` maps ``[u, v, 1] ~ r @ [x, y, 1]`` (Eq. 4.5); names say which frames
  a matrix maps between.

Over 400 lines: every transform and parameter of the thesis's Ch. 2 and 4, written out as
the thesis gives them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .bounds import FRONTAL_TOLERANCE_DEG

Matrix = NDArray[np.float64]
Points = NDArray[np.float64]


# --------------------------------------------------------------------------------------------
# The three transforms as homogeneous matrices (Ch. 2, Sec. 4.2)
# --------------------------------------------------------------------------------------------


def rwt_matrix() -> Matrix:
    """Reciprocal-Wedge Transform ``u = 1/x, v = y/x`` (Eq. 2.1, 2.3); it is its own inverse."""
    return np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def srwt_matrix(shift: float) -> Matrix:
    """Shifted RWT ``u = 1/(x+a), v = y/(x+a)`` with shift ``a`` in pixels (Eq. 2.5)."""
    return np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, float(shift)]])


def srwt_inverse(shift: float) -> Matrix:
    """Inverse of the S-RWT, ``[[-a, 0, 1], [0, 1, 0], [1, 0, 0]]`` (Eq. 2.5, 4.4)."""
    return np.array([[-float(shift), 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def rotation_matrix(angle_deg: float) -> Matrix:
    """``Rot(angle) = [[cos, -sin, 0], [sin, cos, 0], [0, 0, 1]]`` as used in Eq. 4.3."""
    angle = math.radians(angle_deg)
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def gsrwt_matrix(gamma_deg: float, shift: float, delta_deg: float) -> Matrix:
    """GS-RWT ``T(gamma, a, delta) = Rot(-gamma) @ T_SRWT(a) @ Rot(delta)`` (Eq. 4.3)."""
    return rotation_matrix(-gamma_deg) @ srwt_matrix(shift) @ rotation_matrix(delta_deg)


def gsrwt_inverse(gamma_deg: float, shift: float, delta_deg: float) -> Matrix:
    """Inverse GS-RWT ``Rot(-delta) @ T_SRWT(a)^-1 @ Rot(gamma)`` (Eq. 4.4)."""
    return rotation_matrix(-delta_deg) @ srwt_inverse(shift) @ rotation_matrix(gamma_deg)


# --------------------------------------------------------------------------------------------
# Mapping points and lines
# --------------------------------------------------------------------------------------------


def _as_matrix(matrix: ArrayLike) -> Matrix:
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape != (3, 3):
        raise ValueError(f"expected a 3x3 matrix, got shape {m.shape}")
    return m


def _as_points(points: ArrayLike) -> Points:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim == 1 and p.shape[0] == 2:
        p = p[np.newaxis, :]
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"expected points of shape (N, 2), got shape {p.shape}")
    return p


def map_points(dst_from_src: ArrayLike, points: ArrayLike) -> Points:
    """Map ``(N, 2)`` points through a 3x3 homogeneous transform (Eq. 4.5, 4.27).

    Points where the homogeneous ``w`` is 0 (the singular line of the transform, Sec. 4.7)
    come back as ``inf`` or ``nan``; no warning is raised.
    """
    matrix = _as_matrix(dst_from_src)
    pts = _as_points(points)
    homogeneous = pts @ matrix[:, :2].T + matrix[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        return homogeneous[:, :2] / homogeneous[:, 2:3]


def map_points_backward(dst_from_src: ArrayLike, points: ArrayLike) -> Points:
    """Map ``(N, 2)`` destination points back through the inverse of ``dst_from_src``."""
    return map_points(np.linalg.inv(_as_matrix(dst_from_src)), points)


def local_stretch(homography: ArrayLike, points: ArrayLike) -> NDArray[np.float64]:
    """Largest singular value of the homography's Jacobian at ``(N, 2)`` points.

    How many destination pixels one source pixel is stretched over, in the direction where
    that is largest: ``J = (H[:2, :2] - o h^T) / w`` with ``o`` the mapped point and
    ``h = H[2, :2]``.
    """
    h = _as_matrix(homography)
    homogeneous = _as_points(points) @ h[:, :2].T + h[:, 2]
    w = homogeneous[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        mapped = homogeneous[:, :2] / w[:, None]
        a = (h[0, 0] - mapped[:, 0] * h[2, 0]) / w
        b = (h[0, 1] - mapped[:, 0] * h[2, 1]) / w
        c = (h[1, 0] - mapped[:, 1] * h[2, 0]) / w
        d = (h[1, 1] - mapped[:, 1] * h[2, 1]) / w
    return largest_singular_value(a, b, c, d)


def largest_singular_value(a, b, c, d) -> NDArray[np.float64]:
    """The largest singular value of the 2x2 matrices ``[[a, b], [c, d]]`` (arrays)."""
    squares = a * a + b * b + c * c + d * d
    determinant = a * d - b * c
    with np.errstate(invalid="ignore"):
        return np.sqrt((squares + np.sqrt(np.maximum(squares**2 - 4 * determinant**2, 0))) / 2)


def homogeneous_w(dst_from_src: ArrayLike, points: ArrayLike) -> NDArray[np.float64]:
    """The homogeneous ``w`` of each mapped point; it is 0 on the transform's singular line."""
    matrix = _as_matrix(dst_from_src)
    return _as_points(points) @ matrix[2, :2] + matrix[2, 2]


def hough_matrix(dst_from_src: ArrayLike) -> Matrix:
    """Slope-intercept (Hough space) mapping of lines for ``[u, v, 1] ~ r @ [x, y, 1]``.

    Eq. 4.6 with the sign of ``r21`` corrected (the thesis prints ``+r21``): a line
    ``v = m_uv u + c_uv`` of the destination is the line ``y = m_xy x + c_xy`` of the source with
    ``[m_xy, c_xy, 1] ~ [[r11, r31, -r21], [r13, r33, -r23], [-r12, -r32, r22]] @ [m_uv, c_uv, 1]``.
    (The thesis prints ``+r21``, which mapped points disprove.)
    """
    r = _as_matrix(dst_from_src)
    return np.array(
        [
            [r[0, 0], r[2, 0], -r[1, 0]],
            [r[0, 2], r[2, 2], -r[1, 2]],
            [-r[0, 1], -r[2, 1], r[1, 1]],
        ]
    )


def map_lines_to_source(
    dst_from_src: ArrayLike, slopes: ArrayLike, intercepts: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Source-frame (slope, intercept) of destination lines ``v = m u + c`` (Eq. 4.6).

    Lines that become parallel to the source ``y`` axis (``x = const``) have no slope and come
    back as ``inf``/``nan``.
    """
    hough = hough_matrix(dst_from_src)
    m = np.asarray(slopes, dtype=np.float64)
    c = np.asarray(intercepts, dtype=np.float64)
    mapped = hough @ np.stack([m.ravel(), c.ravel(), np.ones(m.size)])
    with np.errstate(divide="ignore", invalid="ignore"):
        return (mapped[0] / mapped[2]).reshape(m.shape), (mapped[1] / mapped[2]).reshape(m.shape)


def map_lines_to_destination(
    dst_from_src: ArrayLike, slopes: ArrayLike, intercepts: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Destination-frame (slope, intercept) of source lines ``y = m x + c`` (Eq. 4.6 on T^-1)."""
    return map_lines_to_source(np.linalg.inv(_as_matrix(dst_from_src)), slopes, intercepts)


# --------------------------------------------------------------------------------------------
# Parameters from pan and tilt (Sec. 4.5)
# --------------------------------------------------------------------------------------------


def _check_angle(name: str, value_deg: float) -> float:
    value = float(value_deg)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number of degrees, got {value_deg}")
    if abs(value) >= 90.0:
        raise ValueError(
            f"{name} must be strictly between -90 and 90 degrees (the camera cannot see the "
            f"wall otherwise), got {value_deg:g}"
        )
    return value


def _check_focal(focal_px: float) -> float:
    focal = float(focal_px)
    if not math.isfinite(focal) or focal <= 0:
        raise ValueError(f"focal must be a positive number of pixels, got {focal_px}")
    return focal


def camera_from_world(pan_deg: float, tilt_deg: float) -> Matrix:
    """World-to-camera rotation after pan then tilt, ``Rot_Y(-beta) @ Rot_X(-alpha)`` (Eq. 3.8).

    ``[[cos b, sin a sin b, -cos a sin b], [0, cos a, sin a], [sin b, -sin a cos b, cos a cos b]]``;
    its rows are the camera's X (up), Y (right) and Z (forward) axes in the world frame.
    """
    alpha, beta = math.radians(pan_deg), math.radians(tilt_deg)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    return np.array([[cb, sa * sb, -ca * sb], [0.0, ca, sa], [sb, -sa * cb, ca * cb]])


def interception(pan_deg: float, tilt_deg: float) -> tuple[float, float]:
    """``(theta, cos theta)`` of a pose: the angle between image plane and wall in degrees,
    and its cosine ``cos alpha cos beta``, the foreshortening (Eq. 4.15; no focal length)."""
    alpha, beta = math.radians(pan_deg), math.radians(tilt_deg)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    foreshortening = ca * cb
    return math.degrees(math.atan2(math.sqrt(sa * sa + ca * ca * sb * sb), foreshortening)), (
        foreshortening)


@dataclass(frozen=True)
class GsrwtParameters:
    """The GS-RWT of one camera pose: everything Sec. 4.5 derives from pan, tilt and focal.

    Build it with :func:`gsrwt_parameters`. Angles are degrees, lengths pixels of the image
    frame (``x`` up, ``y`` right, origin at the principal point).
    """

    pan_deg: float
    tilt_deg: float
    focal: float

    @property
    def _trig(self) -> tuple[float, float, float, float]:
        alpha, beta = math.radians(self.pan_deg), math.radians(self.tilt_deg)
        return math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)

    @property
    def is_frontal(self) -> bool:
        """True when the camera faces the wall squarely (M = 0): the transform is the identity."""
        return abs(self.pan_deg) <= FRONTAL_TOLERANCE_DEG and (
            abs(self.tilt_deg) <= FRONTAL_TOLERANCE_DEG
        )

    @property
    def m(self) -> float:
        """``M = sin^2 alpha + cos^2 alpha sin^2 beta = sin^2 theta`` (Eq. 4.26)."""
        ca, sa, _, sb = self._trig
        return sa * sa + ca * ca * sb * sb

    @property
    def sin_theta(self) -> float:
        """``sin theta = sqrt(M)``, the ``r`` that normalizes Eq. 4.19-4.21."""
        return math.sqrt(self.m)

    @property
    def foreshortening(self) -> float:
        """``cos theta = cos alpha cos beta`` (Eq. 4.15): Table 5.2's Jacobian determinant."""
        ca, _, cb, _ = self._trig
        return ca * cb

    @property
    def theta_deg(self) -> float:
        """Interception angle of image plane and wall (Eq. 4.15, :func:`interception`)."""
        return interception(self.pan_deg, self.tilt_deg)[0]

    @property
    def delta_deg(self) -> float:
        """First rotation, the direction of ``L_x = (cos a sin b, -sin a)`` (Eq. 4.14, 4.19).

        ``delta = atan2(sin alpha, cos alpha sin beta)``; 0 for the frontal view.
        """
        if self.is_frontal:
            return 0.0
        ca, sa, _, sb = self._trig
        return math.degrees(math.atan2(sa, ca * sb))

    @property
    def gamma_deg(self) -> float:
        """Second rotation with Table 5.1's sign: ``gamma = atan2(-sin a cos b, sin b)`` (Eq. 4.18).

        The factor Eq. 4.21 calls ``Rot(-gamma)`` is ``rotation_matrix(gamma_deg)``: the thesis
        tabulates the angle with the sign opposite to the one its matrix uses.
        """
        if self.is_frontal:
            return 0.0
        _, sa, cb, sb = self._trig
        return math.degrees(math.atan2(-sa * cb, sb))

    @property
    def shift(self) -> float:
        """Shift ``a = f / tan theta`` in pixels (Eq. 4.16); ``inf`` for the frontal view."""
        if self.is_frontal:
            return math.inf
        return self.focal * self.foreshortening / self.sin_theta

    @property
    def vanishing_point(self) -> NDArray[np.float64]:
        """Main vanishing point ``(x, y) = a (cos delta, -sin delta)`` in the image frame.

        The foot of the perpendicular from the principal point to the vanishing line; ``inf``
        components for the frontal view. Table 5.1 prints it as ``(y, x)``.
        """
        if self.is_frontal:
            return np.array([math.inf, math.inf])
        delta = math.radians(self.delta_deg)
        return self.shift * np.array([math.cos(delta), -math.sin(delta)])

    @property
    def vanishing_line(self) -> NDArray[np.float64]:
        """Coefficients ``(A, B, C)`` of ``A x + B y + C = 0`` in the image frame (Eq. 4.28-4.30).

        ``(-cos a sin b, sin a, f cos a cos b)``, the wall normal of Eq. 4.29 with ``f``: it is
        positive at the principal point, so ``A x + B y + C > 0`` is the side where the wall is
        visible. For the frontal view the line is at infinity, ``(0, 0, 1)``.
        """
        ca, sa, cb, sb = self._trig
        if self.is_frontal:
            return np.array([0.0, 0.0, 1.0])
        return np.array([-ca * sb, sa, self.focal * ca * cb])

    def canonical_scale(self, distance: float = 1.0) -> float:
        """Scale of the canonical view, ``-sin theta / Zc`` (Eq. 4.25; negative: a 180-degree turn).

        ``u/w = scale * X + t_u`` and ``v/w = scale * Y + t_v`` for the wall point
        ``(X, Y, Zc)``, with ``Zc = distance``.
        """
        return -self.sin_theta / float(distance)

    @property
    def canonical_offsets(self) -> tuple[float, float]:
        """Shifts ``(t_u, t_v)`` of the canonical view (Eq. 4.25).

        ``t_u = -cos a sin b cos b / sin theta``, ``t_v = sin a cos a cos^2 b / sin theta``;
        ``(0, 0)`` for the frontal view.
        """
        if self.is_frontal:
            return 0.0, 0.0
        ca, sa, cb, sb = self._trig
        r = self.sin_theta
        return -ca * sb * cb / r, sa * ca * cb * cb / r

    @cached_property
    def factors(self) -> tuple[Matrix, Matrix, Matrix]:
        """``(Rot(delta), T_SRWT(a), Rot(-gamma))`` with the thesis's scaling (Eq. 4.19-4.21).

        ``T_SRWT`` here is ``[[0, 0, f/r], [0, 1, 0], [1, 0, -f cos a cos b / r]]`` with
        ``r = sin theta``: Eq. 4.20 scales ``u`` by ``f/r`` and its singular line sits at
        ``x = +a``. ``Rot(-gamma)`` equals ``rotation_matrix(gamma_deg)`` (see
        :attr:`gamma_deg`). All three are the identity for the frontal view.
        """
        if self.is_frontal:
            return np.eye(3), np.eye(3), np.eye(3)
        ca, sa, cb, sb = self._trig
        r = self.sin_theta
        f = self.focal
        rot_delta = np.array([[ca * sb / r, -sa / r, 0.0], [sa / r, ca * sb / r, 0.0], [0, 0, 1]])
        srwt = np.array([[0.0, 0.0, f / r], [0.0, 1.0, 0.0], [1.0, 0.0, -f * ca * cb / r]])
        rot_minus_gamma = np.array(
            [[sb / r, sa * cb / r, 0.0], [-sa * cb / r, sb / r, 0.0], [0.0, 0.0, 1.0]]
        )
        return rot_delta, srwt, rot_minus_gamma

    @cached_property
    def matrix(self) -> Matrix:
        """The composite ``T_GS-RWT(alpha, beta)`` of Eq. 4.22 / 4.26, gsrwt from image frame.

        Written out entry by entry as the thesis prints it (``M`` and ``sqrt(M)`` denominators);
        the identity for the frontal view.
        """
        if self.is_frontal:
            return np.eye(3)
        ca, sa, cb, sb = self._trig
        m, r, f = self.m, self.sin_theta, self.focal
        return np.array(
            [
                [sa * sa * cb / m, sa * ca * sb * cb / m, f * sb / m],
                [sa * sb / m, ca * sb * sb / m, -f * sa * cb / m],
                [ca * sb / r, -sa / r, -f * ca * cb / r],
            ]
        )

    def canonical_from_image(self) -> Matrix:
        """The GS-RWT scaled by ``f / sin theta``: canonical coordinates at frontal resolution.

        At frontal resolution: ``(U, V) = (f / sin theta) (u/w, v/w)``, so that one unit is ``Zc/f``
        wall units, what a camera at the same place facing the wall squarely would see with the
        same focal length (up to the 180-degree turn and the shift of Eq. 4.25).
        """
        if self.is_frontal:
            return np.diag([-1.0, -1.0, 1.0])
        scale = self.focal / self.sin_theta
        return np.diag([scale, scale, 1.0]) @ self.matrix


def gsrwt_parameters(pan_deg: float, tilt_deg: float, focal: float) -> GsrwtParameters:
    """GS-RWT parameters of a camera at ``pan``, ``tilt`` (degrees) with focal length ``focal``.

    Raises ``ValueError`` naming the argument when an angle is not finite or ``|angle| >= 90``
    (the camera cannot see the wall) or the focal length is not a positive finite number.
    """
    return GsrwtParameters(
        pan_deg=_check_angle("pan", pan_deg),
        tilt_deg=_check_angle("tilt", tilt_deg),
        focal=_check_focal(focal),
    )


def pan_tilt_from_gsrwt(delta_deg: float, shift: float, focal: float) -> tuple[float, float]:
    """Pan and tilt (degrees) of the camera whose GS-RWT has rotation ``delta`` and shift ``a``.

    Inverts Eq. 4.14-4.16: ``tan theta = f / a``, ``sin alpha = sin theta sin delta`` and
    ``tan beta = sin theta cos delta / cos theta``. ``gamma`` follows from these (Eq. 4.18), so
    it is not needed. An infinite shift is the frontal view.
    """
    focal = _check_focal(focal)
    shift = float(shift)
    if math.isnan(shift) or shift <= 0:
        raise ValueError(f"a must be a positive number of pixels, got {shift}")
    if not math.isfinite(float(delta_deg)):
        raise ValueError(f"delta must be a finite number of degrees, got {delta_deg}")
    theta = math.atan2(focal, shift)
    delta = math.radians(delta_deg)
    pan = math.asin(math.sin(theta) * math.sin(delta))
    tilt = math.atan2(math.sin(theta) * math.cos(delta), math.cos(theta))
    return math.degrees(pan), math.degrees(tilt)


def _elementwise(function: Callable[[float, float], float], first: NDArray[np.float64],
                 second: NDArray[np.float64]) -> NDArray[np.float64]:
    """``function`` (of :mod:`math`) of each pair: numpy's own ``arctan2`` and ``hypot`` differ
    from the C library's in the last bit for some 5 % of arguments, and these arrays must be
    exactly what the per-view properties give."""
    return np.fromiter(map(function, first.tolist(), second.tolist()), dtype=np.float64,
                       count=first.size).reshape(first.shape)


def parameter_arrays(pan_deg: ArrayLike, tilt_deg: ArrayLike,
                     focal: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """:class:`GsrwtParameters` of many poses at once (Sec. 4.5), bit for bit as its properties
    compute them: ``theta_deg``, ``delta_deg``, ``gamma_deg``, ``shift`` (``a``, Eq. 4.16;
    ``inf`` when frontal), ``foreshortening`` (Eq. 4.15), the vanishing point ``vp_x, vp_y``
    (image frame, ``inf`` when frontal), the vanishing line ``line_a, line_b, line_c``
    (Eq. 4.28-4.30) and ``frontal``. The poses must be valid (``|pan|, |tilt| < 90``,
    ``focal > 0``): nothing is checked here.
    """
    pan, tilt = np.asarray(pan_deg, dtype=np.float64), np.asarray(tilt_deg, dtype=np.float64)
    focal = np.asarray(focal, dtype=np.float64)
    alpha, beta = np.radians(pan), np.radians(tilt)
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    frontal = (np.abs(pan) <= FRONTAL_TOLERANCE_DEG) & (np.abs(tilt) <= FRONTAL_TOLERANCE_DEG)
    foreshortening = ca * cb
    sin_theta = np.sqrt(sa * sa + ca * ca * sb * sb)
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(frontal, np.inf, focal * foreshortening / sin_theta)
        delta_deg = np.where(frontal, 0.0, np.degrees(_elementwise(math.atan2, sa, ca * sb)))
        delta = np.radians(delta_deg)
        vp_x = np.where(frontal, np.inf, shift * np.cos(delta))
        vp_y = np.where(frontal, np.inf, shift * -np.sin(delta))
    return {
        "theta_deg": np.degrees(_elementwise(math.atan2, sin_theta, foreshortening)),
        "delta_deg": delta_deg,
        "gamma_deg": np.where(frontal, 0.0,
                              np.degrees(_elementwise(math.atan2, -sa * cb, sb))),
        "shift": shift,
        "foreshortening": foreshortening,
        "vp_x": vp_x,
        "vp_y": vp_y,
        "line_a": np.where(frontal, 0.0, -ca * sb),
        "line_b": np.where(frontal, 0.0, sa),
        "line_c": np.where(frontal, 1.0, focal * ca * cb),
        "frontal": frontal,
    }
