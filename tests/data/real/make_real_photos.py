"""Make the real photos of ``tests/data/real/`` from their sources, as ``photos.csv`` lists them.

    python tests/data/real/make_real_photos.py KIND=FOLDER ...

Each ``source`` of ``photos.csv`` is ``KIND:NAME``, read from the ``FOLDER`` given for its
``KIND`` (photos of a kind not given are left as they are):

- ``opencv``: Debian's ``opencv-doc`` folder ``/usr/share/doc/opencv-doc/examples/data``
  (OpenCV's ``samples/data``);
- ``skimage``: the ``skimage/data`` folder of a scikit-image wheel (``pip download --no-deps
  scikit-image``, unzipped);
- ``sklearn``: the ``sklearn/datasets/images`` folder of a scikit-learn wheel;
- ``scipy``: the ``scipy/misc`` folder of a SciPy 1.9.3 wheel (``ascent.dat``, a pickled
  array, and ``face.dat``, bz2-compressed RGB bytes: the last wheels that carried them);
- ``backgrounds``: a folder holding Debian's ``lomiri-wallpapers`` and
  ``lomiri-wallpapers-20.04`` ``/usr/share/backgrounds`` (``dpkg-deb -x`` of each package).

Each is shrunk with ``cv2.INTER_AREA`` so that its longer side is at most :data:`LONG_SIDE`
pixels (smaller photos keep their size), and written as ``image`` in JPEG quality
:data:`JPEG_QUALITY` (grey when its three channels are equal). The copies carry no EXIF, so no
focal length comes with them.
"""

from __future__ import annotations

import bz2
import csv
import pickle
import sys
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
LONG_SIDE = 640
JPEG_QUALITY = 90


def shrunk(image: np.ndarray, long_side: int = LONG_SIDE) -> np.ndarray:
    """``image`` with its longer side at most ``long_side`` (area averaging)."""
    height, width = image.shape[:2]
    factor = long_side / max(height, width)
    if factor >= 1:
        return image
    size = (round(width * factor), round(height * factor))
    return cv2.resize(image, size, interpolation=cv2.INTER_AREA)


def read_source(path: Path) -> np.ndarray | None:
    """A source photo as BGR pixels (SciPy's two ``.dat`` files decoded), None if unreadable."""
    if path.name == "ascent.dat":  # a pickled 512 x 512 array of grey levels (SciPy 1.9.3)
        with open(path, "rb") as file:
            grey = np.asarray(pickle.load(file)).clip(0, 255).astype(np.uint8)
        return cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    if path.name == "face.dat":  # bz2-compressed 768 x 1024 RGB bytes (SciPy 1.9.3)
        rgb = np.frombuffer(bz2.decompress(path.read_bytes()), np.uint8).reshape(768, 1024, 3)
        return np.ascontiguousarray(rgb[..., ::-1])
    return cv2.imread(str(path), cv2.IMREAD_COLOR)


def main() -> None:
    pairs = [argument.split("=", 1) for argument in sys.argv[1:]]
    if not pairs or any(len(pair) != 2 for pair in pairs):
        raise SystemExit(__doc__.split("\n\n")[1])
    folders = {kind: Path(folder) for kind, folder in pairs}
    with open(HERE / "photos.csv", newline="") as file:
        for row in csv.DictReader(file):
            kind, name = row["source"].split(":", 1)
            if kind not in folders:
                continue
            image = read_source(folders[kind] / name)
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
