"""``io/metadata.py``: a photo's EXIF, cleaned, and gsrwt's XMP record, put into the bytes
OpenCV encoded, for JPEG, PNG, WebP and TIFF, the pixels untouched.

The EXIF is written by Pillow and read back by exifread (and tifffile for TIFF's own tags);
the XMP is found by Pillow and parsed by the standard library's XML parser; pixels are
decoded by OpenCV from the file with and without the metadata (the same encoder's bytes, so
exactly equal).
"""

from __future__ import annotations

import io

import cv2
import numpy as np
import pytest
import tifffile
from PIL import Image

from gsrwt_cli.io.metadata import (
    MetadataError,
    PhotoExif,
    exif_block,
    photo_exif,
    with_metadata,
)
from tests.helpers.exif_photos import (
    EXPECTED,
    camera_exif,
    exif_tags,
    gsrwt_record,
    riff_chunk,
    xmp_of,
)

RECORD = {"Pan": "20", "Tilt": "-7.5", "Homography": "1 0 0 0 1 0 0 0 1", "Lens": "a<b&\"c\""}
RNG = np.random.default_rng(5)
#: Images OpenCV encodes into each format, as gsrwt writes them: (extension, pixels, params).
ENCODED = {
    "jpg-colour": (".jpg", RNG.integers(0, 256, (30, 50, 3), np.uint8), []),
    "jpg-grey": (".jpg", RNG.integers(0, 256, (30, 50), np.uint8), []),
    "png-16bit": (".png", RNG.integers(0, 65536, (30, 50, 3), np.uint16), []),
    "png-alpha": (".png", RNG.integers(0, 256, (30, 50, 4), np.uint8), []),
    "webp-lossy": (".webp", RNG.integers(0, 256, (30, 50, 3), np.uint8),
                   [cv2.IMWRITE_WEBP_QUALITY, 90]),
    "webp-lossy-alpha": (".webp", RNG.integers(0, 256, (30, 50, 4), np.uint8),
                         [cv2.IMWRITE_WEBP_QUALITY, 80]),
    "webp-lossless": (".webp", RNG.integers(0, 256, (30, 50, 3), np.uint8),
                      [cv2.IMWRITE_WEBP_QUALITY, 100]),
    "webp-lossless-alpha": (".webp", RNG.integers(0, 256, (30, 50, 4), np.uint8),
                            [cv2.IMWRITE_WEBP_QUALITY, 100]),
    "tif-float": (".tif", RNG.random((30, 50)).astype(np.float32), []),
    "tif-colour": (".tif", RNG.integers(0, 256, (30, 50, 3), np.uint8), []),
    "tif-16bit-alpha": (".tif", RNG.integers(0, 65536, (30, 50, 4), np.uint16), []),
}
SIZE = (50, 30)


def encoded(name: str) -> tuple[str, bytes]:
    extension, pixels, params = ENCODED[name]
    ok, data = cv2.imencode(extension, pixels, params)
    assert ok
    return extension, data.tobytes()


def camera_jpeg(orientation: int = 6) -> bytes:
    buffer = io.BytesIO()
    Image.new("RGB", (60, 40), "grey").save(buffer, "JPEG", exif=camera_exif(orientation))
    return buffer.getvalue()


def decoded(data: bytes) -> np.ndarray:
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)


def test_the_camera_photo_carries_what_the_output_must_lose() -> None:
    """The input of these tests has a thumbnail, a maker's note and a subject area, and its
    orientation turns it: the tests below can fail."""
    tags = exif_tags(camera_jpeg())
    assert "JPEGThumbnail" in tags and any(name.startswith("Thumbnail") for name in tags)
    assert "EXIF MakerNote" in tags and "EXIF SubjectArea" in tags
    assert tags["Image Orientation"] == "Rotated 90 CW"
    assert {name: tags.get(name) for name in EXPECTED} == EXPECTED


@pytest.mark.parametrize("name", list(ENCODED))
def test_exif_and_record_go_into_each_format_and_the_pixels_stay(name: str) -> None:
    extension, plain = encoded(name)
    photo = photo_exif(camera_jpeg())
    assert photo is not None
    written = with_metadata(plain, extension, SIZE, photo, RECORD)

    assert written != plain
    got, want = decoded(written), decoded(plain)
    assert got.dtype == want.dtype and np.array_equal(got, want)

    tags = exif_tags(written)
    assert {name: tags.get(name) for name in EXPECTED} == EXPECTED
    assert tags["Image Orientation"] == "Horizontal (normal)"
    assert (tags["EXIF ExifImageWidth"], tags["EXIF ExifImageLength"]) == ("50", "30")
    assert not [name for name in tags if "Thumbnail" in name or "MakerNote" in name]
    assert "EXIF SubjectArea" not in tags
    assert gsrwt_record(xmp_of(written)) == RECORD


def test_a_webp_says_in_its_extended_header_what_it_carries() -> None:
    for name in ("webp-lossy", "webp-lossless", "webp-lossless-alpha", "webp-lossy-alpha"):
        extension, plain = encoded(name)
        written = with_metadata(plain, extension, SIZE, photo_exif(camera_jpeg()), RECORD)
        header = riff_chunk(written, b"VP8X")
        assert written[12:16] == b"VP8X" and header is not None, name
        flags = header[0]
        assert flags & 0x08 and flags & 0x04, name  # EXIF, XMP
        assert bool(flags & 0x10) == name.endswith("alpha"), name
        assert int.from_bytes(header[4:7], "little") + 1 == SIZE[0]
        assert int.from_bytes(header[7:10], "little") + 1 == SIZE[1]
        assert int.from_bytes(written[4:8], "little") == len(written) - 8
        with Image.open(io.BytesIO(written)) as image:  # libwebp's demuxer, through Pillow
            assert image.size == SIZE and image.getexif()[0x010F] == "Canon"


