"""The camera of one image: intrinsics (focal length, principal point, size) and pose (pan, tilt).

``View`` is the one object that carries what is known about how an image was taken; it grows
with the camera model (roll, separate fx/fy, lens distortion) without changing its callers.
Pixel coordinates are ``(col, row)`` with row growing downward and pixel centres at integers.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, replace

import numpy as np

from .geometry import GsrwtParameters, Matrix, gsrwt_parameters
from .messages import quote


class ViewError(ValueError):
    """An invalid camera parameter; ``field`` names the offending parameter."""

    def __init__(self, field_name: str, message: str) -> None:
        super().__init__(message)
        self.field = field_name


#: Focal lengths (fx, fy) must be below this many pixels. The longest real ones are ~1e5-1e6
#: (a 2000 mm lens on 2 um pixels is 1e6); the bound keeps ``f**2`` and ``f / sin(theta)``
#: far from floating-point limits.
MAX_FOCAL_PX = 1e7
#: Image width and height: whole numbers of pixels, at most this many each.
MAX_SIDE_PX = 1_000_000
#: The principal point may lie outside the image (a crop), but within this many pixels of 0.
MAX_PRINCIPAL_POINT_PX = 1e7
#: ``distance`` (``Zc``, in the user's unit) must lie strictly between these. Twelve orders of
#: magnitude either way of any unit (nanometres to terametres, in metres): no wall needs more,
#: and ``Zc``, ``1/Zc`` and their products with focal lengths and scales stay finite.
DISTANCE_RANGE = (1e-12, 1e12)
#: The vanishing line (the horizon of the wall) must pass at least this many pixels from the
#: principal point: ``a = f cos(theta) / sin(theta) >= 0.5`` (Eq. 4.16). Closer, the pixel at
#: the principal point sees the horizon, so the point where the optical axis meets the wall
#: (which anchors the output frame, Fig. 5.7) is beyond what the camera resolves, and the
#: pixel homography, normalized at the principal point, divides by ``w ~ a`` that rounding
#: errors of size ``1e-16 (|cx| + |cy|)`` swamp (pan = tilt = 89.9999999 at f = 300 has
#: ``a = 9e-16`` px). Non-frontal views only.
MIN_HORIZON_OFFSET_PX = 0.5


def _as_number(name: str, value: object) -> float | int | None:
    """``value`` as a finite Python number (numpy scalars and big integers too), else ViewError."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ViewError(name, f"{name} must be a number, got {quote(value)}")
    given = value
    try:
        if type(value) not in (int, float):  # numpy scalars, Fractions: plain Python numbers
            value = int(value) if isinstance(value, numbers.Integral) else float(value)
        finite = math.isfinite(value)
    except OverflowError:  # an int or a Fraction too large for a float
        finite = False
    if not finite:
        raise ViewError(name, f"{name} must be a finite number, got {quote(given)}")
    return value


def _check_range(name: str, value: float, low: float, high: float, unit: str) -> None:
    """``low < value < high``; ``low`` 0 reads "positive"."""
    if value <= low:
        what = "positive" if low == 0 else f"above {low:g}{unit}"
        raise ViewError(name, f"{name} must be {what}, got {value:.15g}")
    if value >= high:
        raise ViewError(name, f"{name} must be below {high:g}{unit}, got {value:.15g}")


