"""The camera of one image: intrinsics (focal length, principal point, size) and pose (pan, tilt).

``View`` is the one object that carries what is known about how an image was taken; it grows
with the camera model (roll, separate fx/fy, lens distortion) without changing its callers.
Pixel coordinates are ``(col, row)`` with row growing downward and pixel centres at integers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .geometry import GsrwtParameters, Matrix, gsrwt_parameters


class ViewError(ValueError):
    """An invalid camera parameter; ``field`` names the offending parameter."""

    def __init__(self, field_name: str, message: str) -> None:
        super().__init__(message)
        self.field = field_name


def _finite(name: str, value: float | None, *, positive: bool = False) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ViewError(name, f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ViewError(name, f"{name} must be a finite number, got {value}")
    if positive and value <= 0:
        raise ViewError(name, f"{name} must be positive, got {value:g}")


@dataclass(frozen=True)
class View:
    """Camera intrinsics and pose for one image.

    Convention
    ----------
    - ``pan``, ``tilt``: degrees, ``pan > 0`` turns left, ``tilt > 0`` tilts up (spec section 1).
    - ``focal``: focal length in pixels.
    - ``cx``, ``cy``: principal point in pixels; default ``((width-1)/2, (height-1)/2)``.
    - ``width``, ``height``: image size in pixels, when known.
    - ``distance``: ``Zc``, camera to wall along the wall's normal, in the user's unit.
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
        for name in ("pan", "tilt", "cx", "cy"):
            _finite(name, getattr(self, name))
        for name in ("focal", "width", "height", "distance"):
            _finite(name, getattr(self, name), positive=True)
        for name in ("width", "height"):
            value = getattr(self, name)
            if value is not None and value != int(value):
                raise ViewError(name, f"{name} must be a whole number of pixels, got {value:g}")
            if value is not None:
                object.__setattr__(self, name, int(value))
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
        object.__setattr__(
            self, "parameters", gsrwt_parameters(self.pan, self.tilt, self.focal)
        )

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
