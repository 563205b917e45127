"""Make docs/refusals.jpg: what one `gsrwt rectify --auto` call (no focal length, no pose)
says of photos nobody here took. Top: four photos with no man-made straight structure, each
with the reason `--auto` gives for refusing it; bottom: two facades it accepts, each beside
its rectification, with the confidence and pose it wrote. Every caption is read from the
table the command writes.

    python docs/make_refusals_figure.py
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
#: Photos that must be refused: gravel, fruit, an aerial view, a painted wall with no edges.
REFUSED = [REAL / name for name in ("gravel.jpg", "fruits.jpg", "aero1.jpg", "graf3.jpg")]
#: Photos of buildings, shown with their rectification.
ACCEPTED = [ROOT / "tests" / "data" / "facade" / "building.jpg", REAL / "leuvenB.jpg"]

WIDTH = 1200
MARGIN = 12
FONT = cv2.FONT_HERSHEY_SIMPLEX
TEXT_SCALE = 0.45
LINE_HEIGHT = 18
INK = (40, 40, 40)
REFUSED_INK = (30, 30, 190)
OK_INK = (40, 130, 30)


def auto_table(photos: list[Path], work: Path) -> dict[str, dict[str, str]]:
    """Run ``gsrwt rectify PHOTOS --auto --bbox full`` (exit 1: some were refused) and
    return its table's rows by image name."""
    gsrwt = Path(sys.executable).with_name("gsrwt")
    table = work / "auto.csv"
    done = subprocess.run(
        [str(gsrwt), "rectify", *map(str, photos), "--auto", "--bbox", "full",
         "--max-stretch", "3", "--max-size", "1600x1200", "-o", str(work / "out"),
         "--table", str(table), "-q"], capture_output=True, text=True)
    if done.returncode not in (0, 1):
        raise SystemExit(f"gsrwt rectify --auto failed (exit {done.returncode}): {done.stderr}")
    with open(table, newline="") as file:
        return {Path(row["image"]).name: row for row in csv.DictReader(file)}


def wrap(text: str, width: int) -> list[str]:
    """``text`` broken at spaces into lines no wider than ``width`` pixels in the caption
    font."""
    lines: list[str] = []
    for word in text.split():
        candidate = f"{lines[-1]} {word}" if lines else word
        if lines and cv2.getTextSize(candidate, FONT, TEXT_SCALE, 1)[0][0] <= width:
            lines[-1] = candidate
        else:
            lines.append(word)
    return lines


def caption(lines: list[tuple[str, tuple[int, int, int]]], width: int) -> np.ndarray:
    """White strip ``width`` wide with each (text, colour) line written on it."""
    strip = np.full((LINE_HEIGHT * len(lines) + 8, width, 3), 255, np.uint8)
    for index, (text, colour) in enumerate(lines):
        cv2.putText(strip, text, (2, LINE_HEIGHT * (index + 1)), FONT, TEXT_SCALE, colour, 1,
                    cv2.LINE_AA)
    return strip


def fit(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` scaled to fit ``width`` x ``height``, centred on white."""
    scale = min(width / image.shape[1], height / image.shape[0])
    size = (round(image.shape[1] * scale), round(image.shape[0] * scale))
    small = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    canvas = np.full((height, width, 3), 255, np.uint8)
    top, left = (height - size[1]) // 2, (width - size[0]) // 2
    canvas[top:top + size[1], left:left + size[0]] = small
    return canvas


def stack(parts: list[np.ndarray], axis: int, gap: int = MARGIN) -> np.ndarray:
    """``parts`` joined along ``axis`` with white gaps, padded with white to a common size."""
    other = 1 - axis
    size = max(part.shape[other] for part in parts)
    padded = []
    for index, part in enumerate(parts):
        pad = [(0, 0), (0, 0), (0, 0)]
        pad[other] = (0, size - part.shape[other])
        padded.append(np.pad(part, pad, constant_values=255))
        if index < len(parts) - 1:
            shape = [size, size, 3]
            shape[axis] = gap
            padded.append(np.full(shape, 255, np.uint8))
    return np.concatenate(padded, axis=axis)


def refused_panel(photo: Path, row: dict[str, str], width: int) -> np.ndarray:
    """The photo and what ``--auto`` said of it: its status and reason."""
    image = fit(cv2.imread(str(photo)), width, round(width * 3 / 4))
    lines = [(f"{photo.name}: {row['status']}", REFUSED_INK)]
    lines += [(text, INK) for text in wrap(row["error"], width - 4)]
    return stack([image, caption(lines, width)], axis=0, gap=4)


def accepted_panel(photo: Path, row: dict[str, str], rectified: np.ndarray,
                   width: int) -> np.ndarray:
    """The photo beside its rectification, and the pose ``--auto`` estimated for it."""
    height = 250
    before = fit(cv2.imread(str(photo)), (width - MARGIN) * 2 // 5, height)
    after = fit(rectified, width - MARGIN - before.shape[1], height)
    lines = [(f"{photo.name}: {row['status']}, confidence {float(row['confidence']):.2f}",
              OK_INK),
             (f"pan {float(row['pan_deg']):.1f}, tilt {float(row['tilt_deg']):.1f}, roll "
              f"{float(row['roll_deg']):.1f} deg, focal {float(row['focal_px']):.0f} px "
              f"({row['focal_source']})", INK)]
    return stack([stack([before, after], axis=1), caption(lines, width)], axis=0, gap=4)


def title(text: str, width: int) -> np.ndarray:
    strip = np.full((30, width, 3), 255, np.uint8)
    cv2.putText(strip, text, (2, 22), FONT, 0.6, INK, 1, cv2.LINE_AA)
    return strip


def main() -> None:
    with tempfile.TemporaryDirectory() as temporary:
        work = Path(temporary)
        rows = auto_table(REFUSED + ACCEPTED, work)
        for photo in REFUSED:
            if rows[photo.name]["status"] == "ok":
                raise SystemExit(f"{photo.name} was not refused: the figure would mislead")
        rectified = {photo.name: cv2.imread(str(work / "out" / photo.name)) for photo in ACCEPTED
                     if rows[photo.name]["status"] == "ok"}
    if len(rectified) != len(ACCEPTED):
        raise SystemExit(f"not all of {[p.name for p in ACCEPTED]} were accepted")
    column = (WIDTH - MARGIN * (len(REFUSED) - 1)) // len(REFUSED)
    refused = stack([refused_panel(photo, rows[photo.name], column) for photo in REFUSED],
                    axis=1)
    half = (WIDTH - MARGIN) // 2
    accepted = stack([accepted_panel(photo, rows[photo.name], rectified[photo.name], half)
                      for photo in ACCEPTED], axis=1)
    figure = stack([title("gsrwt rectify PHOTOS --auto (no pose, no focal length given): refused",
                          WIDTH), refused,
                    title("... and ok: the photo and its rectification (--bbox full)", WIDTH),
                    accepted], axis=0)
    figure = np.pad(figure, ((MARGIN, MARGIN), (MARGIN, MARGIN), (0, 0)), constant_values=255)
    cv2.imwrite(str(ROOT / "docs" / "refusals.jpg"), figure, [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
