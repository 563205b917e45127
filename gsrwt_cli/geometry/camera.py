"""The camera of one image: :class:`Intrinsics` (how rays become pixels) and :class:`Pose`
(where it looks), composed in :class:`View` with the wall's distance.

``View`` is the one object that carries what is known about how an image was taken; the
intrinsics hold ``fx, fy, cx, cy, skew``, the size and the lens (:mod:`.lens`), the pose pan,
tilt and roll. Pixel coordinates are ``(col, row)`` with row growing downward and pixel centres
at integers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .bounds import (  # noqa: F401  (the bounds of a view, named here too)
    DISTANCE_RANGE,
    MAX_FOCAL_PX,
    MAX_PRINCIPAL_POINT_PX,
    MAX_SIDE_PX,
    MIN_HORIZON_OFFSET_PX,
    VIEW_FIELDS,
)
from .checks import ViewError, as_number, check_range
from .gsrwt import (
    GsrwtParameters,
    Matrix,
    gsrwt_parameters,
    map_points,
)
from .lens import LENS_ALIASES, LENS_FIELDS, LENS_MODELS, Lens, LensDistortion  # noqa: F401
from .rotations import Pose


@dataclass(frozen=True)
class Intrinsics:
    """How a camera maps rays to pixels: ``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]``.

    OpenCV's pixel convention: ``(col, row)``, row down, pixel centres at
    integers; camera ``x`` right, ``y`` down. ``cx, cy`` default to the image centre
    ``((width-1)/2, (height-1)/2)`` when the size is known. ``lens``: a :class:`Lens`, or
    ``None`` for a pinhole. Values are checked as
    :class:`View` documents, raising :class:`ViewError` naming the field.
    """

    fx: float
    fy: float
    cx: float | None = None
    cy: float | None = None
    skew: float = 0.0
    width: int | None = None
    height: int | None = None
    lens: Lens | None = None

    def __post_init__(self) -> None:
        for name in ("fx", "fy", "cx", "cy", "skew", "width", "height"):
            object.__setattr__(self, name, as_number(name, getattr(self, name)))
        for name in ("fx", "fy"):
            check_range(name, getattr(self, name), 0, MAX_FOCAL_PX, " pixels")
        for name in ("cx", "cy", "skew"):
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
            check_range(name, value, 0, math.inf, "")
            if value > MAX_SIDE_PX:
                raise ViewError(
                    name, f"{name} must be at most {MAX_SIDE_PX} pixels, got {value:.15g}"
                )
            if value != int(value):
                raise ViewError(name, f"{name} must be a whole number of pixels, got {value:.15g}")
            object.__setattr__(self, name, int(value))
        if (self.cx is None) != (self.cy is None):
            missing = "cy" if self.cy is None else "cx"
            raise ViewError(missing, "cx and cy must be given together")
        if self.cx is None and self.width is not None and self.height is not None:
            object.__setattr__(self, "cx", (self.width - 1) / 2.0)
            object.__setattr__(self, "cy", (self.height - 1) / 2.0)
        if self.lens is not None and self.lens.is_identity:
            object.__setattr__(self, "lens", None)  # a pinhole, on the fast path

    @property
    def focal(self) -> float:
        """The focal length of the thesis's image frame, ``f = sqrt(fx fy)``."""
        return self.fx if self.fx == self.fy else math.sqrt(self.fx * self.fy)

    @property
    def has_principal_point(self) -> bool:
        return self.cx is not None

    def _principal_point(self) -> tuple[float, float]:
        if self.cx is None or self.cy is None:
            raise ValueError("the principal point is unknown: give cx, cy or width, height")
        return self.cx, self.cy

    def matrix(self) -> Matrix:
        """The camera matrix ``K`` (OpenCV's)."""
        cx, cy = self._principal_point()
        return np.array([[self.fx, self.skew, cx], [0.0, self.fy, cy], [0.0, 0.0, 1.0]])

    def distortion(self) -> LensDistortion | None:
        """This camera's lens as the pixel map applies it (OpenCV's model with this
        camera's matrix), None for a pinhole: the one place it is built."""
        if self.lens is None:
            return None
        camera_matrix = tuple(tuple(float(v) for v in row) for row in self.matrix())
        return LensDistortion(camera_matrix,
                              tuple(float(v) for v in self.lens.opencv_coefficients()),
                              self.lens.is_fisheye)

    def image_from_pixel(self) -> Matrix:
        """Pixel ``(col, row, 1)`` to the thesis's image frame ``(x up, y right, 1)`` at focal
        length :attr:`focal`: ``diag(f, f, 1) @ C @ K^-1`` (``C``:
        :data:`~gsrwt_cli.geometry.rotations.
        THESIS_FROM_OPENCV`).

        Written out so that a square-pixel camera gives exactly ``x = cy - row`` and
        ``y = col - cx``.
        """
        cx, cy = self._principal_point()
        f, fx, fy, s = self.focal, self.fx, self.fy, self.skew
        return np.array(
            [
                [0.0, -(f / fy), (f / fy) * cy],
                [f / fx, -(f / fx) * (s / fy), (f / fx) * (s / fy * cy - cx)],
                [0.0, 0.0, 1.0],
            ]
        )

    def pixel_from_image(self) -> Matrix:
        """Thesis image frame to pixel, the inverse of :meth:`image_from_pixel`."""
        cx, cy = self._principal_point()
        f, fx, fy, s = self.focal, self.fx, self.fy, self.skew
        return np.array(
            [
                [-(s / f), fx / f, cx],
                [-(fy / f), 0.0, cy],
                [0.0, 0.0, 1.0],
            ]
        )

    def ideal_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """``(N, 2)`` pixels of the image to where a pinhole with the same ``K`` puts their
        rays: the lens undone (the same pixels for a pinhole); NaN where no ray reaches
        (beyond where the lens model folds back)."""
        lens = self.distortion()
        pixels = np.asarray(pixels, dtype=np.float64)
        return pixels if lens is None else lens.undistort(pixels)

    def rays_from_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """``(N, 2)`` pixels to ``(N, 3)`` ray directions in the thesis's camera frame
        (``X`` up, ``Y`` right, ``Z`` forward), with ``Z = 1``: through the lens, if there is
        one (:meth:`ideal_pixels`), then ``K^-1`` (Eq. 3.1 read backwards)."""
        image = map_points(self.image_from_pixel(), self.ideal_pixels(pixels))
        return np.column_stack([image / self.focal, np.ones(len(image))])

    def pixels_from_rays(self, rays: np.ndarray) -> np.ndarray:
        """``(N, 3)`` ray directions in the thesis's camera frame to ``(N, 2)`` pixels, through
        ``K`` and then the lens, if there is one (rays with ``Z <= 0``, or beyond the lens's
        fold, come back as ``inf``/``nan``)."""
        rays = np.asarray(rays, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            image = self.focal * rays[:, :2] / rays[:, 2:3]
        ideal = map_points(self.pixel_from_image(), image)
        lens = self.distortion()
        return ideal if lens is None else lens.distort(ideal)


@dataclass(frozen=True, init=False)
class View:
    """The camera of one image: :class:`Intrinsics`, :class:`Pose` and the wall's distance.

    ``View(pan, tilt, focal, cx=None, cy=None, width=None, height=None, distance=None)``, or
    ``View(intrinsics=..., pose=..., distance=...)``.

    Convention
    ----------
    - ``pan``, ``tilt``: degrees, ``pan > 0`` turns left, ``tilt > 0`` tilts up (Sec. 3.2);
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

    intrinsics: Intrinsics
    pose: Pose
    distance: float | None
    parameters: GsrwtParameters = field(repr=False, compare=False)

    def __init__(
        self,
        pan: float | None = None,
        tilt: float | None = None,
        focal: float | None = None,
        cx: float | None = None,
        cy: float | None = None,
        width: int | None = None,
        height: int | None = None,
        distance: float | None = None,
        *,
        roll: float = 0.0,
        fx: float | None = None,
        fy: float | None = None,
        skew: float = 0.0,
        lens: Lens | None = None,
        intrinsics: Intrinsics | None = None,
        pose: Pose | None = None,
        parameters: GsrwtParameters | None = None,  # accepted from dataclasses.replace
    ) -> None:
        if pose is None:
            for name, value in (("pan", pan), ("tilt", tilt)):
                if value is None:
                    raise ViewError(name, f"{name} is required")
            pose = Pose(pan, tilt, roll)  # type: ignore[arg-type]
        if intrinsics is None:
            focal = as_number("focal", focal)
            if focal is not None:
                check_range("focal", focal, 0, MAX_FOCAL_PX, " pixels")
            if (fx is None) != (fy is None):
                missing = "fy" if fy is None else "fx"
                raise ViewError(missing, "fx and fy must be given together")
            if fx is None:
                if focal is None:
                    raise ViewError("focal", "focal is required")
                fx = fy = focal
            intrinsics = Intrinsics(fx, fy, cx, cy, skew, width, height, lens)
        distance = as_number("distance", distance)
        if distance is not None:
            check_range("distance", distance, *DISTANCE_RANGE, "")
        object.__setattr__(self, "intrinsics", intrinsics)
        object.__setattr__(self, "pose", pose)
        object.__setattr__(self, "distance", distance)
        parameters = gsrwt_parameters(pose.pan, pose.tilt, intrinsics.focal)
        if not parameters.is_frontal and parameters.shift < MIN_HORIZON_OFFSET_PX:
            name = "pan" if abs(pose.pan) >= abs(pose.tilt) else "tilt"
            raise ViewError(
                name,
                f"pan {pose.pan!r} and tilt {pose.tilt!r} with focal {intrinsics.focal:g} put "
                f"the horizon {parameters.shift:.2g} pixels from the principal point, less "
                f"than {MIN_HORIZON_OFFSET_PX:g} (the optical axis meets the wall beyond what "
                "the camera resolves)",
            )
        object.__setattr__(self, "parameters", parameters)

    pan = property(lambda self: self.pose.pan, doc="Pan in degrees (:class:`Pose`).")
    tilt = property(lambda self: self.pose.tilt, doc="Tilt in degrees (:class:`Pose`).")
    roll = property(lambda self: self.pose.roll, doc="Roll in degrees (:class:`Pose`).")
    focal = property(lambda self: self.intrinsics.focal, doc="Focal length in pixels.")
    cx = property(lambda self: self.intrinsics.cx, doc="Principal point column.")
    cy = property(lambda self: self.intrinsics.cy, doc="Principal point row.")
    width = property(lambda self: self.intrinsics.width, doc="Image width, if known.")
    height = property(lambda self: self.intrinsics.height, doc="Image height, if known.")

    def sidecar_values(self) -> dict[str, float | int | None]:
        """The view as a sidecar row gives it: every field of :data:`VIEW_FIELDS`, those at
        their defaults (no roll, square pixels, no skew) as None, so that they are left out."""
        intrinsics = self.intrinsics
        square = intrinsics.fx == intrinsics.fy
        return {
            "pan": self.pan, "tilt": self.tilt, "roll": self.roll or None,
            "focal": intrinsics.fx if square else None,
            "fx": None if square else intrinsics.fx, "fy": None if square else intrinsics.fy,
            "cx": self.cx, "cy": self.cy, "skew": intrinsics.skew or None,
            "width": self.width, "height": self.height, "distance": self.distance,
        }

    def with_size(self, width: int, height: int) -> View:
        """The same view with a known image size (the principal point defaults to its centre)."""
        return replace(self, intrinsics=replace(self.intrinsics, width=width, height=height))

    @property
    def has_principal_point(self) -> bool:
        """Whether pixel coordinates can be related to the image frame."""
        return self.intrinsics.has_principal_point

    def _principal_point(self) -> tuple[float, float]:
        return self.intrinsics._principal_point()

    def image_from_pixel(self) -> Matrix:
        """Pixel ``(col, row, 1)`` to the image frame of the camera at this pan and tilt
        *without* roll (:meth:`Intrinsics.image_from_pixel`, then the roll undone:
        the GS-RWT of a rolled view is the thesis's applied after turning the
        image frame by the roll). Ideal (undistorted) pixels when the camera has a lens."""
        if self.pose.roll == 0:
            return self.intrinsics.image_from_pixel()
        return self.pose.unrolled_from_rolled() @ self.intrinsics.image_from_pixel()

    def pixel_from_image(self) -> Matrix:
        """The inverse of :meth:`image_from_pixel`."""
        if self.pose.roll == 0:
            return self.intrinsics.pixel_from_image()
        return self.intrinsics.pixel_from_image() @ self.pose.unrolled_from_rolled().T

    def vanishing_point_pixels(self) -> np.ndarray:
        """The main vanishing point as ``(col, row)``; ``inf`` for the frontal view."""
        x, y = self.parameters.vanishing_point
        cx, cy = self._principal_point()
        intrinsics = self.intrinsics
        if intrinsics.fx == intrinsics.fy and intrinsics.skew == 0 and self.pose.roll == 0:
            return np.array([y + cx, cy - x])  # exact where infinite
        return map_points(self.pixel_from_image(), [[x, y]])[0]

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
