"""EXIF orientation of image files: read from JPEG, PNG, TIFF and WebP, applied to pixels of
every sample type exactly as Pillow's ``ImageOps.exif_transpose`` shows them."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image, ImageOps

from gsrwt_cli.imaging.images import Scratch, displayed_pixels, file_orientation, read_image

ORIENTATION = 0x0112


def _exif(orientation: int) -> bytes:
    exif = Image.Exif()
    exif[ORIENTATION] = orientation
    return exif.tobytes()


@pytest.mark.parametrize("suffix", [".jpg", ".png", ".tif", ".webp"])
@pytest.mark.parametrize("orientation", [1, 2, 5, 6, 8])
def test_orientation_is_read_from_every_format_pillow_writes(tmp_path, suffix, orientation):
    path = tmp_path / f"photo{suffix}"
    Image.new("RGB", (40, 30), (10, 200, 30)).save(path, exif=_exif(orientation))
    assert file_orientation(path) == orientation


def test_no_exif_damaged_exif_and_invalid_values_are_upright(tmp_path):
    plain = tmp_path / "plain.png"
    Image.new("RGB", (8, 6)).save(plain)
    assert file_orientation(plain) == 1
    for value in (0, 9, 1000):
        path = tmp_path / f"bad{value}.jpg"
        Image.new("RGB", (8, 6)).save(path, exif=_exif(value))
        assert file_orientation(path) == 1
    damaged = tmp_path / "damaged.jpg"
    Image.new("RGB", (8, 6)).save(damaged, exif=b"Exif\x00\x00II*\x00\xff\xff\xff\x7f")
    assert file_orientation(damaged) == 1
    not_an_image = tmp_path / "text.jpg"
    not_an_image.write_bytes(b"not an image")
    assert file_orientation(not_an_image) == 1


@pytest.mark.parametrize("orientation", range(1, 9))
def test_pixels_are_turned_as_pillow_shows_them(tmp_path, orientation):
    """Pillow's own transpose of the file, against gsrwt's, for an RGB file; then the same
    turn on other sample types and layouts (uint16, float32 grey, BGRA, int16, float64
    BGRA), index for index."""
    rng = np.random.default_rng(orientation)
    rgb = rng.integers(0, 256, (5, 7, 3), dtype=np.uint8)
    path = tmp_path / "photo.png"
    Image.fromarray(rgb).save(path, exif=_exif(orientation))
    with Image.open(path) as image:
        shown = np.asarray(ImageOps.exif_transpose(image))
    bgr = read_image(path, orientation=file_orientation(path))
    assert np.array_equal(bgr[..., ::-1], shown)
    assert np.array_equal(read_image(path), rgb[..., ::-1])  # as stored, by default
    where = displayed_pixels(np.arange(35).reshape(5, 7), orientation)  # the stored index
    assert np.array_equal(displayed_pixels(rgb, orientation), shown)
    for pixels in (rgb.astype(np.uint16) * 257, rgb[..., 0].astype(np.float32) / 7,
                   np.dstack([rgb, rgb[..., :1]]), rgb.astype(np.int16) - 128,
                   np.dstack([rgb, rgb[..., :1]]).astype(np.float64) / 3):
        turned = displayed_pixels(pixels, orientation)
        assert turned.flags.c_contiguous and turned.dtype == pixels.dtype
        flat = pixels.reshape(35, *pixels.shape[2:])
        assert np.array_equal(turned, flat[where])


def test_scratch_turns_a_jpeg_decoded_for_the_warp(tmp_path):
    """The warp's JPEG path (decoded straight to BGRA into reused memory) turns it too."""
    rgb = np.zeros((30, 40, 3), np.uint8)
    rgb[:10, :20] = 255  # a white top-left block
    path = tmp_path / "phone.jpg"
    Image.fromarray(rgb).save(path, quality=100, exif=_exif(6))
    turned = Scratch().read(path, orientation=6)
    assert turned.shape == (40, 30, 3)
    assert turned[:20, -10:].min() > 200 and turned[20:, :20].max() < 50  # now top-right


def test_a_png_is_not_decoded_to_find_its_orientation(tmp_path):
    """An ``eXIf`` chunk after the pixels is found only by decoding them (Pillow's
    ``getexif`` would): not looked for, so a PNG without EXIF costs no decode."""
    import struct
    import zlib

    path = tmp_path / "late.png"
    Image.new("RGB", (40, 30)).save(path, exif=_exif(6))
    data = path.read_bytes()
    start = data.index(b"eXIf") - 4
    length = struct.unpack(">I", data[start:start + 4])[0]
    chunk = data[start:start + 12 + length]
    assert zlib.crc32(chunk[4:-4]) == struct.unpack(">I", chunk[-4:])[0]
    without = data[:start] + data[start + len(chunk):]
    end = without.index(b"IEND") - 4
    path.write_bytes(without[:end] + chunk + without[end:])  # eXIf moved after IDAT
    with Image.open(path) as image:
        assert image.getexif().get(ORIENTATION) == 6  # Pillow finds it, decoding the pixels
    assert file_orientation(path) == 1
