"""A camera's lens: the model as calibration files name it (:class:`Lens`) and its numerics
as OpenCV applies it (:class:`LensDistortion`: distort, undistort, the dense maps of a warp).

A :class:`Lens` is what an :class:`~gsrwt_cli.geometry.camera.Intrinsics` carries;
``Intrinsics.distortion()`` pairs it with the camera matrix into a :class:`LensDistortion`,
the one place the two meet. OpenCV is imported only when a lens is evaluated, so a pinhole
camera (and start-up) never loads it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..base.messages import quote
from .checks import ViewError, as_number
from .gsrwt import map_points

#: OpenCV's iterative inverse: at most 50 iterations, or a step under 1e-12
#: (``(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)``, written out so that this
#: module loads without OpenCV).
_POINT_CRITERIA = (3, 50, 1e-12)
#: A pixel's ideal position is taken when the lens puts it back within this many pixels.
_INVERSE_TOLERANCE_PX = 0.01
#: OpenCV's inverse of a radial model is bisected again where it is further off than this.
_RADIAL_TOLERANCE_PX = 1e-6
#: Where output pixels have no source: far outside any image, sampled as the fill.
NO_SOURCE = -1e6


#: Lens models (docs/CONVENTIONS.md, "Lens distortion") and the coefficients each takes, in
#: OpenCV's order.
LENS_MODELS = {
    "plumb_bob": ("k1", "k2", "p1", "p2", "k3"),
    "rational_polynomial": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6",
                            "s1", "s2", "s3", "s4", "tau_x", "tau_y"),
    "equidistant": ("k1", "k2", "k3", "k4"),
}
#: Other names people use for them (ROS's ``radtan``, OpenCV's ``fisheye``).
LENS_ALIASES = {"radtan": "plumb_bob", "fisheye": "equidistant"}
#: Every coefficient any model takes (the sidecar columns of a lens).
LENS_FIELDS = LENS_MODELS["rational_polynomial"]


@dataclass(frozen=True)
class Lens:
    """A lens distortion model as OpenCV applies it (docs/CONVENTIONS.md).

    ``model``: ``plumb_bob`` (k1, k2, p1, p2, k3), ``rational_polynomial`` (k1..k6, p1, p2,
    thin prism s1..s4, tilt tau_x, tau_y) or ``equidistant`` (the fisheye model of
    ``cv2.fisheye``, k1..k4); ``coefficients`` by name, absent ones 0.
    """

    model: str
    coefficients: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        model = LENS_ALIASES.get(self.model, self.model)
        if model not in LENS_MODELS:
            raise ViewError("distortion_model", f"unknown lens model {quote(self.model)}; use "
                            f"one of {', '.join(LENS_MODELS)}")
        object.__setattr__(self, "model", model)
        allowed = LENS_MODELS[model]
        checked = []
        for name, value in dict(self.coefficients).items():
            if name not in allowed:
                raise ViewError(name, f"the {model} model has no coefficient {name}")
            number = as_number(name, value)
            if abs(number) >= 1e6:
                raise ViewError(name, f"{name} must be within 1e6 of 0, got {number:.15g}")
            checked.append((name, number))
        checked.sort(key=lambda coefficient: allowed.index(coefficient[0]))
        object.__setattr__(self, "coefficients", tuple(checked))

    @property
    def is_fisheye(self) -> bool:
        return self.model == "equidistant"

    def value(self, name: str) -> float:
        return dict(self.coefficients).get(name, 0.0)

    @property
    def is_identity(self) -> bool:
        """No distortion at all (every coefficient 0): a pinhole."""
        return all(value == 0 for _, value in self.coefficients)

    def opencv_names(self) -> tuple[str, ...]:
        """The coefficients of the vector OpenCV's functions take, in its order: 4 for the
        fisheye model, 5 for plumb_bob, 8 or (with prism or tilt terms) 14 for rational."""
        names = LENS_MODELS[self.model]
        if self.model == "rational_polynomial" and not any(
            self.value(name) for name in names[8:]
        ):
            names = names[:8]
        return names

    def opencv_coefficients(self) -> np.ndarray:
        """The vector OpenCV's functions take (:meth:`opencv_names`)."""
        return np.array([self.value(name) for name in self.opencv_names()], dtype=np.float64)



