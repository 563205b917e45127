"""``--orientation``: a photo whose EXIF orientation turns it rectifies as it is displayed.

Each of the eight EXIF orientations stores the pixels of one upright view turned or mirrored,
written by Pillow with the tag that shows them upright (checked with Pillow's own
``ImageOps.exif_transpose``, an implementation independent of gsrwt's). Rectified with the
pose of the displayed photo, every one must give the upright view's output; with
``--orientation ignore``, the output of the stored pixels as today (the same pixels written
without EXIF).
"""

from __future__ import annotations

import io
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, ImageOps

from tests.helpers.camera import render_view
from tests.helpers.cli import run_gsrwt
from tests.helpers.images import smooth_texture
from tests.helpers.tables import by_image_name, read_table

DATA = Path(__file__).resolve().parents[1] / "data"
TEXTURE = smooth_texture(1400, 1800, seed=3)
# The displayed photo's camera: portrait-agnostic values, principal point off centre.
PAN, TILT, FOCAL, WIDTH, HEIGHT, CX, CY = -20, 25, 500, 480, 360, 250.0, 170.0
POSE = ["--pan", str(PAN), "--tilt", str(TILT), "--focal", str(FOCAL), "--cx", str(CX),
        "--cy", str(CY)]

#: The Pillow transpose that stores an upright image so that orientation N displays it
#: upright: the inverse of what ``exif_transpose`` applies for N.
STORED_BY = {
    1: None, 2: Image.Transpose.FLIP_LEFT_RIGHT, 3: Image.Transpose.ROTATE_180,
    4: Image.Transpose.FLIP_TOP_BOTTOM, 5: Image.Transpose.TRANSPOSE,
    6: Image.Transpose.ROTATE_90, 7: Image.Transpose.TRANSVERSE,
    8: Image.Transpose.ROTATE_270,
}


def write_oriented(path: Path, upright: Image.Image, orientation: int | None,
                   quality: int = 95) -> Path:
    """``upright`` stored turned so that EXIF ``orientation`` displays it upright (None: no
    EXIF at all, the pixels as for orientation 1)."""
    method = STORED_BY.get(orientation)  # FLIP_LEFT_RIGHT is 0: compared with None
    stored = upright if method is None else upright.transpose(method)
    options = {"quality": quality} if path.suffix == ".jpg" else {}
    if orientation is not None:
        exif = Image.Exif()
        exif[0x0112] = orientation
        options["exif"] = exif.tobytes()
    stored.save(path, **options)
    return path


def stored_pixels(path: Path) -> np.ndarray:
    return cv2.imdecode(np.fromfile(str(path), np.uint8), cv2.IMREAD_UNCHANGED)


def displayed_by_pillow(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(ImageOps.exif_transpose(image).convert("RGB"))


@pytest.fixture(scope="module")
def upright() -> Image.Image:
    bgr, _, _ = render_view(TEXTURE, PAN, TILT, FOCAL, WIDTH, HEIGHT, CX, CY)
    return Image.fromarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))


def rectified(path: Path, out: Path, *extra: str) -> tuple[np.ndarray, dict]:
    result = run_gsrwt("rectify", str(path), *POSE, "--ext", "png", "-j", "1", "-o", str(out),
                       "--table", str(out / "t.csv"), *extra)
    assert result.returncode == 0, result.stderr
    row = read_table(out / "t.csv")[0]
    return stored_pixels(out / (path.stem + ".png")), row


def test_every_orientation_rectifies_to_the_upright_output(tmp_path, upright):
    reference, row = rectified(write_oriented(tmp_path / "upright.png", upright, None),
                               tmp_path / "out-upright")
    assert row["orientation"] == "1"
    for orientation in STORED_BY:
        path = write_oriented(tmp_path / f"o{orientation}.png", upright, orientation)
        assert np.array_equal(displayed_by_pillow(path), np.asarray(upright))
        if orientation >= 5:
            assert stored_pixels(path).shape[:2] == (WIDTH, HEIGHT)  # stored on its side
        output, row = rectified(path, tmp_path / f"out{orientation}")
        assert row["orientation"] == str(orientation)
        assert row["status"] == "ok"
        assert output.shape == reference.shape, orientation
        assert np.array_equal(output, reference), orientation


