"""Sobel edges of grey images, shared by the Hough lines and the GHT (thesis Sec. 5.2.2).

Plain pixel coordinates: ``x`` is the column (to the right), ``y`` the row (downward), pixel
centres at integers; angles in degrees. Images are 2-D ``uint8`` grey arrays or ``uint8`` BGR /
BGRA colour arrays (:func:`grey_image`); :func:`pixels8` brings any image
:func:`~gsrwt_cli.imaging.images.read_image` gives (8 to 32-bit integers, 32 or 64-bit floats; grey,
colour, alpha) to 8 bits, :func:`grey8` and :func:`colour8` to 8-bit grey and BGR.

The gradient orientation ``atan2(gy, gx)`` in ``[0, 360)`` points from dark to light: a dark
left half and light right half gives 0 deg, dark top and light bottom gives 90 deg. It is
the normal ``theta`` of the line ``x cos(theta) + y sin(theta) = rho`` through the edge, so
a vertical edge has ``theta`` near 0 or 180 deg and a horizontal one near 90 or 270 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

#: Sobel magnitude (raw 3x3 mask, grey levels) at which a pixel is an edge (thesis Sec. 5.2.2).
DEFAULT_EDGE_THRESHOLD = 80.0

#: The high hysteresis threshold of :func:`line_edges`: the gradient magnitude (3x3 Sobel of
#: the smoothed image, compensated for magnification) a chain of edge pixels needs somewhere.
#: About a 9-grey-level step after the smoothing (a sharp step of ``d`` levels gives ``4 d``
#: unsmoothed, about ``2.8 d`` after a Gaussian of sigma 1).
DEFAULT_LINE_THRESHOLD = 25.0

#: Gaussian smoothing (sigma, pixels) of the grey image before the gradient: JPEG blocks and
#: sensor noise of a few grey levels otherwise outweigh a faint edge.
DEFAULT_SMOOTHING = 1.0

#: Gaussian smoothing (sigma, pixels) of the gradient vector from which each pixel's
#: orientation is taken (not its magnitude), beyond :data:`DEFAULT_SMOOTHING`: none, each
#: pixel's orientation is that of its own edge. A blur of 2 px mixes in the edges beside it
#: (the two sides of a thin bar, a window frame's second edge, the crossing edge at a
#: corner) and turns a real photo's edges by 10 to 30 degrees there; the Hough transform of
#: ``gsrwt lines`` allows for the orientation's noise instead, pixel by pixel
#: (:attr:`EdgeMap.gradient_noise`). ``gsrwt match`` smooths it
#: (:data:`~.ght.MATCH_ORIENTATION_SMOOTHING`).
DEFAULT_ORIENTATION_SMOOTHING = 0.0

#: :data:`EdgeMap.gradient_noise` is measured on the pixels at least this far (pixels, a
#: square's half-width) from every edge pixel.
NOISE_CLEARANCE = 3

#: Hysteresis of :func:`line_edges`: a chain of edge pixels needs one pixel at the high
#: threshold (``edge_threshold``) and keeps its pixels down to this fraction of it.
DEFAULT_LOW_RATIO = 0.4

#: Pixels of the frontal view this close to the fill (no source pixel) give no edges: their
#: 3x3 Sobel sees the fill, and bilinear sampling mixes the fill in one pixel further.
FILL_MARGIN = 3

#: The magnification compensation of :func:`line_edges` is capped at this factor.
MAX_MAGNIFICATION = 4.0

GreyImage = NDArray[np.uint8]


@dataclass(frozen=True, eq=False)
class EdgeMap:
    """Sobel gradient of a grey image and its edge pixels (thesis Sec. 5.2.2).

    ``magnitude``: ``float32``, the raw ``cv2.Sobel`` (``ksize=3``) magnitude
    ``sqrt(gx**2 + gy**2)``. ``orientation_deg``: ``float32``, ``atan2(gy, gx)`` in degrees,
    in ``[0, 360)``, pointing from dark to light. ``mask``: ``bool``, ``magnitude >=
    threshold``, never set on the 1-pixel image border (where the mask sees outside the image).
    """

    magnitude: NDArray[np.float32]
    orientation_deg: NDArray[np.float32]
    mask: NDArray[np.bool_]
    #: Pixels that may carry an edge's weight in sub-pixel fits (``magnitude`` at least the
    #: low hysteresis threshold, not thinned); None: the ``mask`` itself.
    support: NDArray[np.bool_] | None = None
    #: Weights of sub-pixel fits: the raw 3x3 Sobel magnitude of the unsmoothed image (its
    #: profile across an edge is narrow); None: ``magnitude``.
    weight: NDArray[np.float32] | None = None
    #: The raw 3x3 Sobel ``(gx, gy)`` of the unsmoothed image, shape ``(2, height, width)``,
    #: where segments' ends are looked for; None if not kept.
    gradient: NDArray[np.float32] | None = None
    #: The standard deviation of each component of the gradient behind ``magnitude`` that
    #: the image's noise and fine texture give (:func:`gradient_noise`); None if not measured.
    gradient_noise: float | None = None
    #: The pixels whose gradient is measured (inside the image's 1-pixel border, at least
    #: :data:`FILL_MARGIN` px from the fill); None: all.
    measured: NDArray[np.bool_] | None = None

    @property
    def support_mask(self) -> NDArray[np.bool_]:
        """``support`` if set, else ``mask``."""
        return self.mask if self.support is None else self.support

    @property
    def fit_weight(self) -> NDArray[np.float32]:
        """``weight`` if set, else ``magnitude``."""
        return self.magnitude if self.weight is None else self.weight


def gradient_magnitude(gradient_x: np.ndarray, gradient_y: np.ndarray) -> NDArray[np.float32]:
    """``sqrt(gx**2 + gy**2)`` element by element, each step an IEEE 754 float32 operation
    (numpy's multiply, add and square root, which round exactly as the standard says): the
    same bits on every CPU and at every call. ``cv2.magnitude`` is not: through Intel IPP
    its last bits depend on where in memory its output lands (an output 8 bytes off a
    64-byte boundary gave other values), which made ``gsrwt lines``' ``contrast`` differ
    from run to run of the same command."""
    magnitude = np.multiply(gradient_x, gradient_x, dtype=np.float32)
    magnitude += np.multiply(gradient_y, gradient_y, dtype=np.float32)
    return np.sqrt(magnitude, out=magnitude)


def gradient_noise(magnitude: np.ndarray, edges: np.ndarray, inside: np.ndarray) -> float:
    """The standard deviation ``sigma`` of each gradient component that noise and texture
    give, measured where there is no edge: on the pixels of ``inside`` at least
    :data:`NOISE_CLEARANCE` px from every pixel of ``edges``. There the magnitude of a
    gradient of two independent normal components of deviation ``sigma`` follows Rayleigh's
    law, whose median is ``sigma sqrt(2 ln 2)``. 0 if no pixel is left."""
    size = 2 * NOISE_CLEARANCE + 1
    near = cv2.dilate(edges.astype(np.uint8), np.ones((size, size), np.uint8))
    away = magnitude[(near == 0) & inside]
    if away.size == 0:
        return 0.0
    return float(np.median(away)) / math.sqrt(2.0 * math.log(2.0))


def grey_image(image: np.ndarray) -> GreyImage:
    """The 2-D ``uint8`` grey version of a grey, BGR or BGRA ``uint8`` image."""
    pixels = np.asarray(image)
    if pixels.dtype != np.uint8:
        raise TypeError(f"expected an 8-bit (uint8) image, got {pixels.dtype}")
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    if pixels.ndim == 2:
        return np.ascontiguousarray(pixels)
    if pixels.ndim != 3 or pixels.shape[2] not in (3, 4):
        raise ValueError(f"expected a grey, BGR or BGRA image, got shape {pixels.shape}")
    if pixels.shape[0] == 0 or pixels.shape[1] == 0:
        return np.zeros(pixels.shape[:2], np.uint8)
    code = cv2.COLOR_BGR2GRAY if pixels.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
    return cv2.cvtColor(np.ascontiguousarray(pixels), code)


def edge_map(image: np.ndarray, threshold: float = DEFAULT_EDGE_THRESHOLD) -> EdgeMap:
    """Sobel magnitude, orientation and edge pixels of ``image`` (thesis Sec. 5.2.2).

    ``threshold`` is compared with the raw 3x3 Sobel magnitude (a step of ``d`` grey levels
    gives ``4 d``); the thesis uses 80.
    """
    grey = grey_image(image)
    height, width = grey.shape
    if height == 0 or width == 0:
        empty = np.zeros((height, width), np.float32)
        return EdgeMap(empty, empty.copy(), np.zeros((height, width), bool))
    gradient_x = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gradient_y = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    magnitude = gradient_magnitude(gradient_x, gradient_y)
    orientation = np.degrees(np.arctan2(gradient_y, gradient_x)).astype(np.float32)
    orientation[orientation < 0] += np.float32(360.0)
    orientation[orientation >= 360.0] = 0.0  # -tiny + 360 rounds to 360 in float32
    mask = np.zeros((height, width), bool)
    mask[1:-1, 1:-1] = magnitude[1:-1, 1:-1] >= threshold
    return EdgeMap(magnitude, orientation, mask)


def line_edges(
    image: np.ndarray,
    threshold: float = DEFAULT_LINE_THRESHOLD,
    *,
    low_ratio: float = DEFAULT_LOW_RATIO,
    magnification: np.ndarray | None = None,
    valid: np.ndarray | None = None,
    smoothing: float = DEFAULT_SMOOTHING,
    orientation_smoothing: float = DEFAULT_ORIENTATION_SMOOTHING,
) -> EdgeMap:
    """Thin hysteresis edges of a frontal view (Canny 1986 on the thesis's 3x3 Sobel gradient).

    The raw ``cv2.Sobel`` gradient (a step of ``d`` grey levels gives ``4 d``, as in
    :func:`edge_map`) is first multiplied by ``magnification`` (output pixels per source pixel
    at each pixel, :func:`~gsrwt_cli.vision.frontal_pixels.magnification`; clipped to ``[1,``
    :data:`MAX_MAGNIFICATION` ``]``): a rectification that stretches the far side of a wall
    ``s`` times spreads each edge over ``s`` times more pixels and divides its gradient by
    about ``s``, and so does it for the noise; the product is the gradient per source pixel.
    Edge pixels (``mask``) are the local maxima of that magnitude across the edge
    (non-maximum suppression) that are connected, through pixels of at least ``low_ratio *
    threshold``, to a pixel of at least ``threshold`` (``cv2.Canny`` with the L2 norm): a
    faint stretch of a white frame on a white wall is kept when the same edge is strong
    elsewhere, an isolated faint texture pixel is not. ``support``: the pixels of at least
    the low threshold within 2 px of an edge pixel (not thinned), for sub-pixel fits, whose
    weights (``weight``) are the raw Sobel magnitude of the unsmoothed image.

    ``valid``: the frontal pixels that have a source pixel; the gradient is zeroed within
    :data:`FILL_MARGIN` pixels of the others, so the border with the fill gives no edges.
    ``magnitude`` is the compensated one, ``gradient_noise`` the deviation of its components
    away from edges (:func:`gradient_noise`); ``orientation_deg`` as in :func:`edge_map`, of
    the compensated gradient smoothed by ``orientation_smoothing``.
    """
    grey = grey_image(image)
    height, width = grey.shape
    if height < 3 or width < 3:
        empty = np.zeros((height, width), np.float32)
        nothing = np.zeros((height, width), bool)
        return EdgeMap(empty, empty.copy(), nothing, nothing.copy(), empty.copy())
    gradient_x = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gradient_y = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    weight = gradient_magnitude(gradient_x, gradient_y)
    raw_gradient = np.stack([gradient_x, gradient_y])
    if smoothing > 0:  # the Sobel of the smoothed image is the smoothed Sobel
        gradient_x = cv2.GaussianBlur(gradient_x, (0, 0), smoothing)
        gradient_y = cv2.GaussianBlur(gradient_y, (0, 0), smoothing)
    if magnification is not None:
        gain = np.clip(np.asarray(magnification, np.float32), 1.0, MAX_MAGNIFICATION)
        gradient_x *= gain
        gradient_y *= gain
    inside = np.zeros((height, width), np.uint8)
    inside[1:-1, 1:-1] = 1
    if valid is not None:
        inside &= cv2.erode(np.asarray(valid, np.uint8), np.ones((3, 3), np.uint8),
                            iterations=FILL_MARGIN, borderType=cv2.BORDER_CONSTANT,
                            borderValue=1)
        gradient_x *= inside
        gradient_y *= inside
    magnitude = gradient_magnitude(gradient_x, gradient_y)
    if orientation_smoothing > 0:
        direction_x = cv2.GaussianBlur(gradient_x, (0, 0), orientation_smoothing)
        direction_y = cv2.GaussianBlur(gradient_y, (0, 0), orientation_smoothing)
    else:
        direction_x, direction_y = gradient_x, gradient_y
    orientation = np.degrees(np.arctan2(direction_y, direction_x)).astype(np.float32)
    orientation[orientation < 0] += np.float32(360.0)
    orientation[orientation >= 360.0] = 0.0
    low = float(threshold) * float(low_ratio)
    limit = np.float32(32767.0)
    dx = np.clip(np.rint(gradient_x), -limit, limit).astype(np.int16)
    dy = np.clip(np.rint(gradient_y), -limit, limit).astype(np.int16)
    mask = cv2.Canny(dx, dy, low, float(threshold), L2gradient=True) > 0
    mask &= inside.astype(bool)
    # Support: only near edge pixels (within 2 px), where segments' fits and gaps look.
    near_edges = cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    support = (magnitude >= low) & inside.astype(bool) & near_edges
    weight *= inside
    raw_gradient *= inside
    measured = inside.astype(bool)
    noise = gradient_noise(magnitude, mask, measured)
    return EdgeMap(magnitude, orientation, mask, support, weight, raw_gradient, noise, measured)


def orientation_bin_count(step_deg: float) -> int:
    """How many bins of ``step_deg`` cover 360 degrees; ``step_deg`` must divide 360."""
    if not step_deg > 0:
        raise ValueError(f"orientation step must be positive, got {step_deg}")
    count = 360.0 / step_deg
    if abs(count - round(count)) > 1e-6:
        raise ValueError(f"orientation step {step_deg} deg does not divide 360 deg")
    return int(round(count))


def bin_of_orientation(orientation_deg: np.ndarray, step_deg: float, bin_count: int) -> np.ndarray:
    """Bin ``k`` (centre ``k * step_deg``) of each orientation, wrapping at 360 degrees."""
    return np.rint(orientation_deg / step_deg).astype(np.int64) % bin_count


def compatible_bins(orientation_bin: int, tolerance_bins: int, bin_count: int) -> list[int]:
    """Orientation bins within ``tolerance_bins`` of ``orientation_bin``, wrapping, no repeats."""
    if 2 * tolerance_bins + 1 >= bin_count:
        return list(range(bin_count))
    return [(orientation_bin + d) % bin_count for d in range(-tolerance_bins, tolerance_bins + 1)]


def pixels8(pixels: np.ndarray) -> NDArray[np.uint8]:
    """The 8-bit version of any decoded image, channels kept: the one conversion of every
    command that looks at pixels (estimate, rectify --auto, lines, match, their drawings).

    Integers map their type's range ``[0, max]`` onto ``[0, 255]`` (negative values of signed
    types are black). Floats are nominally ``[0, 1]`` (OpenCV's convention, and gsrwt's own
    for the fill); an image with brighter finite values (a float copy of 0-255 or 0-65535
    levels, a radiance map) is scaled by its brightest finite value instead, so that it is
    not all white. NaN and -inf are black, +inf white.
    """
    pixels = np.asarray(pixels)
    kind = pixels.dtype.kind
    if pixels.dtype == np.uint8:
        return pixels
    if kind in "iu":
        top = float(np.iinfo(pixels.dtype).max)
        source = np.maximum(pixels, 0) if kind == "i" else pixels
        if source.dtype not in (np.uint16, np.int8, np.int16, np.int32):
            source = source.astype(np.float64)  # types OpenCV has no depth for
    elif kind == "f":
        finite = np.isfinite(pixels)
        top = max(1.0, float(np.max(pixels, where=finite, initial=0.0)))
        source = np.nan_to_num(pixels, nan=0.0, posinf=top, neginf=0.0)
        np.maximum(source, 0.0, out=source)
        if source.dtype not in (np.float32, np.float64):
            source = source.astype(np.float32)
    else:
        raise TypeError(f"expected an image of integer or float samples, got {pixels.dtype}")
    # Every value is now in [0, top]: convertScaleAbs's absolute value changes nothing.
    return cv2.convertScaleAbs(source, alpha=255.0 / top)


def colour8(pixels: np.ndarray) -> np.ndarray:
    """An 8-bit BGR copy of any decoded image (:func:`pixels8`; grey, BGR or BGRA), for
    drawing."""
    pixels = pixels8(pixels)
    if pixels.ndim == 2:
        return cv2.cvtColor(pixels, cv2.COLOR_GRAY2BGR)
    return pixels[..., :3].copy()


def grey8(pixels: np.ndarray) -> GreyImage:
    """The 8-bit grey version of any decoded image (:func:`pixels8`), for edge search."""
    return grey_image(pixels8(pixels))