def monotonic_radius(coefficients: tuple[float, ...], fisheye: bool = False) -> float:
    """How far from the optical axis a lens model is one-to-one: the normalized radius
    ``r = tan(angle off axis)`` of ideal rays below which the distorted radius ``r_d(r)``
    grows with ``r``; ``inf`` if it always does.

    Beyond that radius the model folds back (``r_d`` shrinks again, or passes a pole): its
    pixels repeat, mirrored, what rays nearer the axis show, and have no ray of their own.
    ``coefficients``: OpenCV's vector. Plumb-bob and rational models:
    ``r_d = r N(r^2) / D(r^2)`` with ``N = 1 + k1 s + k2 s^2 + k3 s^3`` and ``D = 1 + k4 s +
    k5 s^2 + k6 s^3``; ``d r_d / dr`` has the sign of ``(N + 2 s N') D - 2 s N D'``, and the
    radius is the square root of the smallest positive root of that polynomial or of ``D``
    (tangential, prism and tilt terms, which are not radial, are left out). Fisheye model:
    ``r_d = theta (1 + k1 theta^2 + ... + k4 theta^8)`` with ``theta = atan r``; the radius is
    ``tan`` of the smallest root of ``d r_d / d theta`` below 90 degrees.
    """
    from numpy.polynomial import Polynomial

    def smallest_positive_root(*polynomials: Polynomial) -> float:
        roots = np.concatenate([polynomial.trim().roots() for polynomial in polynomials])
        real = roots.real[(np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots.real)))
                          & (roots.real > 0)]
        return float(real.min()) if len(real) else math.inf

    d = tuple(coefficients) + (0.0,) * 8
    if fisheye:
        k1, k2, k3, k4 = d[:4]
        slope = Polynomial([1.0, 3 * k1, 5 * k2, 7 * k3, 9 * k4])  # d r_d / d theta, t = theta^2
        theta = math.sqrt(smallest_positive_root(slope))
        return math.tan(theta) if theta < math.pi / 2 else math.inf
    k1, k2, _, _, k3, k4, k5, k6 = d[:8]
    numerator, denominator = Polynomial([1.0, k1, k2, k3]), Polynomial([1.0, k4, k5, k6])
    s = Polynomial([0.0, 1.0])
    slope = ((numerator + 2 * s * numerator.deriv()) * denominator
             - 2 * s * numerator * denominator.deriv())
    return math.sqrt(smallest_positive_root(slope, denominator))


def _radial_distortion(coefficients: tuple[float, ...], fisheye: bool,
                       theta: np.ndarray) -> np.ndarray:
    """``r_d`` of rays ``theta`` radians off the axis (the radial part of the model)."""
    d = tuple(coefficients) + (0.0,) * 8
    t = theta * theta
    if fisheye:
        k1, k2, k3, k4 = d[:4]
        return theta * (1 + t * (k1 + t * (k2 + t * (k3 + t * k4))))
    k1, k2, _, _, k3, k4, k5, k6 = d[:8]
    s = np.tan(theta) ** 2
    return np.tan(theta) * (1 + s * (k1 + s * (k2 + s * k3))) / (1 + s * (k4 + s * (k5 + s * k6)))