def test_ignore_rectifies_the_stored_pixels_as_before(tmp_path, upright):
    for orientation in (3, 6):
        tagged = write_oriented(tmp_path / f"o{orientation}.png", upright, orientation)
        untagged = write_oriented(tmp_path / f"plain{orientation}.png", upright, None)
        Image.open(tagged).save(untagged)  # the same stored pixels, no EXIF
        assert np.array_equal(stored_pixels(tagged), stored_pixels(untagged))
        ignored, row = rectified(tagged, tmp_path / f"ign{orientation}", "--orientation",
                                 "ignore")
        assert row["orientation"] == "ignored"
        assert "orientation=ignore" in row["made_with"]
        today, _ = rectified(untagged, tmp_path / f"today{orientation}")
        assert np.array_equal(ignored, today)
        applied, _ = rectified(tagged, tmp_path / f"exif{orientation}")
        assert not np.array_equal(applied, ignored) if applied.shape == ignored.shape else True


def test_phone_jpegs_in_every_orientation_agree_within_jpeg_noise(tmp_path, upright):
    """JPEG's 8x8 blocks fall on other pixels once turned: the outputs agree within noise."""
    reference, _ = rectified(write_oriented(tmp_path / "upright.jpg", upright, None),
                             tmp_path / "out-upright")
    for orientation in (2, 5, 6, 8):
        path = write_oriented(tmp_path / f"o{orientation}.jpg", upright, orientation)
        output, row = rectified(path, tmp_path / f"out{orientation}")
        assert row["orientation"] == str(orientation)
        difference = np.abs(output.astype(float) - reference.astype(float))
        assert output.shape == reference.shape
        assert difference.mean() < 1.0 and np.percentile(difference, 99) < 8, orientation


@pytest.mark.parametrize("value", [0, 9, 300])
def test_invalid_orientation_values_are_upright(tmp_path, upright, value):
    """An Orientation tag outside 1-8 is read as 1 (as most viewers do), no error."""
    reference, _ = rectified(write_oriented(tmp_path / "upright.png", upright, None),
                             tmp_path / "out-upright")
    output, row = rectified(write_oriented(tmp_path / "bad.png", upright, value),
                            tmp_path / "out-bad")
    assert row["orientation"] == "1" and row["status"] == "ok"
    assert np.array_equal(output, reference)


def test_a_damaged_exif_block_is_upright(tmp_path, upright):
    buffer = io.BytesIO()
    upright.save(buffer, "JPEG", quality=95, exif=b"Exif\x00\x00MM\x00*\x00\x00\x00\x08\xff\xff")
    path = tmp_path / "damaged.jpg"
    path.write_bytes(buffer.getvalue())
    _, row = rectified(path, tmp_path / "out")
    assert row["orientation"] == "1" and row["status"] == "ok"


def test_a_calibration_file_describes_the_sensor_of_a_turned_photo(tmp_path):
    """OpenCV's right01.jpg with its calibration (640x480, a lens, cx, cy off centre), tagged
    orientation 6 as a phone held upright would: the displayed photo is 480x640, and the
    frontal view through the calibration is the sensor's frontal view turned a quarter."""
    sensor = tmp_path / "right01.png"
    with Image.open(DATA / "right01.jpg") as photo:
        photo.save(sensor)
    turned = tmp_path / "turned.png"
    exif = Image.Exif()
    exif[0x0112] = 6
    with Image.open(sensor) as photo:
        photo.save(turned, exif=exif.tobytes())
    camera = ["--camera", str(DATA / "right_camera.yml"), "--pan", "0", "--tilt", "0"]

    def run(path: Path, out: str, *extra: str) -> tuple[np.ndarray, dict]:
        result = run_gsrwt("rectify", str(path), *camera, "--ext", "png", "-j", "1", "-o",
                           str(tmp_path / out), "--table", str(tmp_path / out / "t.csv"),
                           *extra)
        assert result.returncode == 0, result.stderr
        return (stored_pixels(tmp_path / out / (path.stem + ".png")),
                read_table(tmp_path / out / "t.csv")[0])

    of_sensor, _ = run(sensor, "sensor")
    displayed, row = run(turned, "displayed")
    assert row["orientation"] == "6"
    expected = np.ascontiguousarray(np.rot90(of_sensor, k=-1))  # 90 degrees clockwise
    assert displayed.shape == expected.shape
    difference = np.abs(displayed.astype(int) - expected.astype(int))
    assert difference.max() <= 2 and difference.mean() < 0.05
    # Ignored, the sensor's calibration meets the sensor's pixels: the sensor's output.
    ignored, _ = run(turned, "ignored", "--orientation", "ignore")
    assert np.array_equal(ignored, of_sensor)
    rows = by_image_name([row])
    assert rows["turned.png"]["fx_px"] == read_table(tmp_path / "sensor" / "t.csv")[0]["fy_px"]


