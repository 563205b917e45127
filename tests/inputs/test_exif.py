"""The focal length from EXIF: real EXIF written by Pillow and EXIF built byte by byte here
(both byte orders, any type and value a damaged file can hold), read by focal_from_exif."""

from __future__ import annotations

import io
import math
import struct

import cv2
import numpy as np
import pytest
from PIL import Image, TiffImagePlugin

from gsrwt_cli.inputs.exif import (
    ExifCamera,
    ExifFocal,
    camera_from_exif,
    focal_from_exif,
    read_exif_tags,
)
from tests.helpers.images import smooth_texture

RATIONAL, SRATIONAL, SHORT, LONG, ASCII, UNDEFINED = 5, 10, 3, 4, 2, 7
FOCAL_LENGTH, FOCAL_35MM = 0x920A, 0xA405
PLANE_X, PLANE_Y, PLANE_UNIT = 0xA20E, 0xA20F, 0xA210
PIXEL_X, PIXEL_Y = 0xA002, 0xA003


# --------------------------------------------------------------------------------------------
# EXIF built byte by byte (TIFF 6.0 / EXIF 2.3 layout), so that any value can be written

def _encode(order: str, kind: int, values) -> tuple[bytes, int]:
    if kind in (ASCII, UNDEFINED):
        return bytes(values), len(values)
    if kind in (RATIONAL, SRATIONAL):
        pair = "II" if kind == RATIONAL else "ii"
        return b"".join(struct.pack(order + pair, *value) for value in values), len(values)
    fmt = {SHORT: "H", LONG: "I"}[kind]
    return b"".join(struct.pack(order + fmt, value) for value in values), len(values)


def tiff_exif(exif: list[tuple[int, int, object]], order: str = "<") -> bytes:
    """An APP1 payload: ``Exif\\0\\0``, a TIFF header, IFD0 (Make and the Exif IFD pointer),
    the Exif IFD with ``exif``'s entries ``(tag, type, values)``, then the values' data."""
    ifd0 = [(0x010F, ASCII, b"Maker\x00"), (0x8769, LONG, [0])]
    exif = sorted(exif, key=lambda entry: entry[0])
    exif_offset = 8 + 2 + 12 * len(ifd0) + 4
    data_offset = exif_offset + 2 + 12 * len(exif) + 4
    data = bytearray()

    def ifd(entries) -> bytes:
        out = struct.pack(order + "H", len(entries))
        for tag, kind, values in entries:
            if tag == 0x8769:
                values = [exif_offset]
            raw, count = _encode(order, kind, values)
            if len(raw) <= 4:
                field = raw.ljust(4, b"\x00")
            else:
                field = struct.pack(order + "I", data_offset + len(data))
                data.extend(raw + b"\x00" * (len(raw) % 2))
            out += struct.pack(order + "HHI", tag, kind, count) + field
        return out + struct.pack(order + "I", 0)

    body = ifd(ifd0) + ifd(exif)
    head = (b"II" if order == "<" else b"MM") + struct.pack(order + "HI", 42, 8)
    return b"Exif\x00\x00" + head + body + bytes(data)


def jpeg_with_app1(payload: bytes, width: int = 64, height: int = 48) -> bytes:
    """An OpenCV-encoded JPEG with ``payload`` as an APP1 segment right after its SOI."""
    jpeg = cv2.imencode(".jpg", smooth_texture(height, width, 5))[1].tobytes()
    return jpeg[:2] + b"\xff\xe1" + struct.pack(">H", len(payload) + 2) + payload + jpeg[2:]


def pillow_jpeg(exif_ifd: dict[int, object], width: int = 64, height: int = 48) -> bytes:
    """A JPEG that Pillow writes, with its EXIF (``Image.save(exif=...)``)."""
    exif = Image.Exif()
    exif[0x010F], exif[0x0110] = "Phone maker", "Phone 12"
    exif.get_ifd(0x8769).update(exif_ifd)
    buffer = io.BytesIO()
    Image.new("RGB", (width, height), (90, 120, 150)).save(buffer, "JPEG", exif=exif)
    return buffer.getvalue()


# --------------------------------------------------------------------------------------------
# The two methods, on EXIF as Pillow writes it and as built here

PHONE = {  # a 1/2.55" phone sensor: 6.17 x 4.63 mm, 4000 x 3000 pixels, f = 4.73 mm
    FOCAL_LENGTH: TiffImagePlugin.IFDRational(473, 100),
    PLANE_X: TiffImagePlugin.IFDRational(4000 * 1000, 617),  # pixels per cm: 4000 / 0.617
    PLANE_Y: TiffImagePlugin.IFDRational(3000 * 1000, 463),
    PLANE_UNIT: 3,
    FOCAL_35MM: 26,
}


