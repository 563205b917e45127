"""``gsrwt estimate`` and ``gsrwt rectify --auto``, run as a user runs them (real files, real
subprocesses of the ``gsrwt`` command)."""

from __future__ import annotations

import shutil

import cv2
import numpy as np
import pytest

from tests.helpers.cli import run_gsrwt, start_gsrwt
from tests.helpers.estimate_scenes import render_room
from tests.helpers.paths import ROOT
from tests.helpers.tables import by_image_name, read_table

VIEWS = ROOT / "sample_data" / "views"


def test_estimate_then_rectify_reproduces_the_known_pose_rectification(tmp_path):
    """The sample views' sidecar gives their intrinsics only for the estimate (its poses are
    ignored); the estimated rows rectify as the known poses do: PSNR >= 30 dB each."""
    poses = tmp_path / "poses.csv"
    result = run_gsrwt("estimate", str(VIEWS), "--sidecar", str(VIEWS / "views.csv"),
                       "-o", str(poses), "-j", "2")
    assert result.returncode == 0, result.stderr
    assert "9 estimated, 0 failed" in result.stderr
    rows = read_table(poses)
    assert list(rows[0])[:9] == ["image", "pan", "tilt", "roll", "focal", "fx", "fy", "cx", "cy"]
    truth = {row["image"]: row for row in read_table(VIEWS / "views.csv")}
    for row in rows:
        assert row["status"] == "ok" and row["focal_source"] == "sidecar"
        known = truth[row["image"]]
        assert float(row["tilt"]) == pytest.approx(float(known["tilt"]), abs=0.2)
        assert float(row["pan"]) == pytest.approx(float(known["pan"]), abs=0.2)
        assert 0.5 < float(row["confidence"]) <= 1
    for sidecar, out in ((poses, "estimated"), (VIEWS / "views.csv", "known")):
        result = run_gsrwt("rectify", str(VIEWS), "--sidecar", str(sidecar), "-o",
                           str(tmp_path / out), "-q")
        assert result.returncode == 0, result.stderr
    for row in rows:
        name = row["image"]
        known = cv2.imread(str(tmp_path / "known" / name)).astype(np.float64)
        estimated = cv2.imread(str(tmp_path / "estimated" / name)).astype(np.float64)
        assert cv2.PSNR(known, estimated) >= 30, name


def test_images_that_cannot_tell_are_error_rows_and_exit_1(tmp_path):
    rng = np.random.default_rng(3)
    cv2.imwrite(str(tmp_path / "blank.png"), np.full((480, 640), 200, np.uint8))
    cv2.imwrite(str(tmp_path / "noise.png"), rng.integers(0, 256, (480, 640), dtype=np.uint8))
    shot = render_room(20, -8, 3, focal=520, seed=4)
    cv2.imwrite(str(tmp_path / "room.png"), shot.image)
    result = run_gsrwt("estimate", str(tmp_path), "--focal", "520", "-f", "csv")
    assert result.returncode == 1
    rows = {row["image"]: row for row in read_table(result.stdout)}
    for name in ("blank.png", "noise.png"):
        assert rows[name]["status"] == "error" and rows[name]["pan"] == ""
        assert rows[name]["error"].startswith("too few straight segments")
        assert f"Error: {name}: too few straight segments" in result.stderr
    assert rows["room.png"]["status"] == "ok"
    assert float(rows["room.png"]["tilt"]) == pytest.approx(-8, abs=0.5)
    assert float(rows["room.png"]["roll"]) == pytest.approx(3, abs=0.5)
    assert "Traceback" not in result.stderr


def test_min_confidence_turns_weak_estimates_into_errors(tmp_path):
    image = VIEWS / "corridor_p45_t30.png"  # confidence below 1, as every estimate's
    result = run_gsrwt("estimate", str(image), "--focal", "280", "--min-confidence", "1",
                       "-f", "json")
    assert result.returncode == 1
    assert "is below the minimum 1 (another orientation fits the lines" in result.stderr
    # and says what would settle it; the focal length was given, so not that
    assert "; give the pose, or guides (--verticals)\ngsrwt: 0 estimated, 1 failed" in result.stderr
    result = run_gsrwt("estimate", str(image), "--min-confidence", "1", "-f", "json")
    assert result.returncode == 1
    assert "; give the focal length, the pose, or guides (--verticals)" in result.stderr
    result = run_gsrwt("estimate", str(image), "--focal", "280", "--min-confidence", "0.3",
                       "-f", "json")
    assert result.returncode == 0, result.stderr


def test_draw_writes_a_picture_per_image(tmp_path):
    result = run_gsrwt("estimate", str(VIEWS / "door_p20_t-8_f800.jpg"), "--focal", "800",
                       "--draw", str(tmp_path / "drawn"), "-q")
    assert result.returncode == 0, result.stderr
    picture = cv2.imread(str(tmp_path / "drawn" / "door_p20_t-8_f800.png"))
    assert picture.shape == (960, 1280, 3)
    red = (picture[:, :, 2] > 200) & (picture[:, :, 1] < 60) & (picture[:, :, 0] < 60)
    assert red.sum() > 500  # the vertical segments


