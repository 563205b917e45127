"""Renders through a lens with radial distortion, by OpenCV's own projection
(``cv2.projectPoints`` with distortion coefficients), independent of gsrwt's lens code: the
pose estimator's box rooms (:mod:`tests.helpers.estimate_scenes`) rendered as a pinhole on a
larger canvas, then each pixel of the distorted photo sampled where OpenCV's model sends its
ray (the model inverted by fixed-point iteration on ``cv2.projectPoints`` itself).

Used by tests/api/test_lens_lines.py and benchmarks/bench_lens_lines.py.
"""

from __future__ import annotations

import cv2
import numpy as np

from tests.helpers.estimate_scenes import Shot, render_room


def ideal_from_distorted(pixels: np.ndarray, focal: float, centre: tuple[float, float],
                         coefficients: np.ndarray, iterations: int = 200) -> np.ndarray:
    """``(N, 2)`` distorted pixels to the pinhole pixels whose rays OpenCV's model puts
    there: ``p <- p + (target - projectPoints(p))`` until it settles (within 1e-4 px)."""
    matrix = np.array([[focal, 0, centre[0]], [0, focal, centre[1]], [0, 0, 1.0]])
    target = np.asarray(pixels, dtype=np.float64)
    ideal = target.copy()
    zero = np.zeros(3)
    for _ in range(iterations):
        rays = np.column_stack([(ideal - centre) / focal, np.ones(len(ideal))])
        projected = cv2.projectPoints(rays.reshape(-1, 1, 3), zero, zero, matrix,
                                      coefficients)[0].reshape(-1, 2)
        step = target - projected
        ideal += step
        if np.abs(step).max() < 1e-4:
            break
    return ideal


def render_distorted_room(pan: float, tilt: float, roll: float = 0.0, *, k1: float,
                          focal: float = 700.0, size: tuple[int, int] = (640, 480),
                          seed: int = 0, noise: float = 2.0, blur: float = 0.5,
                          jpeg: int | None = 90) -> Shot:
    """A box room seen at the pose through a lens ``x_d = x (1 + k1 r^2)`` (OpenCV's
    plumb_bob with only k1), principal point at the image's centre; the truth in the
    :class:`Shot` (its pose and focal length; k1 is the caller's)."""
    width, height = size
    pad = int(0.45 * max(width, height))
    big = render_room(pan, tilt, roll, focal=focal, size=(width + 2 * pad, height + 2 * pad),
                      seed=seed, blur=0.0, noise=0.0, jpeg=None)
    cx, cy = (width - 1) / 2.0, (height - 1) / 2.0
    cols, rows = np.meshgrid(np.arange(width, dtype=np.float64),
                             np.arange(height, dtype=np.float64))
    pixels = np.column_stack([cols.ravel(), rows.ravel()])
    ideal = ideal_from_distorted(pixels, focal, (cx, cy), np.array([k1, 0.0, 0.0, 0.0, 0.0]))
    map_x = (ideal[:, 0] + pad).reshape(height, width).astype(np.float32)
    map_y = (ideal[:, 1] + pad).reshape(height, width).astype(np.float32)
    image = cv2.remap(big.image, map_x, map_y, cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_REPLICATE)
    rng = np.random.default_rng(seed + 7)
    if blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), blur)
    if noise > 0:
        image = np.clip(image + rng.normal(0, noise, image.shape), 0, 255).astype(np.uint8)
    if jpeg is not None:
        image = cv2.imdecode(cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, jpeg])[1],
                             cv2.IMREAD_COLOR)
    return Shot(image, pan, tilt, roll, focal, cx, cy)
