"""Sobel edges of grey images, shared by the Hough lines and the GHT (thesis Sec. 5.2.2).

Plain pixel coordinates: ``x`` is the column (to the right), ``y`` the row (downward), pixel
centres at integers; angles in degrees. Images are 2-D ``uint8`` grey arrays or ``uint8`` BGR /
BGRA colour arrays (:func:`grey_image`); :func:`grey8` and :func:`colour8` bring any image
:func:`~gsrwt_cli.imaging.read_image` gives (8 or 16 bits, grey, colour, alpha) to 8 bits.

The gradient orientation ``atan2(gy, gx)`` in ``[0, 360)`` points from dark to light: a dark
left half and light right half gives 0 deg, dark top and light bottom gives 90 deg. It is
the normal ``theta`` of the line ``x cos(theta) + y sin(theta) = rho`` through the edge, so
a vertical edge has ``theta`` near 0 or 180 deg and a horizontal one near 90 or 270 deg.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

#: Sobel magnitude (raw 3x3 mask, grey levels) at which a pixel is an edge (thesis Sec. 5.2.2).
DEFAULT_EDGE_THRESHOLD = 80.0

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
    magnitude = cv2.magnitude(gradient_x, gradient_y)
    orientation = np.degrees(np.arctan2(gradient_y, gradient_x)).astype(np.float32)
    orientation[orientation < 0] += np.float32(360.0)
    orientation[orientation >= 360.0] = 0.0  # -tiny + 360 rounds to 360 in float32
    mask = np.zeros((height, width), bool)
    mask[1:-1, 1:-1] = magnitude[1:-1, 1:-1] >= threshold
    return EdgeMap(magnitude, orientation, mask)


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


def colour8(pixels: np.ndarray) -> np.ndarray:
    """An 8-bit BGR copy of any decoded image (8 or 16 bits; grey, BGR or BGRA), for drawing."""
    if pixels.dtype != np.uint8:
        pixels = cv2.convertScaleAbs(pixels, alpha=255.0 / float(np.iinfo(pixels.dtype).max))
    if pixels.ndim == 2:
        return cv2.cvtColor(pixels, cv2.COLOR_GRAY2BGR)
    return pixels[..., :3].copy()


def grey8(pixels: np.ndarray) -> GreyImage:
    """The 8-bit grey version of any decoded image (as :func:`colour8`), for edge search."""
    return cv2.cvtColor(colour8(pixels), cv2.COLOR_BGR2GRAY)
