"""``gsrwt rectify`` keeps a photo's EXIF and records what it did (issue 25, item 2).

Photos with a camera's EXIF (:mod:`tests.helpers.exif_photos`: make, model, lens, dates,
exposure, GPS, a maker's note, a subject area, a thumbnail), one turned by its orientation,
one without EXIF and one whose EXIF is damaged, rectified into each output format with and
without ``--strip-metadata``. The EXIF is read back by exifread (gsrwt writes it with
Pillow), the XMP record parsed as XML and compared with the table's row, and the pixels
decoded by OpenCV from the outputs with and without metadata.
"""

from __future__ import annotations

import io
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

import gsrwt_cli
from tests.helpers.cli import run_gsrwt
from tests.helpers.exif_photos import (
    EXPECTED,
    camera_exif,
    exif_tags,
    gsrwt_record,
    write_camera_photo,
    xmp_of,
)
from tests.helpers.images import smooth_texture
from tests.helpers.tables import by_image_name, read_table

#: The photos name a camera and lens lensfun knows: no lens profile here, so that the outputs
#: differ by their metadata alone (tests/cli/test_lens_profiles.py tests the profiles).
POSE = ["--pan", "15", "--tilt", "8", "--roll", "2", "--focal", "400", "--lens-profile", "off"]
FORMATS = ("jpg", "png", "webp", "tif")
UPRIGHT = smooth_texture(240, 320, seed=4)


def _photos(where: Path) -> Path:
    """``turned.jpg`` (orientation 6), ``upright.jpg`` (orientation 1), ``plain.jpg`` (the
    same pixels as upright, no EXIF) and ``damaged.jpg`` (an EXIF block Pillow refuses)."""
    photos = where / "photos"
    photos.mkdir()
    pixels = UPRIGHT[..., ::-1].copy()  # RGB for Pillow
    write_camera_photo(photos / "turned.jpg", np.rot90(pixels).copy(), orientation=6)
    write_camera_photo(photos / "upright.jpg", pixels, orientation=1)
    Image.fromarray(pixels).save(photos / "plain.jpg", quality=95)
    data = (photos / "plain.jpg").read_bytes()
    junk = b"Exif\x00\x00" + b"XX*\x00" + bytes(range(40))  # no TIFF byte order
    (photos / "damaged.jpg").write_bytes(
        data[:2] + b"\xff\xe1" + (len(junk) + 2).to_bytes(2, "big") + junk + data[2:])
    return photos


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, bool], Path]:
    """The outputs of each format, with metadata kept (False) and stripped (True)."""
    where = tmp_path_factory.mktemp("metadata")
    photos = _photos(where)
    outputs = {}
    for fmt in FORMATS:
        for strip in (False, True):
            out = where / f"{fmt}-{'stripped' if strip else 'kept'}"
            result = run_gsrwt("rectify", photos, "-o", out, "--ext", fmt, *POSE, "-q",
                               *(["--strip-metadata"] if strip else []))
            assert result.returncode == 0, result.stderr
            outputs[fmt, strip] = out
    return outputs


def _rows(out: Path) -> dict[str, dict[str, str]]:
    return by_image_name(read_table(out / "gsrwt.csv"))


def _photo_tags(tags: dict[str, str]) -> list[str]:
    """The tags of ``tags`` (exifread's) that are the photo's, not a TIFF's own layout."""
    return [tag for tag in tags if tag in EXPECTED or tag.startswith(("EXIF ", "GPS "))]


