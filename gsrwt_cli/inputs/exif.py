"""The focal length in pixels from a photo's EXIF, for images whose focal length is given
nowhere else (issue "Real cameras", item 6).

:func:`focal_from_exif` tries, in order:

1. ``FocalLength`` (mm) with ``FocalPlaneXResolution`` / ``FocalPlaneYResolution`` (pixels
   per ``FocalPlaneResolutionUnit``: 2 inch, the EXIF default when the tag is missing, 3 cm,
   and TIFF/EP's 4 mm and 5 um): ``fx = F * Rx``, ``fy = F * Ry`` in pixels per mm, so non-square
   pixels give ``fx != fy``. These resolutions count pixels of the image the camera wrote
   (``PixelXDimension`` x ``PixelYDimension``); an image resized since (the same aspect) is
   scaled to its own size, one turned a quarter (the dimensions swapped) swaps them, and one
   of another shape (cropped) cannot use them.
2. ``FocalLengthIn35mmFilm`` (0 means unknown in EXIF), by the diagonal:
   ``f = F35 * sqrt(W^2 + H^2) / 43.27`` (43.27 mm: the diagonal of the 36 x 24 mm frame),
   square pixels.

EXIF is read by Pillow (``Image.open`` reads the header, never the pixels), not by a parser of
gsrwt's own: ``benchmarks/bench_exif.py`` measured it against exifread (import 9.6 against
15 ms, 0.13 ms per phone photo both, and on 3000 damaged EXIF blocks no exception escaped
Pillow, where 134 ``IndexError`` escaped exifread, which also logged 2400 lines and took up to
150 ms on one). Pillow's warnings about damaged EXIF are silenced while reading; whatever it
raises on a damaged file means "no EXIF focal length". The tags describe the stored pixels
(``W, H`` are the stored image's); for a photo whose EXIF orientation turns it a quarter,
:func:`~gsrwt_cli.inputs.focal.exif_focal` swaps ``fx`` and ``fy``.

:func:`camera_from_exif` reads the camera and lens the EXIF names (``Make``, ``Model``,
``LensMake``, ``LensModel``) and ``FocalLength``: what finds a lens profile
(:mod:`~gsrwt_cli.inputs.lensfun`).
"""

from __future__ import annotations

import io
import math
import numbers
import warnings
from typing import NamedTuple

from ..geometry.camera import MAX_FOCAL_PX

#: The diagonal of a 36 x 24 mm frame, in mm.
FULL_FRAME_DIAGONAL_MM = math.hypot(36.0, 24.0)  # 43.2666
#: Millimetres per ``FocalPlaneResolutionUnit`` (EXIF: 2 inch, 3 cm; TIFF/EP: 4 mm, 5 um).
#: Unit 1 ("no absolute unit") cannot give a length.
UNIT_MM = {2: 25.4, 3: 10.0, 4: 1.0, 5: 0.001}
#: EXIF's default ``FocalPlaneResolutionUnit`` when the tag is missing: inch.
DEFAULT_UNIT = 2
#: A focal length from EXIF is kept only between these multiples of the image diagonal (a
#: 35 mm-equivalent of 2 to 20 000 mm): outside, the tags are garbage, not a lens.
FOCAL_DIAGONALS = (0.05, 500.0)
#: The focal plane's pixels may be this much taller than wide, or wider than tall, at most.
MAX_PIXEL_ASPECT = 2.0
#: Relative difference in aspect ratio below which a resized image counts as the same shape.
ASPECT_TOLERANCE = 0.01

# EXIF tags (Exif IFD, 0x8769).
_EXIF_IFD = 0x8769
_FOCAL_LENGTH = 0x920A
_FOCAL_35MM = 0xA405
_PLANE_X, _PLANE_Y, _PLANE_UNIT = 0xA20E, 0xA20F, 0xA210
_PIXEL_X, _PIXEL_Y = 0xA002, 0xA003


class ExifFocal(NamedTuple):
    """A focal length from EXIF: ``focal_px = (fx, fy)`` in pixels, and where it came from."""

    focal_px: tuple[float, float]
    source: str

    @property
    def fx(self) -> float:
        return self.focal_px[0]

    @property
    def fy(self) -> float:
        return self.focal_px[1]


def read_exif_tags(data: bytes) -> dict[int, object] | None:
    """The Exif IFD's tags of an image file's bytes (JPEG, TIFF, WebP, PNG), by Pillow; None
    when the file has none or Pillow cannot read them."""
    from PIL import Image  # Pillow only when EXIF is wanted

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Corrupt EXIF data", "Truncated File Read", ...
        try:
            with Image.open(io.BytesIO(data)) as image:
                tags = dict(image.getexif().get_ifd(_EXIF_IFD))
        except Exception:  # noqa: BLE001 - a damaged file of a third-party parser: no EXIF
            return None
    return tags or None


def focal_from_exif(data: bytes, width: int, height: int) -> ExifFocal | None:
    """The focal length in pixels of the image file ``data`` of ``width`` x ``height``
    pixels, from its EXIF (module docstring), or None if EXIF does not give a usable one.

    Never raises for what a file holds: missing, zero, negative, non-finite, mistyped or
    absurd values mean None (or the next method); ``width``/``height`` must be positive.
    """
    if not (isinstance(width, numbers.Integral) and isinstance(height, numbers.Integral)
            and width > 0 and height > 0):
        raise ValueError(f"width and height must be positive whole numbers, got {width}x{height}")
    tags = read_exif_tags(data)
    if tags is None:
        return None
    return _from_focal_plane(tags, width, height) or _from_35mm(tags, width, height)


