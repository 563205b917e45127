"""Test images: textures like photographs, and how close two images are."""

from __future__ import annotations

import math

import cv2
import numpy as np


def smooth_texture(height: int, width: int, seed: int = 0, channels: int = 3) -> np.ndarray:
    """A textured 8-bit image: luminance detail a few pixels wide, colour that varies slowly.

    Like photographs (and unlike colour noise) it survives JPEG's chroma subsampling.
    """
    rng = np.random.default_rng(seed)

    def noise(step: int, sigma: float, depth: int = 1) -> np.ndarray:
        shape = (height // step + 2, width // step + 2) + ((depth,) if depth > 1 else ())
        field = cv2.resize(rng.uniform(-1, 1, shape).astype(np.float32), (width, height),
                           interpolation=cv2.INTER_CUBIC)
        return cv2.GaussianBlur(field, (0, 0), sigma)

    luminance = 128 + 110 * noise(6, 1.5)
    if channels == 1:
        return np.clip(luminance, 0, 255).astype(np.uint8)
    colour = luminance[..., None] + 40 * noise(24, 4, channels)
    return np.clip(colour, 0, 255).astype(np.uint8)


def psnr(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> float:
    """Peak signal-to-noise ratio (dB, 8-bit peak) of ``a`` against ``b`` where ``mask``."""
    diff = a.astype(float)[mask] - b.astype(float)[mask]
    mse = float(np.mean(diff**2))
    return math.inf if mse == 0 else 10 * math.log10(255.0**2 / mse)


def phase_shift(reference: np.ndarray, image: np.ndarray, border: int = 3) -> float:
    """The larger component of ``image``'s shift against ``reference`` (output pixels) by
    ``cv2.phaseCorrelate`` (Hann window), on an inner crop whose sides are even sizes the
    DFT takes as they are (padded to an odd size, its peak is placed half a pixel off)."""
    def side(length: int) -> int:
        return max(n for n in range(2, length + 1, 2) if cv2.getOptimalDFTSize(n) == n)

    height = side(reference.shape[0] - 2 * border)
    width = side(reference.shape[1] - 2 * border)
    crop = (slice(border, border + height), slice(border, border + width))
    window = cv2.createHanningWindow((width, height), cv2.CV_64F)
    (dx, dy), _ = cv2.phaseCorrelate(reference[crop].astype(np.float64),
                                     image[crop].astype(np.float64), window)
    return max(abs(dx), abs(dy))