def test_estimate_and_auto_see_the_displayed_photo(tmp_path):
    """A sample door view (pan 40, tilt -12, f = 700) stored turned, tagged 8: ``estimate``
    finds the displayed photo's pose; ignoring the tag, the sideways photo's is another one;
    ``rectify --auto`` rectifies the displayed photo."""
    path = tmp_path / "door.png"
    with Image.open(Path(__file__).resolve().parents[2] / "sample_data" / "views"
                    / "door_p40_t-12_f700.jpg") as door:
        write_oriented(path, door.copy(), 8)

    def pose(*extra: str) -> dict:
        result = run_gsrwt("estimate", str(path), "--focal", "700", "--format", "csv", *extra)
        assert result.returncode == 0, result.stderr
        return read_table(result.stdout)[0]

    shown = pose()
    assert abs(float(shown["pan"]) - 40) < 0.5 and abs(float(shown["tilt"]) + 12) < 0.5
    assert abs(float(shown["roll"])) < 0.5
    assert (shown["width"], shown["height"]) == ("1280", "960")
    stored = pose("--orientation", "ignore")
    assert (stored["width"], stored["height"]) == ("960", "1280")
    assert stored["status"] != "ok" or abs(float(stored["pan"]) - 40) + abs(
        float(stored["tilt"]) + 12) + abs(float(stored["roll"])) > 5  # another camera
    result = run_gsrwt("rectify", str(path), "--auto", "--focal", "700", "-j", "1", "-o",
                       str(tmp_path / "auto"), "--table", str(tmp_path / "auto.csv"))
    assert result.returncode == 0, result.stderr
    row = read_table(tmp_path / "auto.csv")[0]
    assert row["orientation"] == "8" and abs(float(row["pan_deg"]) - 40) < 0.5


def test_lines_and_match_find_the_same_landmarks_on_a_turned_photo(tmp_path):
    """A sample door view stored turned (tag 6): lines and match give the upright view's rows,
    frontal and source pixels alike (the source pixels are the displayed photo's)."""
    views = Path(__file__).resolve().parents[2] / "sample_data"
    with Image.open(views / "views" / "door_p20_t-8_f800.jpg") as door:
        upright = write_oriented(tmp_path / "upright.png", door.copy(), None)
        turned = write_oriented(tmp_path / "turned.png", door.copy(), 6)
    pose = ["--pan", "20", "--tilt", "-8", "--focal", "800", "--format", "csv"]

    def rows(command: str, path: Path, *extra: str) -> list[dict]:
        result = run_gsrwt(command, str(path), *pose, *extra)
        assert result.returncode == 0, result.stderr
        found = read_table(result.stdout)
        assert found
        return [{key: value for key, value in row.items() if key != "image"} for row in found]

    knob = ["--template", str(views / "templates" / "knob.png")]
    assert rows("lines", turned, "--orientation", "vertical") == rows(
        "lines", upright, "--orientation", "vertical")
    assert rows("match", turned, *knob) == rows("match", upright, *knob)
    ignored = run_gsrwt("lines", str(turned), *pose, "--exif-orientation", "ignore")
    assert ignored.stdout != run_gsrwt("lines", str(upright), *pose).stdout


def test_corners_are_the_displayed_photos(tmp_path):
    """``--corners`` (the README's door) on the door view stored turned (tag 7): the same
    corners, of the displayed photo, give the upright view's output and pose."""
    door_path = Path(__file__).resolve().parents[2] / "sample_data" / "views" / \
        "door_p20_t-8_f800.jpg"
    with Image.open(door_path) as door:
        upright = write_oriented(tmp_path / "upright.png", door.copy(), None)
        turned = write_oriented(tmp_path / "turned.png", door.copy(), 7)
    corners = "541.9,77.9 780.4,45.4 766.7,638.2 550.5,613.2"

    def run(path: Path) -> tuple[np.ndarray, dict]:
        out = tmp_path / path.stem
        result = run_gsrwt("rectify", str(path), "--corners", corners, "--bbox", "corners",
                           "-j", "1", "-o", str(out), "--table", str(out / "t.csv"))
        assert result.returncode == 0, result.stderr
        return stored_pixels(out / path.name), read_table(out / "t.csv")[0]

    (reference, upright_row), (output, turned_row) = run(upright), run(turned)
    assert turned_row["orientation"] == "7"
    for column in ("pan_deg", "tilt_deg", "roll_deg", "focal_px"):
        assert turned_row[column] == upright_row[column]
    assert np.array_equal(output, reference)