@dataclass(frozen=True)
class View:
    """Camera intrinsics and pose for one image.

    Convention
    ----------
    - ``pan``, ``tilt``: degrees, ``pan > 0`` turns left, ``tilt > 0`` tilts up (spec section 1);
      strictly between -90 and 90, and the horizon at least :data:`MIN_HORIZON_OFFSET_PX`
      from the principal point.
    - ``focal``: focal length in pixels, ``0 < focal <`` :data:`MAX_FOCAL_PX`.
    - ``cx``, ``cy``: principal point in pixels; default ``((width-1)/2, (height-1)/2)``;
      ``|cx|, |cy| <`` :data:`MAX_PRINCIPAL_POINT_PX`.
    - ``width``, ``height``: image size in pixels, when known; whole, 1 to :data:`MAX_SIDE_PX`.
    - ``distance``: ``Zc``, camera to wall along the wall's normal, in the user's unit, within
      :data:`DISTANCE_RANGE`.

    Any real number is accepted (numpy scalars included) and stored as a Python number;
    anything else, or a value out of range, raises :class:`ViewError` naming the field.
    """

    pan: float
    tilt: float
    focal: float
    cx: float | None = None
    cy: float | None = None
    width: int | None = None
    height: int | None = None
    distance: float | None = None
    parameters: GsrwtParameters = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("pan", "tilt", "focal", "cx", "cy", "width", "height", "distance"):
            object.__setattr__(self, name, _as_number(name, getattr(self, name)))
        for name in ("pan", "tilt", "focal"):
            if getattr(self, name) is None:
                raise ViewError(name, f"{name} is required")
        _check_range("focal", self.focal, 0, MAX_FOCAL_PX, " pixels")
        for name in ("cx", "cy"):
            value = getattr(self, name)
            if value is not None and abs(value) >= MAX_PRINCIPAL_POINT_PX:
                raise ViewError(
                    name, f"{name} must be within {MAX_PRINCIPAL_POINT_PX:g} pixels of 0, "
                    f"got {value:.15g}"
                )
        for name in ("width", "height"):
            value = getattr(self, name)
            if value is None:
                continue
            _check_range(name, value, 0, math.inf, "")
            if value > MAX_SIDE_PX:
                raise ViewError(
                    name, f"{name} must be at most {MAX_SIDE_PX} pixels, got {value:.15g}"
                )
            if value != int(value):
                raise ViewError(name, f"{name} must be a whole number of pixels, got {value:.15g}")
            object.__setattr__(self, name, int(value))
        if self.distance is not None:
            _check_range("distance", self.distance, *DISTANCE_RANGE, "")
        if (self.cx is None) != (self.cy is None):
            missing = "cy" if self.cy is None else "cx"
            raise ViewError(missing, "cx and cy must be given together")
        if self.cx is None and self.width is not None and self.height is not None:
            object.__setattr__(self, "cx", (self.width - 1) / 2.0)
            object.__setattr__(self, "cy", (self.height - 1) / 2.0)
        for name in ("pan", "tilt"):
            value = getattr(self, name)
            if abs(value) >= 90.0:
                raise ViewError(
                    name,
                    f"{name} must be strictly between -90 and 90 degrees (the camera cannot see "
                    f"the wall otherwise), got {value:g}",
                )
        parameters = gsrwt_parameters(self.pan, self.tilt, self.focal)
        if not parameters.is_frontal and parameters.shift < MIN_HORIZON_OFFSET_PX:
            name = "pan" if abs(self.pan) >= abs(self.tilt) else "tilt"
            raise ViewError(
                name,
                f"pan {self.pan!r} and tilt {self.tilt!r} with focal {self.focal:g} put the "
                f"horizon {parameters.shift:.2g} pixels from the principal point, less than "
                f"{MIN_HORIZON_OFFSET_PX:g} (the optical axis meets the wall beyond what the "
                "camera resolves)",
            )
        object.__setattr__(self, "parameters", parameters)

    def with_size(self, width: int, height: int) -> View:
        """The same view with a known image size (the principal point defaults to its centre)."""
        return replace(self, width=width, height=height)

    @property
    def has_principal_point(self) -> bool:
        """Whether pixel coordinates can be related to the image frame."""
        return self.cx is not None

    def _principal_point(self) -> tuple[float, float]:
        if self.cx is None or self.cy is None:
            raise ValueError("the principal point is unknown: give cx, cy or width, height")
        return self.cx, self.cy

    def image_from_pixel(self) -> Matrix:
        """``[x, y, 1] = A @ [col, row, 1]`` with ``x = cy - row`` and ``y = col - cx``."""
        cx, cy = self._principal_point()
        return np.array([[0.0, -1.0, cy], [1.0, 0.0, -cx], [0.0, 0.0, 1.0]])

    def pixel_from_image(self) -> Matrix:
        """``[col, row, 1] = A @ [x, y, 1]`` with ``col = y + cx`` and ``row = cy - x``."""
        cx, cy = self._principal_point()
        return np.array([[0.0, 1.0, cx], [-1.0, 0.0, cy], [0.0, 0.0, 1.0]])

    def vanishing_point_pixels(self) -> np.ndarray:
        """The main vanishing point as ``(col, row)``; ``inf`` for the frontal view."""
        x, y = self.parameters.vanishing_point
        cx, cy = self._principal_point()
        return np.array([y + cx, cy - x])

    def vanishing_line_pixels(self) -> np.ndarray | None:
        """``(a, b, c)`` with ``a col + b row + c = 0`` and ``a^2 + b^2 = 1`` (Eq. 4.28-4.30).

        ``a col + b row + c > 0`` on the side where the wall is visible (the principal point's
        side). ``None`` for the frontal view, whose vanishing line is at infinity.
        """
        if self.parameters.is_frontal:
            return None
        line = self.image_from_pixel().T @ self.parameters.vanishing_line
        return line / math.hypot(line[0], line[1])

    def horizon_in_image(self) -> bool | None:
        """Whether the vanishing line crosses or touches the image; ``None`` if the size is unknown.

        The image is the rectangle of pixel edges, ``[-0.5, width - 0.5] x [-0.5, height - 0.5]``.
        """
        if self.width is None or self.height is None:
            return None
        line = self.vanishing_line_pixels()
        if line is None:
            return False
        cols = np.array([-0.5, self.width - 0.5, self.width - 0.5, -0.5])
        rows = np.array([-0.5, -0.5, self.height - 0.5, self.height - 0.5])
        return bool(np.any(line[0] * cols + line[1] * rows + line[2] <= 0))
