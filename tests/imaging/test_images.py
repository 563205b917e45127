"""The image layer: decoding into reused memory, warping layouts, encoding, atomic writes."""

from __future__ import annotations

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from gsrwt_cli import View
from gsrwt_cli.geometry.framing import output_from_input
from gsrwt_cli.geometry.pixelmap import PixelMap
from gsrwt_cli.imaging.images import (
    ImageError,
    Scratch,
    Working,
    encode_image,
    read_image,
    warp_image,
)
from gsrwt_cli.io.outputs import write_atomic
from tests.helpers.images import smooth_texture
from tests.helpers.paths import DATA


def test_scratch_gives_the_same_pixels_as_fresh_arrays_across_shapes_and_types(tmp_path):
    images = [
        smooth_texture(120, 160, 1),
        smooth_texture(120, 160, 2),  # same shape: decoded into the reused region
        smooth_texture(90, 200, 3, channels=1),  # grey, another shape
        smooth_texture(150, 100, 4).astype(np.uint16) * 257,  # 16-bit
        np.dstack([smooth_texture(120, 160, 5), smooth_texture(120, 160, 6, channels=1)]),
        smooth_texture(120, 160, 7),
    ]
    scratch = Scratch()
    for index, image in enumerate(images):
        path = tmp_path / f"{index}.png"
        cv2.imwrite(str(path), image)
        decoded = scratch.read(path)
        assert decoded.shape == image.shape and decoded.dtype == image.dtype
        np.testing.assert_array_equal(decoded, image)
        del decoded
        height, width = image.shape[:2]
        homography = output_from_input(View(20, -10, 150, width=width, height=height))
        size = (width + 30, height - 10)
        for alpha in (False, True):
            expected = warp_image(image, PixelMap(homography, size), "linear", 9, alpha)
            scratch.read(path)
            warped = scratch.warp(PixelMap(homography, size), "linear", 9, alpha)
            got = cv2.cvtColor(warped.pixels, cv2.COLOR_BGRA2BGR) if warped.padded else (
                warped.pixels)
            np.testing.assert_array_equal(got, expected)


def test_padded_jpeg_encodes_exactly_like_the_colour_image():
    image = smooth_texture(100, 120, 8)
    padded = Working(cv2.cvtColor(image, cv2.COLOR_BGR2BGRA), padded=True)
    assert encode_image(padded, ".jpg") == encode_image(image, ".jpg")
    assert encode_image(padded, ".png") == encode_image(image, ".png")


@pytest.mark.parametrize(
    ("extension", "image", "message"),
    [
        (".jpg", np.zeros((4, 4), np.uint16), ".jpg cannot store 16-bit images"),
        (".jpg", np.zeros((4, 4, 4), np.uint8), ".jpg cannot store alpha (RGBA) images"),
        (".gif", np.zeros((4, 4), np.uint8), "cannot write '.gif' files"),
    ],
)
def test_formats_that_cannot_hold_the_pixels_are_refused(extension, image, message):
    with pytest.raises(ImageError, match=message.replace("(", r"\(").replace(")", r"\)")):
        encode_image(image, extension)


def test_write_atomic_replaces_whole_files_and_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.bin"
    write_atomic(target, b"first")
    write_atomic(target, b"second")
    assert target.read_bytes() == b"second"
    assert oct(os.stat(target).st_mode & 0o777) != oct(0o600)  # not mkstemp's private mode
    with pytest.raises(TypeError):
        write_atomic(target, "not bytes")  # fails while writing the temporary file
    assert target.read_bytes() == b"second"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]


