"""Every sample type gsrwt decodes (8/16-bit, signed, 32/64-bit float with NaN and inf; grey,
colour, alpha) gives the commands that look at pixels (estimate, rectify --auto, lines,
match) the answer they give for the 8-bit file: real TIFFs written by OpenCV, real
subprocesses of the ``gsrwt`` command."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from gsrwt_cli.vision.edges import grey8, pixels8
from tests.helpers.cli import run_gsrwt
from tests.helpers.estimate_scenes import render_room
from tests.helpers.paths import ROOT
from tests.helpers.tables import by_image_name, read_table

VIEWS = ROOT / "sample_data" / "views"
TEMPLATES = ROOT / "sample_data" / "templates"


def sprinkled(image: np.ndarray, seed: int) -> np.ndarray:
    """A float image with NaN, +inf and -inf at 30 scattered pixels each."""
    rng = np.random.default_rng(seed)
    out = image.copy()
    for value in (np.nan, np.inf, -np.inf):
        rows = rng.integers(0, image.shape[0], 30)
        cols = rng.integers(0, image.shape[1], 30)
        out[rows, cols] = value
    return out


def variants(image: np.ndarray) -> dict[str, np.ndarray]:
    """The same 8-bit BGR scene in every sample type and channel layout gsrwt decodes."""
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    opaque = np.dstack([image, np.full(image.shape[:2], 255, np.uint8)])
    return {
        "float32.tif": image.astype(np.float32) / 255,
        "float64_bgra.tif": opaque.astype(np.float64) / 255,
        "float32_grey_nan_inf.tif": sprinkled(grey.astype(np.float32) / 255, 1),
        "float64_nan_inf.tif": sprinkled(image.astype(np.float64) / 255, 2),
        "float32_0_to_255.tif": image.astype(np.float32),  # brighter than 1: scaled, not white
        "uint16.tif": image.astype(np.uint16) * 257,
        "uint16_grey.png": grey.astype(np.uint16) * 257,
        "int16.tif": image.astype(np.int16) * 128,
        "int8_grey.tif": (grey // 2).astype(np.int8),
        "int32.tif": image.astype(np.int32) * 8421504,  # 255 * 8421504 < 2**31
    }


def write_variants(directory: Path, image: np.ndarray) -> list[str]:
    directory.mkdir()
    cv2.imwrite(str(directory / "eight_bit.png"), image)
    for name, pixels in variants(image).items():
        assert cv2.imwrite(str(directory / name), pixels)
        decoded = cv2.imread(str(directory / name), cv2.IMREAD_UNCHANGED)
        assert decoded.dtype == pixels.dtype and decoded.shape == pixels.shape, name
    return sorted(variants(image))


def test_the_conversion_to_8_bits_takes_every_sample_type():
    image = render_room(20, -8, 3, focal=520, seed=4).image
    expected = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    for name, pixels in variants(image).items():
        grey = grey8(pixels)
        assert grey.dtype == np.uint8 and grey.shape == expected.shape, name
        if "nan" in name:
            finite = np.isfinite(pixels) if pixels.ndim == 2 else np.isfinite(pixels).all(2)
            difference = np.abs(grey.astype(int) - expected)[finite]
        else:
            difference = np.abs(grey.astype(int) - expected)
        # int8 keeps 7 bits and int16 scales by 255 * 128 / 32767: a level or two off
        assert difference.max() <= (2 if "int" in name else 0), name


def test_estimate_and_rectify_auto_give_every_sample_type_the_8_bit_pose(tmp_path):
    shot = render_room(20, -8, 3, focal=520, seed=4)
    names = write_variants(tmp_path / "in", shot.image)
    result = run_gsrwt("estimate", str(tmp_path / "in"), "--focal", "520", "-f", "csv")
    assert result.returncode == 0, result.stderr
    rows = {Path(row["image"]).name: row for row in read_table(result.stdout)}
    reference = rows.pop("eight_bit.png")
    assert float(reference["pan"]) == pytest.approx(20, abs=0.2)
    assert sorted(rows) == names
    for name, row in rows.items():
        assert row["status"] == "ok", (name, row["error"])
        for angle in ("pan", "tilt", "roll"):
            assert float(row[angle]) == pytest.approx(float(reference[angle]), abs=0.1), name

    table = tmp_path / "table.csv"
    floats = [str(tmp_path / "in" / name) for name in ("float32.tif", "float64_bgra.tif",
                                                      "uint16.tif", "int16.tif")]
    result = run_gsrwt("rectify", *floats, "--auto", "--focal", "520",
                       "-o", str(tmp_path / "out"), "--table", str(table))
    assert result.returncode == 0, result.stderr
    rectified = by_image_name(read_table(table))
    for name in ("float32.tif", "float64_bgra.tif", "uint16.tif", "int16.tif"):
        row = rectified[name]
        assert row["status"] == "ok" and row["pose_source"] == "estimated", row
        assert float(row["pan_deg"]) == pytest.approx(float(reference["pan"]), abs=0.1)
        written = cv2.imread(str(tmp_path / "out" / name), cv2.IMREAD_UNCHANGED)
        source = cv2.imread(str(tmp_path / "in" / name), cv2.IMREAD_UNCHANGED)
        assert written.dtype == source.dtype and written.shape[2] == source.shape[2], name


def test_lines_and_match_give_every_sample_type_the_8_bit_answer(tmp_path):
    door = cv2.imread(str(VIEWS / "door_p20_t-8_f800.jpg"))
    names = write_variants(tmp_path / "in", door)
    knob = cv2.imread(str(TEMPLATES / "knob.png"))
    knob_float = tmp_path / "knob.tif"
    cv2.imwrite(str(knob_float), knob.astype(np.float32) / 255)
    pose = ("--pan", "20", "--tilt", "-8", "--focal", "800")

    result = run_gsrwt("lines", str(tmp_path / "in"), *pose, "-f", "csv")
    assert result.returncode == 0, result.stderr
    counts: dict[str, int] = {}
    for row in read_table(result.stdout):
        counts[Path(row["image"]).name] = counts.get(Path(row["image"]).name, 0) + 1
    reference = counts.pop("eight_bit.png")
    assert reference >= 10
    assert sorted(counts) == names
    for name, count in counts.items():
        assert abs(count - reference) <= max(2, reference // 20), (name, count, reference)

    result = run_gsrwt("match", str(tmp_path / "in"), "--template", str(knob_float), *pose,
                       "-f", "csv")
    assert result.returncode == 0, result.stderr
    found = {Path(row["image"]).name: row for row in read_table(result.stdout)}
    reference_match = found.pop("eight_bit.png")
    assert sorted(found) == names
    for name, row in found.items():
        assert math.dist((float(row["x"]), float(row["y"])),
                         (float(reference_match["x"]), float(reference_match["y"]))) <= 1.5, name


@pytest.mark.parametrize("alpha", [False, True])
def test_rectify_keeps_float64_and_signed_16_bit_samples(tmp_path, alpha):
    """Sample types OpenCV's colour conversions refuse (float64, int16) are warped and written
    as they are, with an opaque alpha of their own full value when asked."""
    image = render_room(20, -8, 3, focal=520, seed=4).image
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    inputs = {"f64.tif": image.astype(np.float64) / 255, "f64_grey.tif": grey / 255.0,
              "i16.tif": image.astype(np.int16) * 128}
    for name, pixels in inputs.items():
        cv2.imwrite(str(tmp_path / name), pixels)
    reference = tmp_path / "eight.png"
    cv2.imwrite(str(reference), image)
    args = ("--pan", "20", "--tilt", "-8", "--focal", "520", *(["--alpha"] if alpha else []))
    result = run_gsrwt("rectify", str(reference), *[str(tmp_path / n) for n in inputs], *args,
                       "-o", str(tmp_path / "out"), "--ext", "tif")
    assert result.returncode == 0, result.stderr
    eight = cv2.imread(str(tmp_path / "out" / "eight.tif"), cv2.IMREAD_UNCHANGED)
    for name, pixels in inputs.items():
        written = cv2.imread(str(tmp_path / "out" / name), cv2.IMREAD_UNCHANGED)
        assert written.dtype == pixels.dtype, name
        channels = 1 if pixels.ndim == 2 else pixels.shape[2]
        assert (written.shape[2] if written.ndim == 3 else 1) == (4 if alpha else channels)
        if alpha:
            opaque = eight[..., 3] == 255
            full = 1.0 if pixels.dtype.kind == "f" else 32767
            assert opaque.mean() > 0.5 and (written[..., 3][opaque] == full).all(), name
        as_eight = pixels8(written).reshape(*written.shape[:2], -1)[..., :channels]
        expected = eight.reshape(*eight.shape[:2], -1)[..., :3]
        if channels == 1:
            expected = cv2.cvtColor(expected, cv2.COLOR_BGR2GRAY)[..., None]
        difference = np.abs(as_eight.astype(int) - expected)
        assert np.percentile(difference, 99) <= 2, name