@dataclass(frozen=True)
class LensDistortion:
    """The input camera's lens as OpenCV models it: ``camera_matrix`` (K, skew included),
    ``coefficients`` (OpenCV's vector) and whether it is the ``fisheye`` (equidistant) model.

    Ideal pixels are those of the same K without distortion (a pinhole); the maps go from
    ideal to distorted (the lens, :meth:`distort`) and back (:meth:`undistort`, iterated).
    """

    camera_matrix: tuple[tuple[float, float, float], ...]
    coefficients: tuple[float, ...]
    fisheye: bool = False

    @functools.cached_property
    def limit(self) -> float:
        """The normalized radius of ideal rays up to which the model is one-to-one
        (:func:`monotonic_radius`): like the horizon, nothing beyond it is sampled or framed."""
        return monotonic_radius(self.coefficients, self.fisheye)

    @property
    def limit_px(self) -> float:
        """:attr:`limit` in ideal pixels from the principal point (along the larger focal)."""
        return self.limit * max(self._k[0, 0], self._k[1, 1])

    @property
    def is_radial(self) -> bool:
        """Whether the model only moves points along their radius (no tangential, prism or
        tilt terms): its inverse is then one monotonic function of the radius."""
        return self.fisheye or not any(v for i, v in enumerate(self.coefficients)
                                       if i in (2, 3) or i >= 8)

    def within(self, ideal: np.ndarray) -> np.ndarray:
        """Which ``(N, 2)`` ideal pixels lie within :attr:`limit` (False for NaN)."""
        if math.isinf(self.limit):
            return np.all(np.isfinite(ideal), axis=1)
        normalized = self._normalized(np.asarray(ideal, dtype=np.float64))
        with np.errstate(invalid="ignore"):
            return np.hypot(normalized[:, 0], normalized[:, 1]) < self.limit

    @property
    def _k(self) -> np.ndarray:
        return np.array(self.camera_matrix, dtype=np.float64)

    @property
    def _d(self) -> np.ndarray:
        return np.array(self.coefficients, dtype=np.float64)

    def _normalized(self, pixels: np.ndarray) -> np.ndarray:
        return map_points(np.linalg.inv(self._k), pixels)

    def _pixels(self, normalized: np.ndarray) -> np.ndarray:
        return map_points(self._k, normalized)

    def distort(self, ideal: np.ndarray) -> np.ndarray:
        """``(N, 2)`` ideal pixels to the pixels the lens puts them on; NaN beyond
        :attr:`limit`, where the model folds back and no pixel is the ray's own."""
        import cv2

        ideal = np.asarray(ideal, dtype=np.float64)
        rays = np.column_stack([self._normalized(ideal), np.ones(len(ideal))])[:, None, :]
        zero = np.zeros(3)
        if self.fisheye:
            distorted, _ = cv2.fisheye.projectPoints(rays, zero, zero, np.eye(3), self._d)
        else:
            distorted, _ = cv2.projectPoints(rays, zero, zero, np.eye(3), self._d)
        pixels = self._pixels(distorted.reshape(-1, 2))
        pixels[~self.within(ideal)] = np.nan
        return pixels

    def undistort(self, pixels: np.ndarray) -> np.ndarray:
        """``(N, 2)`` pixels of the image to ideal pixels within :attr:`limit`; NaN for pixels
        no such ray reaches (beyond where the model folds back).

        OpenCV's iterative inverse first; an answer is kept when the lens puts it back on the
        pixel (:data:`_INVERSE_TOLERANCE_PX`). A radial model's answers further off than
        :data:`_RADIAL_TOLERANCE_PX` (OpenCV's fisheye inverse stops at 90 degrees of
        distorted angle; its iterations crawl near a fold and can run away on strong
        lenses) are found again by bisection of the model's monotonic part.
        """
        import cv2

        pixels = np.asarray(pixels, dtype=np.float64)
        normalized = self._normalized(pixels)[:, None, :]
        if self.fisheye:
            ideal = cv2.fisheye.undistortPoints(normalized, np.eye(3), self._d,
                                                criteria=_POINT_CRITERIA)
        else:
            ideal = cv2.undistortPoints(normalized, np.eye(3), self._d, None, None, None,
                                            _POINT_CRITERIA)
        ideal = self._pixels(ideal.reshape(-1, 2))
        if self.is_radial:  # answers OpenCV did not polish (slow near a fold): bisected
            unsure = ~(self._residual(ideal, pixels) <= _RADIAL_TOLERANCE_PX)
            if unsure.any():
                ideal[unsure] = self._radial_inverse(pixels[unsure])
        ideal[~(self._residual(ideal, pixels) <= _INVERSE_TOLERANCE_PX)] = np.nan
        return ideal

    def _residual(self, ideal: np.ndarray, pixels: np.ndarray) -> np.ndarray:
        """How far (pixels) the lens puts ``ideal`` from ``pixels``; NaN beyond the limit."""
        with np.errstate(invalid="ignore"):
            return np.hypot(*(self.distort(ideal) - pixels).T)

    def _radial_inverse(self, pixels: np.ndarray, iterations: int = 64) -> np.ndarray:
        """Ideal pixels of a radial model's ``pixels`` by bisection of the angle off axis
        over the monotonic part (NaN where the distorted radius is beyond its reach)."""
        distorted = self._normalized(pixels)
        radius = np.hypot(distorted[:, 0], distorted[:, 1])
        high = np.full(len(pixels), math.atan(self.limit) if math.isfinite(self.limit)
                       else math.pi / 2)
        low = np.zeros(len(pixels))
        with np.errstate(all="ignore"):  # tan near 90 degrees overflows: "not below"
            for _ in range(iterations):
                middle = (low + high) / 2
                below = _radial_distortion(self.coefficients, self.fisheye, middle) < radius
                low, high = np.where(below, middle, low), np.where(below, high, middle)
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = np.where(radius > 0, np.tan(low) / radius, 1.0)
        return self._pixels(distorted * factor[:, None])

    def maps(self, output_from_ideal: np.ndarray, size: tuple[int, int],
             step: int | None = None, reuse: tuple[np.ndarray, np.ndarray] | None = None):
        """Maps (x, y; 32-bit float, which ``cv2.remap`` samples faster than fixed-point maps,
        measured) of every output pixel to its (distorted) input pixel: output -> ideal input
        pixel (the homography's inverse) -> lens; big frames' expanded from :meth:`grid`
        (:meth:`expand`).

        ``reuse``: maps an earlier call returned for a frame of the same size, whose memory
        the new maps take over (writing fresh memory costs more than computing them).
        """
        step = map_step(size) if step is None else step
        grid = self.grid(output_from_ideal, size, step)
        return grid if step == 1 else self.expand(grid, size, step, reuse)

    def grid(self, output_from_ideal: np.ndarray, size: tuple[int, int], step: int
             ) -> tuple[np.ndarray, np.ndarray]:
        """The maps at every ``step``-th output pixel (every pixel for ``step = 1``), with one
        point more than the output on every side, so that :meth:`expand` extrapolates none.

        ``cv2.initUndistortRectifyMap`` computes ``K distort((newK R)^-1 o)``; with ``newK = I``
        and ``R = output_from_ideal @ K`` that is the lens applied to ``K^-1 H^-1 o``. OpenCV
        there ignores skew, so a skewed camera's maps are computed point by point instead.
        """
        import cv2

        k = self._k
        width, height = size
        # Grid point (i, j) is output pixel (step (i - 1) + step/2 - 1/2, ...): the positions
        # from which cv2.resize(fx = step) interpolates every output pixel.
        offset = step / 2 - 0.5 - (step if step > 1 else 0)
        output_from_grid = np.array([[step, 0.0, offset], [0.0, step, offset], [0.0, 0.0, 1.0]])
        grid = size if step == 1 else (-(-width // step) + 3, -(-height // step) + 3)
        if k[0, 1] == 0:
            rotation = (np.linalg.inv(output_from_grid)
                        @ np.asarray(output_from_ideal, dtype=np.float64) @ k)
            initialize = (cv2.fisheye.initUndistortRectifyMap if self.fisheye
                          else cv2.initUndistortRectifyMap)
            maps = initialize(k, self._d, rotation, np.eye(3), grid, cv2.CV_32FC1)
            if math.isfinite(self.limit):  # beyond the fold: no source, like the horizon
                beyond = self._beyond_limit(np.linalg.inv(rotation), grid)
                for part in maps:
                    part[beyond] = NO_SOURCE
            return maps
        cols, rows = np.meshgrid(np.arange(grid[0], dtype=np.float64),
                                 np.arange(grid[1], dtype=np.float64))
        outputs = map_points(output_from_grid, np.column_stack([cols.ravel(), rows.ravel()]))
        sources = self.distort(map_points(np.linalg.inv(output_from_ideal), outputs))
        sources = np.nan_to_num(sources, nan=NO_SOURCE, posinf=NO_SOURCE, neginf=NO_SOURCE)
        return (sources[:, 0].reshape(grid[1], grid[0]).astype(np.float32),
                sources[:, 1].reshape(grid[1], grid[0]).astype(np.float32))

    def _beyond_limit(self, normalized_from_grid: np.ndarray, grid: tuple[int, int]
                      ) -> np.ndarray:
        """Which grid points' normalized rays lie beyond :attr:`limit` (shape ``(rows,
        cols)``); ``normalized_from_grid`` maps grid points to homogeneous normalized rays."""
        cols = np.arange(grid[0], dtype=np.float64)[None, :]
        rows = np.arange(grid[1], dtype=np.float64)[:, None]
        x, y, w = (m[0] * cols + m[1] * rows + m[2] for m in normalized_from_grid)
        with np.errstate(divide="ignore", invalid="ignore"):
            return ~(np.hypot(x, y) < self.limit * np.abs(w))

    @staticmethod
    def expand(grid: tuple[np.ndarray, np.ndarray], size: tuple[int, int], step: int,
               reuse: tuple[np.ndarray, np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        """Every output pixel's map, interpolated bilinearly from :meth:`grid`'s (views into
        the resized grid: ``cv2.remap`` takes row-strided maps as they are), into the memory
        of ``reuse`` when that is an earlier expansion of the same size."""
        import cv2

        width, height = size
        padded = (grid[0].shape[0] * step, grid[0].shape[1] * step)
        targets = [None, None]
        if reuse is not None and all(part.base is not None and part.base.shape == padded
                                     for part in reuse):
            targets = [part.base for part in reuse]
        return tuple(cv2.resize(part, None, dst=target, fx=step, fy=step,
                                interpolation=cv2.INTER_LINEAR)
                     [step:step + height, step:step + width]
                     for part, target in zip(grid, targets))


#: Lens maps of big frames are computed on a grid of every ``MAP_STEP``-th output pixel and
#: interpolated bilinearly: the map is smooth, and interpolating it errs by under 0.01 px
#: (tested) at a sixteenth of the cost.
MAP_STEP = 4

def map_step(size: tuple[int, int]) -> int:
    """Every how many output pixels a frame's lens maps are computed: big frames on a grid
    of :data:`MAP_STEP` (then interpolated), small ones at every pixel."""
    return MAP_STEP if min(size) >= 64 * MAP_STEP else 1
