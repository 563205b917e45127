"""JPEGs with data after the end-of-image marker (motion photos, MPO) are complete images;
truncated JPEGs are still refused."""

from __future__ import annotations

import io
import struct

import cv2
import numpy as np
import pytest

from gsrwt_cli.imaging.images import ImageError, decode_image
from gsrwt_cli.io.jpeg_stream import jpeg_stream_end
from tests.helpers.cli import run_gsrwt
from tests.helpers.images import smooth_texture
from tests.helpers.paths import DATA

PHOTO = DATA / "right01.jpg"  # a real camera's JPEG (OpenCV's sample data)


def _jpeg(image: np.ndarray, *params: int) -> bytes:
    ok, data = cv2.imencode(".jpg", image, list(params))
    assert ok
    return data.tobytes()


def _mp4(seed: int = 0, size: int = 50_000) -> bytes:
    """An MP4 as a motion photo appends it: ``ftyp``, ``mdat`` of video data (random bytes
    here, which hold ``FF D9`` pairs as real video does) and a ``moov`` box last."""
    random = np.random.default_rng(seed).integers(0, 256, size, dtype=np.uint8).tobytes()
    random = random[:1000] + b"\xff\xd9" + random[1000:] + b"\xff\xd9\xff\xd8"
    ftyp = struct.pack(">I4s4sI8s", 24, b"ftyp", b"mp42", 0, b"isommp42")
    mdat = struct.pack(">I4s", 8 + len(random), b"mdat") + random
    moov = struct.pack(">I4s", 16, b"moov") + struct.pack(">I4s4s", 8, b"mvhd", b"\x00" * 4)
    return ftyp + mdat + moov


def _with_app_segment(jpeg: bytes, marker: int, payload: bytes) -> bytes:
    """``jpeg`` with an APPn segment holding ``payload`` right after its SOI."""
    segment = bytes([0xFF, marker]) + struct.pack(">H", len(payload) + 2) + payload
    return jpeg[:2] + segment + jpeg[2:]


TEXTURE = smooth_texture(96, 128, 3)
ENCODINGS = {
    "baseline": _jpeg(TEXTURE),
    "progressive": _jpeg(TEXTURE, cv2.IMWRITE_JPEG_PROGRESSIVE, 1),
    "restart-markers": _jpeg(TEXTURE, cv2.IMWRITE_JPEG_RST_INTERVAL, 2),
    "grey": _jpeg(cv2.cvtColor(TEXTURE, cv2.COLOR_BGR2GRAY)),
    "photo": PHOTO.read_bytes(),
}


@pytest.mark.parametrize("name", list(ENCODINGS))
def test_the_stream_ends_at_the_end_marker_whatever_follows(name):
    jpeg = ENCODINGS[name]
    assert jpeg_stream_end(jpeg) == len(jpeg)
    for trailer in (_mp4(), b"MotionPhoto_Data" + _mp4(1) + b"SEFT", ENCODINGS["baseline"],
                    bytes(4096), b"\xff\xd9\x00junk"):
        assert jpeg_stream_end(jpeg + trailer) == len(jpeg)