def _positive(value: object) -> float | None:
    """A positive finite number from a tag's value (a rational, an integer, one-element
    tuple), else None."""
    if isinstance(value, tuple) and len(value) == 1:
        value = value[0]
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    try:
        number = float(value)  # an IFDRational with a zero denominator is nan
    except (OverflowError, ValueError, ZeroDivisionError):
        return None
    return number if math.isfinite(number) and number > 0 else None


def _plausible(focal: float, width: int, height: int) -> bool:
    low, high = FOCAL_DIAGONALS
    return low * math.hypot(width, height) <= focal <= high * math.hypot(width, height) and (
        focal < MAX_FOCAL_PX
    )


def _from_focal_plane(tags: dict[int, object], width: int, height: int) -> ExifFocal | None:
    focal_mm = _positive(tags.get(_FOCAL_LENGTH))
    per_unit_x, per_unit_y = _positive(tags.get(_PLANE_X)), _positive(tags.get(_PLANE_Y))
    if focal_mm is None or per_unit_x is None or per_unit_y is None:
        return None
    unit = tags.get(_PLANE_UNIT, DEFAULT_UNIT)
    if isinstance(unit, tuple) and len(unit) == 1:
        unit = unit[0]
    if isinstance(unit, bool) or unit not in UNIT_MM:
        return None
    unit_text = {2: "inch", 3: "cm", 4: "mm", 5: "um"}[unit]
    if _PLANE_UNIT not in tags:
        unit_text += ", the EXIF default"
    per_mm_x, per_mm_y = per_unit_x / UNIT_MM[unit], per_unit_y / UNIT_MM[unit]
    note = ""
    written = (_positive(tags.get(_PIXEL_X)), _positive(tags.get(_PIXEL_Y)))
    if None not in written and written != (width, height):
        written_w, written_h = written
        if (written_h, written_w) == (width, height):  # turned a quarter since
            per_mm_x, per_mm_y = per_mm_y, per_mm_x
            note = f"; written {written_w:g}x{written_h:g}, turned"
        elif abs((width / height) / (written_w / written_h) - 1) <= ASPECT_TOLERANCE:
            per_mm_x, per_mm_y = per_mm_x * width / written_w, per_mm_y * height / written_h
            note = f"; written {written_w:g}x{written_h:g}, scaled to {width}x{height}"
        else:
            return None  # cropped: the resolutions are not this image's
    fx, fy = focal_mm * per_mm_x, focal_mm * per_mm_y
    if not (_plausible(fx, width, height) and _plausible(fy, width, height)):
        return None
    if not 1 / MAX_PIXEL_ASPECT <= fx / fy <= MAX_PIXEL_ASPECT:
        return None
    return ExifFocal(
        (fx, fy),
        f"exif FocalLength {focal_mm:g} mm, FocalPlaneX/YResolution {per_unit_x:g}/"
        f"{per_unit_y:g} per {unit_text}{note}",
    )


def _from_35mm(tags: dict[int, object], width: int, height: int) -> ExifFocal | None:
    focal_35 = _positive(tags.get(_FOCAL_35MM))  # 0: unknown, refused here
    if focal_35 is None:
        return None
    focal = focal_35 * math.hypot(width, height) / FULL_FRAME_DIAGONAL_MM
    if not _plausible(focal, width, height):
        return None
    return ExifFocal(
        (focal, focal),
        f"exif FocalLengthIn35mmFilm {focal_35:g} mm over the {width}x{height} diagonal",
    )


# IFD0's camera and the Exif IFD's lens (EXIF 2.3), for lens profiles (inputs/lensfun.py).
_MAKE, _MODEL = 0x010F, 0x0110
_LENS_MAKE, _LENS_MODEL = 0xA433, 0xA434
#: Longest EXIF text kept (a make or model longer than this is garbage, not a name).
NAME_LIMIT = 200


class ExifCamera(NamedTuple):
    """The camera and lens a photo's EXIF names (``""`` when it names none) and its
    ``FocalLength`` in mm (None when absent or unusable): what finds a lens profile."""

    make: str
    model: str
    lens_make: str
    lens_model: str
    focal_mm: float | None


def camera_from_exif(data: bytes) -> ExifCamera | None:
    """The camera, lens and focal length in mm of the image file ``data`` (its head is
    enough), by Pillow as :func:`read_exif_tags`; None when it names no camera model. Never
    raises for what a file holds."""
    from PIL import Image

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            with Image.open(io.BytesIO(data)) as image:
                exif = image.getexif()
                top = {tag: exif.get(tag) for tag in (_MAKE, _MODEL)}
                tags = dict(exif.get_ifd(_EXIF_IFD))
        except Exception:  # noqa: BLE001 - a damaged file of a third-party parser: no EXIF
            return None
    found = ExifCamera(_text(top[_MAKE]), _text(top[_MODEL]), _text(tags.get(_LENS_MAKE)),
                       _text(tags.get(_LENS_MODEL)), _positive(tags.get(_FOCAL_LENGTH)))
    return found if found.model else None


def _text(value: object) -> str:
    """An EXIF ASCII tag as one line of printable text (NULs and padding stripped), ``""``
    when it is not text or too long to be a name."""
    if isinstance(value, bytes):
        value = value.decode("latin-1")
    if not isinstance(value, str):
        return ""
    text = " ".join("".join(c for c in value.split("\0")[0] if c.isprintable()).split())
    return text if len(text) <= NAME_LIMIT else ""