def test_focal_plane_resolution_gives_fx_and_fy_from_pillow_written_exif():
    found = focal_from_exif(pillow_jpeg(PHONE), 4000, 3000)
    assert isinstance(found, ExifFocal)
    focal_px, source = found  # unpacks as (focal_px, source)
    assert focal_px == (found.fx, found.fy)
    assert found.fx == pytest.approx(4.73 * 4000 / 6.17, rel=1e-12)  # 3066.45
    assert found.fy == pytest.approx(4.73 * 3000 / 4.63, rel=1e-12)  # 3064.79
    assert found.fx != found.fy
    assert source == "exif FocalLength 4.73 mm, FocalPlaneX/YResolution 6482.98/6479.48 per cm"


def test_the_photo_resized_since_scales_the_focal_plane_resolution():
    exif = {**PHONE, PIXEL_X: 4000, PIXEL_Y: 3000}
    found = focal_from_exif(pillow_jpeg(exif), 1000, 750)
    assert found.fx == pytest.approx(4.73 * 1000 / 6.17, rel=1e-12)
    assert found.fy == pytest.approx(4.73 * 750 / 4.63, rel=1e-12)
    assert found.source.endswith("; written 4000x3000, scaled to 1000x750")
    turned = focal_from_exif(pillow_jpeg(exif), 3000, 4000)  # stored turned a quarter
    assert turned.fx == pytest.approx(4.73 * 3000 / 4.63, rel=1e-12)
    assert turned.fy == pytest.approx(4.73 * 4000 / 6.17, rel=1e-12)
    cropped = focal_from_exif(pillow_jpeg(exif), 3000, 3000)  # another shape: the 35 mm tag
    assert cropped.focal_px == pytest.approx((26 * math.hypot(3000, 3000) / 43.27,) * 2, rel=1e-4)
    assert cropped.source.startswith("exif FocalLengthIn35mmFilm 26 mm")


@pytest.mark.parametrize("order", ["<", ">"], ids=["little-endian", "big-endian"])
def test_focal_plane_in_inches_from_exif_built_by_hand(order):
    # 50 mm on a camera whose focal plane has 5000 x 4800 pixels per inch (the EXIF default
    # unit, so the unit tag is left out): fx = 50 * 5000 / 25.4.
    payload = tiff_exif([(FOCAL_LENGTH, RATIONAL, [(50, 1)]), (PLANE_X, RATIONAL, [(5000, 1)]),
                         (PLANE_Y, RATIONAL, [(48000, 10)])], order)
    found = focal_from_exif(jpeg_with_app1(payload), 6000, 4000)
    assert found.focal_px == (pytest.approx(50 * 5000 / 25.4, rel=1e-12),
                              pytest.approx(50 * 4800 / 25.4, rel=1e-12))
    assert found.source.endswith("per inch, the EXIF default")
    # The same with the unit given as millimetres (TIFF/EP's 4): 100 pixels per mm.
    payload = tiff_exif([(FOCAL_LENGTH, RATIONAL, [(35, 1)]), (PLANE_X, RATIONAL, [(100, 1)]),
                         (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])], order)
    assert focal_from_exif(jpeg_with_app1(payload), 4000, 3000).focal_px == (3500.0, 3500.0)


@pytest.mark.parametrize("order", ["<", ">"], ids=["little-endian", "big-endian"])
def test_35mm_equivalent_by_the_diagonal(order):
    payload = tiff_exif([(FOCAL_35MM, SHORT, [26])], order)
    found = focal_from_exif(jpeg_with_app1(payload), 4000, 3000)
    expected = 26 * math.hypot(4000, 3000) / 43.27  # 3004.4; 43.27 mm: the 36x24 diagonal
    assert found.fx == found.fy == pytest.approx(expected, rel=1e-4)
    assert found.source == "exif FocalLengthIn35mmFilm 26 mm over the 4000x3000 diagonal"
    pillow = focal_from_exif(pillow_jpeg({FOCAL_35MM: 26}), 4000, 3000)
    assert pillow.focal_px == found.focal_px


def test_the_focal_plane_comes_first_and_the_35mm_tag_is_the_fallback():
    assert focal_from_exif(pillow_jpeg(PHONE), 4000, 3000).source.startswith("exif FocalLength ")
    no_unit_length = {**PHONE, PLANE_UNIT: 1}  # "no absolute unit": cannot give mm
    found = focal_from_exif(pillow_jpeg(no_unit_length), 4000, 3000)
    assert found.source.startswith("exif FocalLengthIn35mmFilm")
    without_plane = {FOCAL_LENGTH: PHONE[FOCAL_LENGTH], FOCAL_35MM: 26}  # most phones
    found = focal_from_exif(pillow_jpeg(without_plane), 4000, 3000)
    assert found.fx == pytest.approx(26 * 5000 / math.hypot(36, 24), rel=1e-12)  # 3004.63