@pytest.mark.parametrize("name", list(ENCODINGS))
def test_every_truncation_is_found(name):
    jpeg = ENCODINGS[name]
    step = max(1, len(jpeg) // 1500)
    for cut in [*range(0, len(jpeg), step), len(jpeg) - 1]:
        assert jpeg_stream_end(jpeg[:cut]) is None, cut


def test_an_end_marker_inside_a_thumbnail_is_not_the_images_end():
    # An EXIF APP1 segment carries a thumbnail JPEG, which ends with FF D9 before the image's
    # own data starts: cut the file right after it and the stream is still short.
    thumbnail = _jpeg(smooth_texture(16, 16, 4))
    jpeg = _with_app_segment(ENCODINGS["baseline"], 0xE1, b"Exif\x00\x00" + thumbnail)
    assert jpeg_stream_end(jpeg) == len(jpeg)
    after_thumbnail = 2 + 4 + 6 + len(thumbnail)
    assert jpeg[:after_thumbnail].endswith(b"\xff\xd9")
    assert jpeg_stream_end(jpeg[:after_thumbnail]) is None
    assert jpeg_stream_end(jpeg[:after_thumbnail] + _mp4()) is None  # then a "video"


def test_not_a_jpeg_or_damaged_between_segments():
    assert jpeg_stream_end(b"") is None
    assert jpeg_stream_end(b"\x89PNG\r\n\x1a\n") is None
    jpeg = ENCODINGS["baseline"]
    # stray bytes before a marker, fill bytes, a bogus length: walked on, the end still found
    damaged = jpeg[:2] + b"junk" + b"\xff\xff" + b"\xff\xe0\x00\x01" + jpeg[2:]
    assert jpeg_stream_end(damaged) == len(damaged)


@pytest.mark.parametrize(
    "trailer",
    [_mp4(), b"MotionPhoto_Data" + _mp4(2) + b"SEFT", ENCODINGS["baseline"] + b"\x00\x01",
     bytes(4096)],
    ids=["google-motion-photo", "samsung-motion-photo", "mpo-second-picture", "nul-padding"],
)
def test_decode_gives_the_same_pixels_with_data_after_the_end(trailer):
    jpeg = PHOTO.read_bytes()
    plain = decode_image(jpeg)
    np.testing.assert_array_equal(decode_image(jpeg + trailer), plain)
    with pytest.raises(ImageError, match="truncated JPEG"):
        decode_image(jpeg[: len(jpeg) * 2 // 3])
    with pytest.raises(ImageError, match="truncated JPEG"):
        decode_image(jpeg[: len(jpeg) * 2 // 3] + bytes(100))  # NUL padding hides nothing


def test_rectify_reads_a_motion_photo_and_still_refuses_a_truncated_jpeg(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    jpeg = PHOTO.read_bytes()
    (folder / "plain.jpg").write_bytes(jpeg)
    (folder / "motion.jpg").write_bytes(jpeg + _mp4())
    (folder / "cut.jpg").write_bytes(jpeg[: len(jpeg) // 2])
    (folder / "cut_then_video.jpg").write_bytes(jpeg[: len(jpeg) // 2] + _mp4(3) + b"\xff\xd9")
    out = tmp_path / "out"
    result = run_gsrwt("rectify", str(folder), "--pan", "10", "--tilt", "-5", "--focal", "537",
                       "-o", str(out), "-j", "1")
    assert result.returncode == 1, result.stderr  # the two cut files failed
    assert "Traceback" not in result.stderr
    assert "2 ok, 0 skipped, 2 failed" in result.stderr
    lines = {name: [line for line in result.stderr.splitlines() if f"/{name}: " in line]
             for name in ("cut.jpg", "cut_then_video.jpg")}
    assert lines["cut.jpg"][0].endswith(": truncated JPEG (no end-of-image marker)")
    # Cut, then other data: the stream runs on into it, and the decoder finds it corrupt
    # (libjpeg's first complaint: "Unsupported marker type", or "Corrupt JPEG data").
    assert ": corrupt JPEG (" in lines["cut_then_video.jpg"][0]
    assert sorted(path.name for path in out.iterdir()) == ["gsrwt.csv", "motion.jpg", "plain.jpg"]
    motion = cv2.imread(str(out / "motion.jpg"), cv2.IMREAD_UNCHANGED)
    plain = cv2.imread(str(out / "plain.jpg"), cv2.IMREAD_UNCHANGED)
    assert motion.shape == (480, 640)
    assert (out / "motion.jpg").read_bytes() == (out / "plain.jpg").read_bytes()
    assert motion.std() > 20  # the photo rectified, not a blank
    np.testing.assert_array_equal(motion, plain)


def icc_profile(colour_space: bytes, device_class: bytes, payload: bytes = b"") -> bytes:
    """A valid ICC profile (ICC.1:2022 section 7.2: its 128-byte header, a tag table of no
    tags) of ``colour_space`` (``b"CMYK"``, ``b"GRAY"``, ``b"RGB "``) with ``payload`` after
    it: little Color Management Module (lcms) opens it, as the test checks."""
    from PIL import ImageCms

    header = bytearray(128)
    body = struct.pack(">I", 0) + payload
    struct.pack_into(">I4sI4s4s4s6H", header, 0, 128 + len(body), b"lcms", 0x04300000,
                     device_class, colour_space, b"Lab ", 2024, 1, 1, 0, 0, 0)
    header[36:40] = b"acsp"
    struct.pack_into(">3i", header, 68, round(0.9642 * 65536), 65536, round(0.8249 * 65536))
    profile = bytes(header) + body
    opened = ImageCms.ImageCmsProfile(io.BytesIO(profile))
    assert opened.profile.xcolor_space == colour_space.decode()
    return profile


@pytest.mark.parametrize(("mode", "space", "kept"), [
    ("CMYK", b"CMYK", False),  # decoded to BGR: a CMYK profile would misdescribe it
    ("CMYK", b"RGB ", False),  # nor does an RGB one describe OpenCV's naive conversion
    ("L", b"GRAY", True),
    ("L", b"RGB ", False),
    ("RGB", b"GRAY", False),
    ("RGB", b"CMYK", False),
    ("RGB", b"RGB ", True),
])
def test_a_colour_profile_is_kept_only_where_its_colour_model_is(tmp_path, mode, space, kept):
    """The output JPEG carries the input's ICC profile only when the profile's colour space
    (header bytes 16-19) is the output's: grey in, grey out; RGB in, RGB out."""
    from PIL import Image

    profile = icc_profile(space, b"prtr" if space == b"CMYK" else b"mntr")
    picture = Image.fromarray(cv2.cvtColor(cv2.imread(str(PHOTO)), cv2.COLOR_BGR2RGB))
    picture.convert(mode).save(tmp_path / "in.jpg", quality=92, icc_profile=profile)
    with Image.open(tmp_path / "in.jpg") as written:
        assert written.mode == mode and written.info["icc_profile"] == profile
    result = run_gsrwt("rectify", str(tmp_path / "in.jpg"), "--pan", "10", "--tilt", "-5",
                       "--focal", "537", "-o", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    with Image.open(tmp_path / "out" / "in.jpg") as rectified:
        assert rectified.mode == ("L" if mode == "L" else "RGB")
        assert rectified.info.get("icc_profile") == (profile if kept else None)


@pytest.mark.parametrize("profile_size", ["srgb", 150_000])
def test_rectify_keeps_a_jpegs_colour_profile(tmp_path, profile_size):
    """A JPEG's ICC profile (one APP2 segment, or a big one split over three) is carried into
    its rectified JPEG byte for byte, as Pillow reads it back; a PNG output and a JPEG with no
    profile get none."""
    from PIL import Image, ImageCms

    if profile_size == "srgb":
        profile = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    else:
        payload = np.random.default_rng(3).integers(0, 256, profile_size, np.uint8).tobytes()
        profile = icc_profile(b"RGB ", b"mntr", payload)
    folder = tmp_path / "in"
    folder.mkdir()
    picture = Image.fromarray(cv2.cvtColor(cv2.imread(str(PHOTO)), cv2.COLOR_BGR2RGB))
    picture.save(folder / "with.jpg", quality=92, icc_profile=profile)
    picture.save(folder / "without.jpg", quality=92)
    out = tmp_path / "out"
    result = run_gsrwt("rectify", str(folder), "--pan", "10", "--tilt", "-5", "--focal", "537",
                       "-o", str(out))
    assert result.returncode == 0, result.stderr
    with Image.open(out / "with.jpg") as rectified:
        assert rectified.info.get("icc_profile") == profile
        difference = np.abs(np.asarray(rectified, np.int16) - np.asarray(picture, np.int16))
        assert difference.mean() > 10  # a new picture, not a copy
    with Image.open(out / "without.jpg") as rectified:
        assert "icc_profile" not in rectified.info
    png = tmp_path / "png"
    run_gsrwt("rectify", str(folder / "with.jpg"), "--pan", "10", "--tilt", "-5", "--focal",
              "537", "-o", str(png), "--ext", ".png")
    with Image.open(next(png.glob("*.png"))) as rectified:
        assert "icc_profile" not in rectified.info
