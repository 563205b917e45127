"""Regenerate the sample data: the corridor wall, its camera views, their sidecars, the picture.

    python sample_data/make_samples.py

1. ``draw_texture.py`` draws the frontal corridor wall (``corridor_wall.png``, ``.json``).
2. The knob and peek-window models are cut from it (``templates/``), and
   ``gsrwt render`` renders it as a pan-tilt camera sees it: the thesis's settings (320x240,
   f = 280 px; pan/tilt 0/30, 15/30, 30/15, 30/30 and the over-decompressed 45/30, Table 5.1
   and Fig. 5.2) and larger views (1280x960, several focal lengths, negative angles), into
   ``views/`` with their sidecar as both ``views.csv`` and ``views.yaml``.
3. ``gsrwt rectify --bbox full`` rectifies one view for the README's picture
   (``docs/sample.png``).

Everything is made by the project's own code; running it again gives the same files.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
VIEWS = HERE / "views"
TEMPLATES = HERE / "templates"
PICTURE = HERE.parent / "docs" / "sample.png"

# name, pan, tilt, focal, width, height
THESIS_VIEWS = [
    ("corridor_p0_t30.png", 0, 30, 280, 320, 240),
    ("corridor_p15_t30.png", 15, 30, 280, 320, 240),
    ("corridor_p30_t15.png", 30, 15, 280, 320, 240),
    ("corridor_p30_t30.png", 30, 30, 280, 320, 240),
    ("corridor_p45_t30.png", 45, 30, 280, 320, 240),
]
LARGE_VIEWS = [
    ("door_p20_t-8_f800.jpg", 20, -8, 800, 1280, 960),
    ("door_p40_t-12_f700.jpg", 40, -12, 700, 1280, 960),
    ("door_p8_t-2_f1500.jpg", 8, -2, 1500, 1280, 960),
    ("sign_p-25_t10_f1120.jpg", -25, 10, 1120, 1280, 960),
]


def gsrwt(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "gsrwt_cli", *args], check=True)


def cut_templates() -> None:
    """The knob and peek-window models, cut once from the frontal texture (thesis Sec. 5.2.2:
    boxes of 40x100 and 120x90 centred on the object)."""
    texture = cv2.imread(str(HERE / "corridor_wall.png"))
    truth = json.loads((HERE / "corridor_wall.json").read_text())
    TEMPLATES.mkdir(exist_ok=True)
    for name in ("knob", "window"):
        (col, row), (width, height) = truth[name]["centre"], truth[name]["box"]
        # "centre" is in pixel-edge coordinates: the box spans [col - w/2, col + w/2).
        left, top = round(col - width / 2), round(row - height / 2)
        cut = texture[top : top + height, left : left + width]
        cv2.imwrite(str(TEMPLATES / f"{name}.png"), cut, [cv2.IMWRITE_PNG_COMPRESSION, 9])


def main() -> None:
    subprocess.run([sys.executable, str(HERE / "draw_texture.py")], check=True)
    cut_templates()
    VIEWS.mkdir(exist_ok=True)
    for stale in VIEWS.iterdir():
        stale.unlink()
    with tempfile.TemporaryDirectory() as scratch:
        views = Path(scratch) / "views.csv"
        lines = ["image,pan,tilt,focal,width,height"]
        lines += [",".join(map(str, view)) for view in THESIS_VIEWS + LARGE_VIEWS]
        views.write_text("\n".join(lines) + "\n")
        texture = str(HERE / "corridor_wall.png")
        gsrwt("render", texture, "--sidecar", str(views), "-o", str(VIEWS), "--quality", "90")
        gsrwt("render", texture, "--sidecar", str(views), "-o", str(Path(scratch) / "again"),
              "--out-sidecar", str(VIEWS / "views.yaml"))
        out = Path(scratch) / "rectified"
        name = "corridor_p30_t30.png"
        gsrwt("rectify", str(VIEWS / name), "--sidecar", str(VIEWS / "views.csv"), "-o",
              str(out), "--bbox", "full", "--max-stretch", "3", "--quiet")
        make_picture(cv2.imread(str(VIEWS / name)), cv2.imread(str(out / name)))


def make_picture(view: np.ndarray, rectified: np.ndarray) -> None:
    """The camera's view beside the whole visible wall rectified, 480 px high, with captions."""
    def caption(image: np.ndarray, text: str) -> np.ndarray:
        scale = 480 / image.shape[0]
        big = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA
                         if scale < 1 else cv2.INTER_CUBIC)
        band = np.full((40, big.shape[1], 3), 255, np.uint8)
        cv2.putText(band, text, (10, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 0), 2,
                    cv2.LINE_AA)
        return np.vstack([band, big])

    gap = np.full((520, 16, 3), 255, np.uint8)
    picture = np.hstack([
        caption(view, "camera view: pan 30, tilt 30, f = 280"),
        gap,
        caption(rectified, "gsrwt rectify --bbox full: the wall, frontal"),
    ])
    PICTURE.parent.mkdir(exist_ok=True)
    cv2.imwrite(str(PICTURE), picture, [cv2.IMWRITE_PNG_COMPRESSION, 9])


if __name__ == "__main__":
    main()