def test_a_tiff_keeps_its_own_tags_and_gains_the_photo_s() -> None:
    extension, plain = encoded("tif-16bit-alpha")
    written = with_metadata(plain, extension, SIZE, photo_exif(camera_jpeg()), RECORD)
    with tifffile.TiffFile(io.BytesIO(plain)) as before, tifffile.TiffFile(
            io.BytesIO(written)) as after:
        old, new = before.pages[0].tags, after.pages[0].tags
        for tag in old:
            assert new[tag.code].value == tag.value, tag.name
        assert new["Make"].value == "Canon" and new["Orientation"].value == 1
        assert new["ExifTag"].value["LensModel"] == EXPECTED["EXIF LensModel"]
        assert len(after.pages) == 1


def test_the_output_s_size_where_the_input_had_image_width() -> None:
    """A TIFF input's ImageWidth/ImageLength are its own layout: in a JPEG's EXIF they become
    the output's size; in a TIFF output the encoder's own tags say it."""
    buffer = io.BytesIO()
    exif = Image.Exif()
    exif.load(camera_exif())
    Image.new("RGB", (70, 45)).save(buffer, "TIFF", exif=exif)
    photo = photo_exif(buffer.getvalue())
    assert photo is not None and photo.ifd0[0x0100] == 70
    assert 0x0111 not in photo.ifd0 and 0x0103 not in photo.ifd0  # strips, compression
    tags = exif_tags(with_metadata(encoded("jpg-colour")[1], ".jpg", SIZE, photo, None))
    assert (tags["Image ImageWidth"], tags["Image ImageLength"]) == ("50", "30")
    assert "Image StripOffsets" not in tags and tags["Image Make"] == "Canon"


@pytest.mark.parametrize("name", ["jpg-colour", "png-16bit", "webp-lossy", "tif-colour"])
def test_nothing_to_add_leaves_the_bytes_as_they_are(name: str) -> None:
    extension, plain = encoded(name)
    assert with_metadata(plain, extension, SIZE, None, None) is plain


def test_exif_is_found_in_each_input_format() -> None:
    exif = camera_exif()
    for extension in (".png", ".webp", ".tif"):
        buffer = io.BytesIO()
        Image.new("RGB", (20, 10)).save(buffer, extension.lstrip(".").replace("tif", "tiff"),
                                        exif=exif)
        data = buffer.getvalue()
        assert exif_block(data) is not None, extension
        photo = photo_exif(data)
        assert photo is not None and photo.ifd0[0x010F] == "Canon", extension
        assert photo.exif[0xA434] == EXPECTED["EXIF LensModel"], extension
    assert exif_block(encoded("png-16bit")[1]) is None
    assert photo_exif(encoded("jpg-colour")[1]) is None


def test_an_orientation_alone_is_no_metadata_to_keep() -> None:
    exif = Image.Exif()
    exif[0x0112] = 6
    buffer = io.BytesIO()
    Image.new("RGB", (20, 10)).save(buffer, "JPEG", exif=exif.tobytes())
    assert exif_block(buffer.getvalue()) is not None
    assert photo_exif(buffer.getvalue()) is None


def test_a_jpeg_s_exif_must_fit_its_segment() -> None:
    photo = photo_exif(camera_jpeg())
    big = PhotoExif({**photo.ifd0, 0x010E: "x" * 70000}, photo.exif, photo.gps)
    with pytest.raises(MetadataError, match="does not fit a JPEG segment"):
        with_metadata(encoded("jpg-colour")[1], ".jpg", SIZE, big, None)
    written = with_metadata(encoded("png-16bit")[1], ".png", SIZE, big, None)
    assert len(exif_tags(written)["Image ImageDescription"]) == 70000


def _damaged(block: bytes, rng: np.random.Generator) -> bytes:
    data = bytearray(block)
    match rng.integers(3):
        case 0:  # bytes overwritten anywhere after the prefix
            for at in rng.integers(6, len(data), size=int(rng.integers(1, 12))):
                data[at] = int(rng.integers(256))
        case 1:  # cut short
            del data[int(rng.integers(6, len(data))):]
        case _:  # an offset or count of the first entries made huge
            at = int(rng.integers(14, min(len(data), 120)))
            data[at:at + 4] = b"\xff\xff\xff\x7f"
    return bytes(data)


def test_damaged_exif_never_raises_anything_but_metadata_error() -> None:
    """600 damaged copies of a camera's EXIF block: each is read, or refused as damaged;
    what is read is written into every format, or refused; nothing else escapes."""
    rng = np.random.default_rng(11)
    block = camera_exif()
    outputs = {name: encoded(name) for name in ("jpg-colour", "png-alpha", "webp-lossless",
                                                  "tif-colour")}
    outcomes = {"read": 0, "refused": 0, "written": 0, "not written": 0}
    for _ in range(600):
        damaged = _damaged(block, rng)
        jpeg = b"\xff\xd8" + b"\xff\xe1" + (len(damaged) + 2).to_bytes(2, "big") + damaged
        try:
            photo = photo_exif(jpeg + b"\xff\xd9")
        except MetadataError:
            outcomes["refused"] += 1
            continue
        outcomes["read"] += 1
        if photo is None:
            continue
        for extension, plain in outputs.values():
            try:
                with_metadata(plain, extension, SIZE, photo, RECORD)
                outcomes["written"] += 1
            except MetadataError:
                outcomes["not written"] += 1
    assert outcomes["refused"] > 0 and outcomes["read"] > 0 and outcomes["written"] > 0, outcomes
