"""Make docs/orientation.jpg: a photo stored as a phone stores it (the sensor's pixels, turned a
quarter, with EXIF Orientation 6 saying how to display them), before and after `gsrwt rectify
--auto --bbox full`. Left: the pixels as stored (what a tool that ignores the tag works on);
right: the output, upright, since gsrwt applies the tag as viewers do.

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
        subprocess.run([sys.executable, "-m", "gsrwt_cli", "rectify", str(phone), "--auto",
                        "--bbox", "full", "-o", str(work / "out"), "-q"], check=True)
        stored = cv2.imread(str(phone), cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
        rectified = cv2.imread(str(work / "out" / "phone.jpg"),
                               cv2.IMREAD_COLOR | cv2.IMREAD_IGNORE_ORIENTATION)
    gap = np.full((HEIGHT, MARGIN, 3), 255, np.uint8)
    cv2.imwrite(str(ROOT / "docs" / "orientation.jpg"),
                np.hstack([scaled(stored), gap, scaled(rectified)]),
                [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
