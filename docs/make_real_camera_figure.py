"""Make docs/real_camera.png: a raw, distorted chessboard photo (OpenCV's right02.jpg, pan 41,
roll 79) beside what one `gsrwt rectify --camera` call makes of it.

    python docs/make_real_camera_figure.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"


def main() -> None:
    photo = DATA / "right02.jpg"
    with tempfile.TemporaryDirectory() as work:
        gsrwt = Path(sys.executable).with_name("gsrwt")
        subprocess.run([str(gsrwt), "rectify", str(photo), "--sidecar",
                        str(DATA / "right_poses.csv"), "--camera", str(DATA / "right_camera.yml"),
                        "--px-per-unit", "20", "--bbox", "full", "--max-stretch", "3",
                        "-o", work, "-q"], check=True)
        rectified = cv2.imread(str(Path(work) / photo.name))
    raw = cv2.imread(str(photo))
    height = 360
    panels = [cv2.resize(image, (round(image.shape[1] * height / image.shape[0]), height),
                         interpolation=cv2.INTER_AREA) for image in (raw, rectified)]
    gap = np.full((height, 12, 3), 255, np.uint8)
    cv2.imwrite(str(ROOT / "docs" / "real_camera.png"), np.hstack([panels[0], gap, panels[1]]))


if __name__ == "__main__":
    main()
