"""Make docs/lines.jpg: `gsrwt lines --draw` on real photos. Left: OpenCV's chessboard photo
right06.jpg rectified with its pose and calibration (one call over tests/data); right:
OpenCV's building.jpg, a facade taken as frontal, vertical segments only.

    python docs/make_lines_figure.py
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
    gsrwt = Path(sys.executable).with_name("gsrwt")
    with tempfile.TemporaryDirectory() as work:
        subprocess.run([str(gsrwt), "lines", str(DATA), "--sidecar", str(DATA / "right_poses.csv"),
                        "--camera", str(DATA / "right_camera.yml"), "--draw", f"{work}/board",
                        "--format", "csv"], check=True, stdout=subprocess.DEVNULL)
        subprocess.run([str(gsrwt), "lines", str(DATA / "facade"), "--orientation", "vertical",
                        "--draw", f"{work}/facade", "--format", "csv"], check=True,
                       stdout=subprocess.DEVNULL)
        board = cv2.imread(f"{work}/board/right06.png")
        facade = cv2.imread(f"{work}/facade/building.png")
    height = 400
    panels = [cv2.resize(image, (round(image.shape[1] * height / image.shape[0]), height),
                         interpolation=cv2.INTER_AREA) for image in (board, facade)]
    gap = np.full((height, 12, 3), 255, np.uint8)
    cv2.imwrite(str(ROOT / "docs" / "lines.jpg"), np.hstack([panels[0], gap, panels[1]]),
                [cv2.IMWRITE_JPEG_QUALITY, 88])


if __name__ == "__main__":
    main()
