"""Make docs/antialias.png: a fine texture rectified at --scale 0.25, without and with
anti-aliasing, beside an area-averaged reference (each panel enlarged 3x, nearest).

    python docs/make_antialias_figure.py
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from gsrwt_cli import View
from gsrwt_cli.api.rectify import Framing, rectify_image

ROOT = Path(__file__).resolve().parent.parent


def fine_texture(height: int, width: int) -> np.ndarray:
    """Stripes and noise at the pixel scale (as tests/geometry/test_real_cameras.py makes them)."""
    rng = np.random.default_rng(5)
    cols, rows = np.meshgrid(np.arange(width), np.arange(height))
    stripes = 127 + 100 * np.sin(cols * 2.6 + rows * 0.9) * np.cos(rows * 2.1)
    grey = np.clip(stripes + rng.normal(0, 25, (height, width)), 0, 255).astype(np.uint8)
    return cv2.merge([grey, np.roll(grey, 3, axis=1), np.roll(grey, 5, axis=0)])


def main() -> None:
    image = fine_texture(480, 640)
    view = View(0, 0, 500, width=640, height=480)
    plain, _ = rectify_image(image, view, Framing(scale=0.25), antialias=False)
    filtered, _ = rectify_image(image, view, Framing(scale=0.25), antialias=True)
    reference = cv2.resize(image, (plain.shape[1], plain.shape[0]), interpolation=cv2.INTER_AREA)
    panels = []
    for label, panel in (("bilinear", plain), ("--antialias", filtered), ("area", reference)):
        big = cv2.resize(panel, None, fx=3, fy=3, interpolation=cv2.INTER_NEAREST)
        cv2.putText(big, label, (8, 26), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (255, 255, 255), 3)
        cv2.putText(big, label, (8, 26), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 1)
        panels.append(big)
        panels.append(np.full((big.shape[0], 10, 3), 255, np.uint8))
    cv2.imwrite(str(ROOT / "docs" / "antialias.png"), np.hstack(panels[:-1]))


if __name__ == "__main__":
    main()