def test_damaged_jpeg_is_an_error_not_a_grey_picture(tmp_path):
    ok, data = cv2.imencode(".jpg", smooth_texture(200, 200, 9))
    data = data.tobytes()
    damaged = data[: len(data) // 2] + bytes(200) + data[-2:]  # hole, but an end marker
    (tmp_path / "d.jpg").write_bytes(damaged)
    with pytest.raises(ImageError, match="corrupt JPEG"):
        read_image(tmp_path / "d.jpg")
    (tmp_path / "t.jpg").write_bytes(data[: len(data) // 2])
    with pytest.raises(ImageError, match="truncated JPEG"):
        read_image(tmp_path / "t.jpg")


def test_importing_the_library_changes_no_process_wide_state():
    """Only the console entry point silences OpenCV; no import touches the umask."""
    script = (
        "import os, pkgutil, importlib, cv2\n"
        "os.umask(0o027)\n"
        "level = cv2.utils.logging.getLogLevel()\n"
        "import gsrwt_cli\n"
        "for module in pkgutil.walk_packages(gsrwt_cli.__path__, 'gsrwt_cli.'):\n"
        "    if not module.name.endswith('__main__'):\n"
        "        importlib.import_module(module.name)\n"
        "assert cv2.utils.logging.getLogLevel() == level, 'OpenCV logging changed'\n"
        "assert os.umask(0o022) == 0o027, 'umask changed'\n"
        "print('unchanged')\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert result.stdout.strip() == "unchanged", result.stderr


JPEG_VARIANTS = {
    "420": [], "444": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444],
    "422": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_422],
    "progressive": [cv2.IMWRITE_JPEG_PROGRESSIVE, 1],
    "restarts": [cv2.IMWRITE_JPEG_RST_INTERVAL, 2],
}


def test_jpegs_decode_to_exactly_opencvs_pixels():
    """JPEGs are decoded by libjpeg-turbo's own API (simplejpeg): pixel for pixel what
    cv2.imdecode gives, for real photos (grey and colour) and every chroma layout. Exact on
    every CPU: both are libjpeg-turbo's accurate integer IDCT and fancy upsampling, whose
    SIMD paths are bit for bit its C code (integer arithmetic; its own tests hold one
    checksum per image whatever SIMD the CPU has)."""

    from gsrwt_cli.imaging.images import decode_image

    samples = [path.read_bytes() for path in sorted(DATA
                                                     .glob("*.jpg"))]
    colour = smooth_texture(301, 403, 11)
    samples += [cv2.imencode(".jpg", colour, params)[1].tobytes()
                for params in JPEG_VARIANTS.values()]
    samples.append(cv2.imencode(".jpg", colour[..., 1])[1].tobytes())
    assert len(samples) > 15
    for data in samples:
        expected = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        np.testing.assert_array_equal(decode_image(data), expected)
        padded = decode_image(data, padded=True)
        if expected.ndim == 3:
            assert padded.shape[2] == 4 and (padded[..., 3] == 255).all()
            np.testing.assert_array_equal(padded[..., :3], expected)


def test_scratch_decodes_jpegs_into_its_own_memory_with_no_pixels_left_behind(tmp_path):
    """A worker's sequence of JPEGs (colour, grey, other sizes, damaged) and PNGs: each warp
    is exactly the warp of OpenCV's decode of that file, and a damaged file is an error."""
    colour = smooth_texture(120, 160, 1)
    files = [
        ("a.jpg", cv2.imencode(".jpg", colour)[1].tobytes()),
        ("b.jpg", cv2.imencode(".jpg", smooth_texture(120, 160, 2), JPEG_VARIANTS["444"])[1]
         .tobytes()),
        ("c.png", cv2.imencode(".png", smooth_texture(90, 100, 3))[1].tobytes()),
        ("d.jpg", cv2.imencode(".jpg", smooth_texture(200, 210, 4, channels=1))[1].tobytes()),
        ("e.jpg", None),  # damaged: a hole in the middle, an end marker
        ("f.jpg", cv2.imencode(".jpg", smooth_texture(130, 170, 5))[1].tobytes()),
    ]
    good = files[0][1]
    files[4] = ("e.jpg", good[: len(good) // 2] + bytes(300) + good[-2:])
    scratch = Scratch()
    for name, data in files:
        path = tmp_path / name
        path.write_bytes(data)
        expected_image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        if name == "e.jpg":
            with pytest.raises(ImageError, match="corrupt JPEG"):
                scratch.read(path)
            with pytest.raises(RuntimeError):
                scratch.warp(PixelMap(np.eye(3), (10, 10)))  # nothing of the last image
            continue
        height, width = expected_image.shape[:2]
        homography = output_from_input(View(20, -10, 150, width=width, height=height))
        size = (width + 30, height - 10)
        for alpha in (False, True):
            decoded = scratch.read(path)
            assert decoded.shape == expected_image.shape
            np.testing.assert_array_equal(decoded, expected_image)
            del decoded
            warped = scratch.warp(PixelMap(homography, size), "linear", 9, alpha)
            expected = warp_image(expected_image, PixelMap(homography, size), "linear", 9,
                                  alpha)
            got = cv2.cvtColor(warped.pixels, cv2.COLOR_BGRA2BGR) if warped.padded else (
                warped.pixels)
            np.testing.assert_array_equal(got, expected)
