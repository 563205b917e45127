"""Pillow against exifread for reading a photo's EXIF focal length (issue "Real cameras", 6).

Measures, for each library: the import time (a fresh interpreter, best of 5), the time to
read the focal-length tags of a phone-sized JPEG (4000x3000, about 5 MB, EXIF with an Exif
IFD and a GPS IFD, written by Pillow; best of 20), and robustness on malformed EXIF: 3000
copies of that EXIF with 1 to 16 random bytes changed or the segment cut short, counting
the exceptions that escape (by type), anything written to stderr or warned, and the slowest
read.

    python benchmarks/bench_exif.py
"""

from __future__ import annotations

import collections
import contextlib
import io
import logging
import struct
import subprocess
import sys
import time
import warnings

import cv2
import numpy as np

IMPORTS = {"pillow": "import PIL.Image", "exifread": "import exifread"}


def phone_exif() -> bytes:
    """An APP1 payload (``Exif\\0\\0`` + TIFF) as a phone writes one, made by Pillow."""
    from PIL import Image, TiffImagePlugin

    rational = TiffImagePlugin.IFDRational
    exif = Image.Exif()
    exif[0x010F], exif[0x0110], exif[0x0131] = "Phone maker", "Phone 12", "Camera app 1.0"
    exif[0x0132] = "2026:01:02 03:04:05"
    exif[0x011A], exif[0x011B], exif[0x0128] = rational(72, 1), rational(72, 1), 2
    ifd = exif.get_ifd(0x8769)
    ifd[0x829A], ifd[0x829D], ifd[0x8827] = rational(1, 120), rational(18, 10), 100
    ifd[0x9003] = "2026:01:02 03:04:05"
    ifd[0x920A], ifd[0xA405] = rational(473, 100), 26
    ifd[0xA20E], ifd[0xA20F] = rational(4000 * 1000, 6170), rational(3000 * 1000, 4630)
    ifd[0xA210], ifd[0xA002], ifd[0xA003] = 4, 4000, 3000
    gps = exif.get_ifd(0x8825)
    gps[1], gps[2] = "N", (rational(52, 1), rational(30, 1), rational(1234, 100))
    return exif.tobytes()


def jpeg_with_exif(jpeg: bytes, payload: bytes) -> bytes:
    """``jpeg`` with an APP1 segment holding ``payload`` right after its SOI."""
    return jpeg[:2] + b"\xff\xe1" + struct.pack(">H", len(payload) + 2) + payload + jpeg[2:]


def read_pillow(data: bytes) -> object:
    from PIL import Image

    with Image.open(io.BytesIO(data)) as image:
        exif = image.getexif()
        ifd = exif.get_ifd(0x8769)
        return [ifd.get(tag) for tag in (0x920A, 0xA20E, 0xA20F, 0xA210, 0xA405)]


def read_exifread(data: bytes) -> object:
    import exifread

    tags = exifread.process_file(io.BytesIO(data), details=False, extract_thumbnail=False)
    names = ("FocalLength", "FocalPlaneXResolution", "FocalPlaneYResolution",
             "FocalPlaneResolutionUnit", "FocalLengthIn35mmFilm")
    return [tags.get(f"EXIF {name}") for name in names]


READERS = {"pillow": read_pillow, "exifread": read_exifread}


def import_time(statement: str) -> float:
    code = f"import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
    runs = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                 check=True).stdout) for _ in range(5)]
    return min(runs)


def mutations(payload: bytes, count: int, seed: int = 0) -> list[bytes]:
    rng = np.random.default_rng(seed)
    out = []
    for index in range(count):
        data = bytearray(payload)
        if index % 10 == 0:  # cut short
            data = data[: int(rng.integers(6, len(data)))]
        else:
            for _ in range(int(rng.integers(1, 17))):
                data[int(rng.integers(6, len(data)))] = int(rng.integers(0, 256))
        out.append(bytes(data))
    return out


def main() -> None:
    grey = np.random.default_rng(1).integers(0, 256, (3000, 4000), dtype=np.uint8)
    image = cv2.GaussianBlur(cv2.merge([grey, grey[::-1], grey[:, ::-1]]), (5, 5), 0)
    jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 92])[1].tobytes()
    payload = phone_exif()
    photo = jpeg_with_exif(jpeg, payload)
    small = cv2.imencode(".jpg", image[:48, :64])[1].tobytes()
    fuzzed = [jpeg_with_exif(small, data) for data in mutations(payload, 3000)]
    print(f"phone JPEG: {len(photo) / 1e6:.1f} MB, EXIF {len(payload)} bytes")
    for name, reader in READERS.items():
        print(f"{name}: import {import_time(IMPORTS[name]) * 1e3:.1f} ms", end="")
        reader(photo)
        times = []
        for _ in range(20):
            start = time.perf_counter()
            values = reader(photo)
            times.append(time.perf_counter() - start)
        print(f", read {min(times) * 1e3:.3f} ms per file -> {values}")
        escaped: collections.Counter[str] = collections.Counter()
        noisy = slowest = 0.0
        log = io.StringIO()
        handler = logging.StreamHandler(log)
        logging.getLogger().addHandler(handler)
        for data in fuzzed:
            stderr = io.StringIO()
            start = time.perf_counter()
            with warnings.catch_warnings(record=True) as caught, \
                    contextlib.redirect_stderr(stderr):
                warnings.simplefilter("always")
                try:
                    reader(data)
                except Exception as error:  # noqa: BLE001 - counting what escapes
                    escaped[type(error).__name__] += 1
            slowest = max(slowest, time.perf_counter() - start)
            noisy += bool(caught or stderr.getvalue())
        logging.getLogger().removeHandler(handler)
        logged = len(log.getvalue().splitlines())
        print(f"  fuzz {len(fuzzed)} files: exceptions {dict(escaped) or 'none'}, "
              f"{sum(escaped.values())} in all; warned/printed on {int(noisy)}, logged "
              f"{logged} lines; slowest {slowest * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