def _pixels(path: Path) -> np.ndarray:
    return cv2.imdecode(np.fromfile(str(path), np.uint8), cv2.IMREAD_UNCHANGED)


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_photo_s_exif_survives_with_orientation_1_its_size_and_no_thumbnail(
        runs: dict[tuple[str, bool], Path], fmt: str) -> None:
    rows = _rows(runs[fmt, False])
    for name in ("turned", "upright"):
        row = rows[f"{name}.jpg"]
        assert (row["status"], row["metadata"]) == ("ok", "kept"), row
        tags = exif_tags((runs[fmt, False] / f"{name}.{fmt}").read_bytes())
        assert {tag: tags.get(tag) for tag in EXPECTED} == EXPECTED
        assert tags["Image Orientation"] == "Horizontal (normal)"
        assert (tags["EXIF ExifImageWidth"], tags["EXIF ExifImageLength"]) == (
            row["out_width"], row["out_height"])
        assert not [tag for tag in tags if "Thumbnail" in tag or "MakerNote" in tag]
        assert "EXIF SubjectArea" not in tags


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_transform_is_recorded_in_xmp(runs: dict[tuple[str, bool], Path],
                                          fmt: str) -> None:
    row = _rows(runs[fmt, False])["turned.jpg"]
    record = gsrwt_record(xmp_of((runs[fmt, False] / f"turned.{fmt}").read_bytes()))
    assert record["Version"] == gsrwt_cli.__version__
    assert (record["Pan"], record["Tilt"], record["Roll"]) == ("15", "8", "2")
    assert (record["Fx"], record["Fy"], record["Lens"]) == ("400", "400", "none")
    assert record["Orientation"] == "6" == row["orientation"]
    assert record["InputSize"] == "320x240"  # as displayed (stored 240x320, turned)
    assert record["OutputSize"] == f"{row['out_width']}x{row['out_height']}"
    assert record["Homography"] == row["homography"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_strip_metadata_writes_the_same_pixels_and_nothing_else(
        runs: dict[tuple[str, bool], Path], fmt: str) -> None:
    kept, stripped = runs[fmt, False], runs[fmt, True]
    for name in ("turned", "upright", "plain", "damaged"):
        assert _rows(stripped)[f"{name}.jpg"]["metadata"] == "stripped"
        data = (stripped / f"{name}.{fmt}").read_bytes()
        assert _photo_tags(exif_tags(data)) == [] and xmp_of(data) is None, name
        carrying, bare = _pixels(kept / f"{name}.{fmt}"), _pixels(stripped / f"{name}.{fmt}")
        assert carrying.dtype == bare.dtype and np.array_equal(carrying, bare)
    assert (kept / f"turned.{fmt}").read_bytes() != (stripped / f"turned.{fmt}").read_bytes()


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_photo_without_exif_or_with_damaged_exif_is_written_as_before(
        runs: dict[tuple[str, bool], Path], fmt: str) -> None:
    """No EXIF in: the output's bytes are those of ``--strip-metadata`` (today's), and those
    of a photo with EXIF of the same pixels, stripped. Damaged EXIF: written without it, and
    the table says so."""
    kept, stripped = runs[fmt, False], runs[fmt, True]
    rows = _rows(kept)
    assert (rows["plain.jpg"]["status"], rows["plain.jpg"]["metadata"]) == ("ok", "none")
    assert (rows["damaged.jpg"]["status"], rows["damaged.jpg"]["metadata"]) == ("ok",
                                                                                "damaged")
    plain = (kept / f"plain.{fmt}").read_bytes()
    assert plain == (stripped / f"plain.{fmt}").read_bytes()
    assert plain == (stripped / f"upright.{fmt}").read_bytes()
    assert (kept / f"damaged.{fmt}").read_bytes() == plain


def test_bmp_holds_no_metadata_and_a_big_exif_does_not_fit_a_jpeg(tmp_path: Path) -> None:
    """A PNG whose EXIF has a 70 KB description: kept in a PNG output, not in a JPEG's
    64 KB segment; a BMP holds none."""
    exif = Image.Exif()
    exif.load(camera_exif())
    exif[0x010E] = "a long description " * 3700
    photo = write_camera_photo(tmp_path / "described.png", UPRIGHT[..., ::-1].copy(),
                               exif=exif.tobytes())
    cells = {}
    for fmt in ("png", "jpg", "bmp"):
        result = run_gsrwt("rectify", photo, "-o", tmp_path / fmt, "--ext", fmt, *POSE, "-q")
        assert result.returncode == 0, result.stderr
        cells[fmt] = read_table(tmp_path / fmt / "gsrwt.csv")[0]["metadata"]
    assert cells == {"png": "kept", "jpg": "unsupported", "bmp": "unsupported"}
    tags = exif_tags((tmp_path / "png" / "described.png").read_bytes())
    assert len(tags["Image ImageDescription"]) == len(exif[0x010E])
    assert exif_tags((tmp_path / "jpg" / "described.jpg").read_bytes()) == {}
    assert _photo_tags(exif_tags((tmp_path / "bmp" / "described.bmp").read_bytes())) == []


def test_a_rerun_that_strips_does_not_keep_outputs_made_with_metadata(tmp_path: Path) -> None:
    photos = _photos(tmp_path)
    first = run_gsrwt("rectify", photos / "turned.jpg", "-o", tmp_path / "out", *POSE, "-q")
    assert first.returncode == 0, first.stderr
    again = run_gsrwt("rectify", photos / "turned.jpg", "-o", tmp_path / "out", *POSE, "-q",
                      "--strip-metadata")
    assert again.returncode == 1
    row = read_table(tmp_path / "out" / "gsrwt.csv")[0]
    assert row["status"] == "error" and "metadata none -> strip" in row["error"]


def test_a_jpeg_keeps_its_colour_profile_beside_its_exif(tmp_path: Path) -> None:
    """A phone's JPEG has both: the output's header has the EXIF, the XMP and the profile,
    each as Pillow and exifread read them."""
    from PIL import ImageCms

    profile = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    photo = tmp_path / "phone.jpg"
    Image.fromarray(UPRIGHT[..., ::-1].copy()).save(photo, quality=95, icc_profile=profile,
                                                    exif=camera_exif(orientation=3))
    result = run_gsrwt("rectify", photo, "-o", tmp_path / "out", *POSE, "-q")
    assert result.returncode == 0, result.stderr
    data = (tmp_path / "out" / "phone.jpg").read_bytes()
    with Image.open(io.BytesIO(data)) as rectified:
        assert rectified.info.get("icc_profile") == profile
    tags = exif_tags(data)
    assert {tag: tags.get(tag) for tag in EXPECTED} == EXPECTED
    assert gsrwt_record(xmp_of(data))["Orientation"] == "3"
