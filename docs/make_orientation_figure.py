"""Make docs/orientation.jpg: a photo stored as a phone stores it (the sensor's pixels, turned a
quarter, with EXIF Orientation 6 saying how to display them), and three frames of `gsrwt
rectify --auto` of it. Left: the pixels as stored (what a tool that ignores the tag works on);
then the outputs, upright, since gsrwt applies the tag as viewers do: `--bbox frontal` (the
thesis's frame: the input's size at frontal resolution, centred where the optical axis meets
the wall, which cuts the facade's top), the default for a pose the photo gives (`full`: the
whole visible wall, at most twice the input's pixels) and `--bbox crop --crop-aspect
original` (the largest rectangle of the photo's shape with no fill).

The photo is OpenCV's `building.jpg` (`tests/data/facade/`), turned by this script and given
the tag with Pillow (no phone photo with a known orientation is in the repository).

    python docs/make_orientation_figure.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
HEIGHT = 300
MARGIN = 10


def scaled(image: np.ndarray) -> np.ndarray:
    factor = HEIGHT / image.shape[0]
    return cv2.resize(image, (round(image.shape[1] * factor), HEIGHT),
                      interpolation=cv2.INTER_AREA)


def main() -> None:
    upright = Image.open(ROOT / "tests" / "data" / "facade" / "building.jpg")
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        phone = work / "phone.jpg"
        # Orientation 6: display = stored turned 90 degrees clockwise, so store it turned back.
        exif = Image.Exif()
        exif[0x0112] = 6
        upright.transpose(Image.Transpose.ROTATE_90).save(phone, quality=92, exif=exif)
        frames = {"frontal": ["--bbox", "frontal"], "default": [],
                  "crop": ["--bbox", "crop", "--crop-aspect", "original"]}
        outputs = []
        for name, options in frames.items():
            subprocess.run([sys.executable, "-m", "gsrwt_cli", "rectify", str(phone), "--auto",
                            *options, "-o", str(work / name), "-q"], check=True)
            outputs.append(cv2.imread(str(work / name / "phone.jpg"),
                                      cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION))
        stored = cv2.imread(str(phone), cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
    gap = np.full((HEIGHT, MARGIN, 3), 255, np.uint8)
    panels = [scaled(image) for image in (stored, *outputs)]
    row = [part for panel in panels for part in (panel, gap)][:-1]
    cv2.imwrite(str(ROOT / "docs" / "orientation.jpg"), np.hstack(row),
                [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