def test_the_focal_length_is_estimated_when_nothing_gives_it(tmp_path):
    image = VIEWS / "door_p40_t-12_f700.jpg"
    result = run_gsrwt("estimate", str(image), "-f", "csv")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout)
    assert row["focal_source"] == "estimated"
    assert float(row["focal"]) == pytest.approx(700, rel=0.02)
    assert float(row["pan"]) == pytest.approx(40, abs=0.3)
    frontal = VIEWS / "door_p8_t-2_f1500.jpg"  # vanishing points far away: it cannot tell
    result = run_gsrwt("estimate", str(frontal), "-f", "csv")
    assert result.returncode == 1
    assert "cannot tell the focal length" in result.stderr


def test_rectify_auto_estimates_what_no_source_gives(tmp_path):
    images = tmp_path / "images"
    images.mkdir()
    for name in ("door_p20_t-8_f800.jpg", "sign_p-25_t10_f1120.jpg"):
        shutil.copy(VIEWS / name, images / name)
    sidecar = tmp_path / "one.csv"
    sidecar.write_text("image,pan,tilt,focal\nsign_p-25_t10_f1120.jpg,-25,10,1120\n")
    table = tmp_path / "table.csv"
    result = run_gsrwt("rectify", str(images), "--sidecar", str(sidecar), "--auto",
                       "--focal", "800", "-o", str(tmp_path / "out"), "--table", str(table))
    assert result.returncode == 0, result.stderr
    rows = by_image_name(read_table(table))
    door = rows["door_p20_t-8_f800.jpg"]
    assert door["pose_source"] == "estimated" and 0.5 < float(door["confidence"]) <= 1
    assert float(door["pan_deg"]) == pytest.approx(20, abs=0.2)
    assert rows["sign_p-25_t10_f1120.jpg"]["pose_source"] == "sidecar"
    assert rows["sign_p-25_t10_f1120.jpg"]["confidence"] == ""
    # Without --bbox, the photo's own pose frames the whole wall it shows (capped at twice
    # the input's pixels); the pose given keeps the thesis's frame, the input's size.
    sign = rows["sign_p-25_t10_f1120.jpg"]
    assert "bbox=frontal" in sign["made_with"] and "max_area" not in sign["made_with"]
    assert (sign["out_width"], sign["out_height"]) == ("1280", "960")
    assert "bbox=full" in door["made_with"] and "max_area=2" in door["made_with"]
    door_pixels = int(door["out_width"]) * int(door["out_height"])
    assert 1280 * 960 < door_pixels <= 2 * 1280 * 960
    known = tmp_path / "known"
    run_gsrwt("rectify", str(VIEWS / "door_p20_t-8_f800.jpg"), "--sidecar",
              str(VIEWS / "views.csv"), "-o", str(known), "-q")
    framed = tmp_path / "framed"  # --bbox given: the estimated pose takes it
    result = run_gsrwt("rectify", str(images / "door_p20_t-8_f800.jpg"), "--auto", "--focal",
                       "800", "--bbox", "frontal", "-o", str(framed), "-q")
    assert result.returncode == 0, result.stderr
    a = cv2.imread(str(known / "door_p20_t-8_f800.jpg")).astype(np.float64)
    b = cv2.imread(str(framed / "door_p20_t-8_f800.jpg")).astype(np.float64)
    assert cv2.PSNR(a, b) >= 30
    result = run_gsrwt("rectify", str(images), "--focal", "800", "-o", str(tmp_path / "no"))
    assert result.returncode == 1  # without --auto, no pose is an error
    assert "no parameters" in result.stderr


def test_an_output_table_over_an_input_is_refused(tmp_path):
    image = tmp_path / "door.jpg"
    shutil.copy(VIEWS / "door_p20_t-8_f800.jpg", image)
    result = run_gsrwt("estimate", str(image), "-o", str(image), "--format", "csv")
    assert result.returncode == 2
    assert "would overwrite an input" in result.stderr
    assert cv2.imread(str(image)) is not None


def test_a_stopped_run_still_gives_every_image_its_row(tmp_path):
    """SIGTERM after the first rows: the workers stop, the rest are rows marked interrupted,
    exit code 143."""
    import signal

    for index in range(40):
        shutil.copy(VIEWS / "door_p20_t-8_f800.jpg", tmp_path / f"door{index:02d}.jpg")
    process = start_gsrwt("estimate", str(tmp_path), "--focal", "800", "-f", "csv", "-j", "1")
    assert process.stdout is not None
    lines = [process.stdout.readline(), process.stdout.readline()]  # header, first row
    process.send_signal(signal.SIGTERM)
    rest, errors = process.communicate(timeout=60)
    rows = read_table("".join(lines) + rest)
    assert process.returncode == 143, errors
    assert len(rows) == 40
    statuses = [row["status"] for row in rows]
    assert statuses[0] == "ok" and statuses[-1] == "interrupted"
    assert set(statuses) <= {"ok", "interrupted"}
    assert "interrupted:" in errors and "Traceback" not in errors


def test_the_tables_name_the_estimators_vanishing_points_in_its_order():
    """``tables.columns`` (numpy-free, for start-up) spells the estimator's directions
    itself; they must be the estimator's, in its order."""
    from gsrwt_cli.api.estimate import DIRECTION_NAMES
    from gsrwt_cli.tables.columns import ESTIMATE_COLUMNS, VANISHING_DIRECTIONS

    assert VANISHING_DIRECTIONS == DIRECTION_NAMES
    assert [name for name in ESTIMATE_COLUMNS if name.startswith("vp_")] == [
        f"vp_{name}_{axis}" for name in DIRECTION_NAMES for axis in ("col", "row")]