# --------------------------------------------------------------------------------------------
# Nothing usable: None, never an exception

def _no_exif_files() -> dict[str, bytes]:
    jpeg = cv2.imencode(".jpg", smooth_texture(48, 64, 1))[1].tobytes()
    png = cv2.imencode(".png", smooth_texture(48, 64, 1))[1].tobytes()
    return {"jpeg-without-exif": jpeg, "png": png, "empty": b"", "text": b"not an image",
            "truncated-jpeg": jpeg[:20], "only-focal-mm": pillow_jpeg({FOCAL_LENGTH: 4.73}),
            "exif-without-focal": pillow_jpeg({0x829A: TiffImagePlugin.IFDRational(1, 100)})}


@pytest.mark.parametrize("name", list(_no_exif_files()))
def test_no_usable_exif_is_none(name):
    assert focal_from_exif(_no_exif_files()[name], 64, 48) is None


GARBAGE = {
    "zero-denominator": [(FOCAL_LENGTH, RATIONAL, [(473, 0)]), (PLANE_X, RATIONAL, [(100, 1)]),
                         (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "zero-focal": [(FOCAL_LENGTH, RATIONAL, [(0, 1)]), (PLANE_X, RATIONAL, [(100, 1)]),
                   (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "negative-focal": [(FOCAL_LENGTH, SRATIONAL, [(-50, 1)]), (PLANE_X, RATIONAL, [(100, 1)]),
                       (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "text-focal": [(FOCAL_LENGTH, ASCII, b"50mm\x00"), (PLANE_X, RATIONAL, [(100, 1)]),
                   (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "unknown-unit": [(FOCAL_LENGTH, RATIONAL, [(50, 1)]), (PLANE_X, RATIONAL, [(100, 1)]),
                     (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [9])],
    "absurd-focal": [(FOCAL_LENGTH, RATIONAL, [(4_000_000_000, 1)]),
                     (PLANE_X, RATIONAL, [(100, 1)]), (PLANE_Y, RATIONAL, [(100, 1)]),
                     (PLANE_UNIT, SHORT, [4])],
    "tiny-focal": [(FOCAL_LENGTH, RATIONAL, [(1, 1_000_000)]), (PLANE_X, RATIONAL, [(100, 1)]),
                   (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "pixels-10-times-wider": [(FOCAL_LENGTH, RATIONAL, [(50, 1)]),
                              (PLANE_X, RATIONAL, [(100, 1)]), (PLANE_Y, RATIONAL, [(10, 1)]),
                              (PLANE_UNIT, SHORT, [4])],
    "two-values": [(FOCAL_LENGTH, RATIONAL, [(50, 1), (60, 1)]), (PLANE_X, RATIONAL, [(100, 1)]),
                   (PLANE_Y, RATIONAL, [(100, 1)]), (PLANE_UNIT, SHORT, [4])],
    "35mm-zero-unknown": [(FOCAL_35MM, SHORT, [0])],
    "35mm-absurd": [(FOCAL_35MM, LONG, [4_000_000_000])],
    "35mm-undefined-bytes": [(FOCAL_35MM, UNDEFINED, b"\x1a\x00\x00\x00")],
}


@pytest.mark.parametrize("name", list(GARBAGE))
def test_zero_garbage_and_absurd_values_are_none(name):
    data = jpeg_with_app1(tiff_exif(GARBAGE[name]))
    assert read_exif_tags(data) is not None  # the EXIF itself reads
    assert focal_from_exif(data, 4000, 3000) is None


def test_garbage_in_the_focal_plane_falls_back_to_the_35mm_tag():
    entries = [*GARBAGE["zero-denominator"], (FOCAL_35MM, SHORT, [28])]
    found = focal_from_exif(jpeg_with_app1(tiff_exif(entries)), 4000, 3000)
    assert found.fx == pytest.approx(28 * 5000 / 43.27, rel=1e-4)


def test_damaged_exif_never_raises():
    good = tiff_exif([(FOCAL_LENGTH, RATIONAL, [(473, 100)]), (PLANE_X, RATIONAL, [(648, 1)]),
                      (PLANE_Y, RATIONAL, [(648, 1)]), (PLANE_UNIT, SHORT, [4]),
                      (FOCAL_35MM, SHORT, [26])])
    rng = np.random.default_rng(7)
    found = 0
    for trial in range(600):
        payload = bytearray(good)
        if trial % 5 == 0:
            payload = payload[: int(rng.integers(6, len(payload)))]
        else:
            for _ in range(int(rng.integers(1, 9))):
                payload[int(rng.integers(6, len(payload)))] = int(rng.integers(0, 256))
        result = focal_from_exif(jpeg_with_app1(bytes(payload)), 4000, 3000)
        if result is not None:
            found += 1
            low, high = 0.05 * 5000, 500 * 5000
            assert low <= result.fx <= high and low <= result.fy <= high
            assert 0.5 <= result.fx / result.fy <= 2
    assert 0 < found < 600  # some damage leaves the focal tags readable, some does not


def test_the_image_size_must_be_given():
    with pytest.raises(ValueError, match="positive whole numbers"):
        focal_from_exif(pillow_jpeg(PHONE), 0, 3000)


# --------------------------------------------------------------------------------------------
# EXIF orientation: the tags describe the stored pixels


@pytest.mark.parametrize("orientation", [1, 3, 6, 8])
def test_a_photo_turned_a_quarter_swaps_fx_and_fy(tmp_path, orientation):
    """The focal plane's X resolution is along the stored rows: displayed turned a quarter
    (6, 8) it is along the displayed columns' other axis, so fx and fy swap; the 35 mm
    equivalent, by the diagonal, does not change."""
    from gsrwt_cli.inputs.focal import exif_focal

    exif = Image.Exif()
    exif[0x0112] = orientation
    exif.get_ifd(0x8769).update({**PHONE, PIXEL_X: 4000, PIXEL_Y: 3000})  # stored, scaled
    path = tmp_path / "phone.jpg"
    Image.new("RGB", (400, 300), (90, 120, 150)).save(path, "JPEG", exif=exif)
    found = exif_focal(path, orientation)
    along_width, along_height = 4.73 * 4000 / 6.17 / 10, 4.73 * 3000 / 4.63 / 10  # 400x300
    if orientation in (6, 8):
        assert found.focal_px == pytest.approx((along_height, along_width), rel=1e-12)
        assert f"turned by EXIF orientation {orientation}" in found.source
    else:
        assert found.focal_px == pytest.approx((along_width, along_height), rel=1e-12)
    exif.get_ifd(0x8769).update({PLANE_X: 0})  # no focal plane: the 35 mm tag, unturned
    Image.new("RGB", (400, 300)).save(path, "JPEG", exif=exif)
    assert exif_focal(path, orientation).fx == pytest.approx(26 * 500 / 43.2666, rel=1e-4)


# --------------------------------------------------------------------------------------------
# The camera and lens EXIF names (lens profiles, gsrwt_cli/inputs/lensfun.py)


def test_the_camera_and_lens_as_exif_names_them():
    found = camera_from_exif(pillow_jpeg({0xA433: "Lens maker", 0xA434: "Zoom 4-12mm\x00\x00",
                                          FOCAL_LENGTH: TiffImagePlugin.IFDRational(473, 100)}))
    assert found == ExifCamera("Phone maker", "Phone 12", "Lens maker", "Zoom 4-12mm", 4.73)
    assert camera_from_exif(pillow_jpeg({})) == ExifCamera("Phone maker", "Phone 12", "", "",
                                                           None)
    # No model (the built EXIF has a Make only), no EXIF: nothing to look a profile up by.
    assert camera_from_exif(jpeg_with_app1(tiff_exif([(FOCAL_LENGTH, RATIONAL,
                                                       [(473, 100)])]))) is None
    assert camera_from_exif(cv2.imencode(".jpg", smooth_texture(8, 8))[1].tobytes()) is None


def test_damaged_camera_names_never_raise():
    good = pillow_jpeg({0xA434: "Zoom 4-12mm", FOCAL_LENGTH: TiffImagePlugin.IFDRational(5, 1)})
    start = good.index(b"Exif\x00\x00") + 6
    end = start + struct.unpack(">H", good[start - 8:start - 6])[0] - 8
    rng = np.random.default_rng(11)
    named = 0
    for trial in range(300):
        payload = bytearray(good)
        for _ in range(int(rng.integers(1, 9))):
            payload[int(rng.integers(start, end))] = int(rng.integers(0, 256))
        found = camera_from_exif(bytes(payload))
        assert found is None or all(isinstance(text, str) and text.isprintable()
                                    for text in found[:4]), (trial, found)
        named += found is not None
    assert 0 < named < 300  # some damage leaves the names readable, some does not
