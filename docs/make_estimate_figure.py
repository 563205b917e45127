"""Make docs/estimate.png and docs/estimate_draw.png: OpenCV's building.jpg (no focal length,
no pose) beside what one `gsrwt rectify --auto` call makes of it, and the picture
`gsrwt estimate --draw` makes of it.

    python docs/make_estimate_figure.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PHOTO = ROOT / "tests" / "data" / "facade" / "building.jpg"


def main() -> None:
    gsrwt = Path(sys.executable).with_name("gsrwt")
    with tempfile.TemporaryDirectory() as work:
        subprocess.run([str(gsrwt), "rectify", str(PHOTO), "--auto",
                        "--bbox", "full", "--max-size", "1600x1200", "-o", work, "-q"],
                       check=True)
        rectified = cv2.imread(str(Path(work) / PHOTO.name))
        subprocess.run([str(gsrwt), "estimate", str(PHOTO), "--wall", "dominant", "--draw",
                        work, "-q", "-f", "csv"], check=True, stdout=subprocess.DEVNULL)
        drawn = cv2.imread(str(Path(work) / "building.png"))
    raw = cv2.imread(str(PHOTO))
    height = 300
    panels = [cv2.resize(image, (round(image.shape[1] * height / image.shape[0]), height),
                         interpolation=cv2.INTER_AREA) for image in (raw, rectified)]
    gap = np.full((height, 12, 3), 255, np.uint8)
    cv2.imwrite(str(ROOT / "docs" / "estimate.png"), np.hstack([panels[0], gap, panels[1]]))
    cv2.imwrite(str(ROOT / "docs" / "estimate_draw.png"),
                cv2.resize(drawn, (640, round(drawn.shape[0] * 640 / drawn.shape[1])),
                           interpolation=cv2.INTER_AREA))


if __name__ == "__main__":
    main()
