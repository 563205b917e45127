"""Make the real photos of ``tests/data/real/`` from their sources, as ``photos.csv`` lists them.

    python tests/data/real/make_real_photos.py OPENCV_DATA SKIMAGE_DATA

``OPENCV_DATA`` is Debian's ``opencv-doc`` folder ``/usr/share/doc/opencv-doc/examples/data``
(OpenCV's ``samples/data``), ``SKIMAGE_DATA`` the ``skimage/data`` folder of a scikit-image
wheel (``pip download --no-deps scikit-image``, unzipped). Each ``source`` of ``photos.csv``
(``opencv:NAME`` or ``skimage:NAME``) is read, shrunk with ``cv2.INTER_AREA`` so that its
longer side is at most :data:`LONG_SIDE` pixels (smaller photos keep their size), and written
as ``image`` in JPEG quality :data:`JPEG_QUALITY` (grey when its three channels are equal). The
copies carry no EXIF, so no focal length comes with them.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
LONG_SIDE = 640
JPEG_QUALITY = 90


def shrunk(image: np.ndarray) -> np.ndarray:
    """``image`` with its longer side at most :data:`LONG_SIDE` (area averaging)."""
    height, width = image.shape[:2]
    factor = LONG_SIDE / max(height, width)
    if factor >= 1:
        return image
    size = (round(width * factor), round(height * factor))
    return cv2.resize(image, size, interpolation=cv2.INTER_AREA)


def main() -> None:
    if len(sys.argv) != 3:
        raise SystemExit(__doc__.split("\n\n")[1])
    folders = {"opencv": Path(sys.argv[1]), "skimage": Path(sys.argv[2])}
    with open(HERE / "photos.csv", newline="") as file:
        for row in csv.DictReader(file):
            kind, name = row["source"].split(":", 1)
            image = cv2.imread(str(folders[kind] / name), cv2.IMREAD_COLOR)
            if image is None:
                raise SystemExit(f"{row['source']}: cannot read {folders[kind] / name}")
            grey = bool((image[..., 0] == image[..., 1]).all() and
                        (image[..., 1] == image[..., 2]).all())
            out = shrunk(image[..., 0] if grey else image)
            cv2.imwrite(str(HERE / row["image"]), out, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            print(f"{row['image']}: {image.shape[1]}x{image.shape[0]} -> "
                  f"{out.shape[1]}x{out.shape[0]}{' grey' if grey else ''}")


if __name__ == "__main__":
    main()
