"""Make docs/guided.jpg: guided correction on three real photos nobody here took, each before
(its guides drawn in red) and after, as the `gsrwt` commands below make them:

- OpenCV's `sudoku.png` (a newspaper puzzle photographed at an angle): `gsrwt rectify
  --auto document --bbox corners`, the corners found by gsrwt (no focal length given);
- scikit-image's `text.png` (handwriting on ruled paper, seen obliquely): three ruled lines
  clicked by eye, `--horizontals ... --fit horizontal` (the page has no corner in view);
- OpenCV's `building.jpg`: two verticals clicked by eye, `--verticals ... --fit vertical`,
  a photographer's keystone fix.

    python docs/make_guided_figure.py
"""

from __future__ import annotations

import csv
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
REAL = ROOT / "tests" / "data" / "real"
TEXT_HORIZONTALS = "252.1,-0.1,401.9,49.3;190.9,28.5,446.0,128.5;0.3,10.1,330.5,163.5"
BUILDING_VERTICALS = "151,140,150,370;751,70,761,300"
ROW_HEIGHT = 300
MARGIN = 10
RED = (40, 40, 220)


def gsrwt(*args: str) -> str:
    done = subprocess.run([sys.executable, "-m", "gsrwt_cli", *args], capture_output=True,
                          text=True, check=True)
    return done.stdout


def rectified(photo: Path, work: Path, *options: str) -> np.ndarray:
    out = work / photo.stem
    gsrwt("rectify", str(photo), *options, "-o", str(out), "-q")
    return cv2.imread(str(out / photo.name), cv2.IMREAD_COLOR)


def segments(text: str) -> list[np.ndarray]:
    return [np.array([float(v) for v in part.split(",")]).reshape(2, 2)
            for part in text.split(";")]


def scaled(image: np.ndarray, height: int) -> np.ndarray:
    factor = height / image.shape[0]
    size = (max(1, round(image.shape[1] * factor)), height)
    return cv2.resize(image, size, interpolation=cv2.INTER_AREA if factor < 1 else
                      cv2.INTER_CUBIC)


def drawn(photo: Path, polylines: list[np.ndarray], closed: bool) -> np.ndarray:
    image = cv2.imread(str(photo), cv2.IMREAD_COLOR)
    thickness = max(2, round(image.shape[0] / 250))
    for points in polylines:
        cv2.polylines(image, [np.round(points * 4).astype(np.int32)], closed, RED, thickness,
                      cv2.LINE_AA, 2)
    return image


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        sudoku = REAL / "sudoku.jpg"
        [row] = csv.DictReader(gsrwt("estimate", str(sudoku), "--auto", "document",
                                     "-f", "csv").splitlines())
        corners = np.array([[float(v) for v in point.split(",")]
                            for point in row["corners"].split()])
        text, building = REAL / "text.jpg", ROOT / "tests" / "data" / "facade" / "building.jpg"
        rows = [
            (drawn(sudoku, [corners], True),
             rectified(sudoku, work, "--auto", "document", "--bbox", "corners")),
            (drawn(text, segments(TEXT_HORIZONTALS), False),
             rectified(text, work, "--horizontals", TEXT_HORIZONTALS, "--fit", "horizontal",
                       "--focal", "448")),
            (drawn(building, segments(BUILDING_VERTICALS), False),
             rectified(building, work, "--verticals", BUILDING_VERTICALS, "--fit",
                       "vertical", "--focal", "1245")),
        ]
    pictures = []
    for before, after in rows:
        pair = [scaled(before, ROW_HEIGHT), scaled(after, ROW_HEIGHT)]
        gap = np.full((ROW_HEIGHT, MARGIN, 3), 255, np.uint8)
        pictures.append(np.hstack([pair[0], gap, pair[1]]))
    width = max(p.shape[1] for p in pictures)
    canvas = [np.pad(p, ((0, MARGIN), (0, width - p.shape[1]), (0, 0)), constant_values=255)
              for p in pictures]
    cv2.imwrite(str(ROOT / "docs" / "guided.jpg"), np.vstack(canvas)[:-MARGIN],
                [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
