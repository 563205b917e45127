"""Real photos: OpenCV's chessboard photos (``tests/data/right*.jpg``, see its README),
raw and distorted, rectified in one call from their calibration file and solvePnP poses.

The boards must come out square (corners on a square grid to under 0.6 px), upright (board
axes along columns and rows within 0.5 degrees) and at the frontal scale (``--px-per-unit
20``: 20 output pixels per board square, within 2 %). The corners are found in the output by
OpenCV's own chessboard detector, independent of gsrwt.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

PHOTOS = sorted(DATA.glob("right*.jpg"))
BOARD = (9, 6)
PX_PER_SQUARE = 20.0


def board_fit(grey: np.ndarray) -> tuple[float, float, float]:
    """(residual RMS px, pixels per square, angle of the board's x axis mod 90 degrees) of the
    least-squares similarity from board coordinates to the detected corners."""
    found, corners = cv2.findChessboardCorners(grey, BOARD)
    assert found, "no board found in the rectified view"
    corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4))
    corners = corners.reshape(-1, 2)
    board = np.array([[i, j] for j in range(BOARD[1]) for i in range(BOARD[0])], float)
    design = np.zeros((2 * len(board), 4))
    design[0::2] = np.column_stack([board[:, 0], -board[:, 1], np.ones(len(board)),
                                    np.zeros(len(board))])
    design[1::2] = np.column_stack([board[:, 1], board[:, 0], np.zeros(len(board)),
                                    np.ones(len(board))])
    solution, *_ = np.linalg.lstsq(design, corners.ravel(), rcond=None)
    residual = (design @ solution).reshape(-1, 2) - corners
    rms = math.sqrt(float(np.mean(np.sum(residual**2, axis=1))))
    angle = math.degrees(math.atan2(solution[1], solution[0]))
    return rms, math.hypot(solution[0], solution[1]), (angle + 45) % 90 - 45


@pytest.mark.slow
@pytest.mark.parametrize("camera", ["right_camera.yml", "right_camera.xml",
                                    "right_camera_ros.yaml"])
def test_raw_chessboard_photos_come_out_square_upright_and_at_scale(tmp_path, camera):
    assert len(PHOTOS) >= 10
    result = run_gsrwt("rectify", *map(str, PHOTOS), "--sidecar", str(DATA / "right_poses.csv"),
                       "--camera", str(DATA / camera), "--px-per-unit", str(PX_PER_SQUARE),
                       "--bbox", "full", "--max-stretch", "3", "-o", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert {row["focal_source"] for row in rows} == {"camera"}
    assert any(abs(float(row["roll_deg"])) > 45 for row in rows)  # boards turned on their side
    for photo in PHOTOS:
        rectified = cv2.imread(str(tmp_path / "out" / photo.name), cv2.IMREAD_GRAYSCALE)
        rms, scale, angle = board_fit(rectified)
        assert rms < 0.6, (photo.name, rms)
        assert abs(angle) < 0.5, (photo.name, angle)
        assert abs(scale / PX_PER_SQUARE - 1) < 0.02, (photo.name, scale)
        raw = cv2.imread(str(photo), cv2.IMREAD_GRAYSCALE)
        assert board_fit(raw)[0] > 1.0  # the raw photo's board is far from a square grid


def test_a_bad_calibration_file_is_a_usage_error_naming_file_and_key(tmp_path):
    bad = tmp_path / "bad.yaml"
    text = (DATA / "right_camera_ros.yaml").read_text().replace("rows: 3\n  cols: 3",
                                                                 "rows: 2\n  cols: 3", 1)
    bad.write_text(text)
    result = run_gsrwt("rectify", str(PHOTOS[0]), "--pan", "10", "--tilt", "5", "--camera",
                       str(bad), "-o", str(tmp_path / "out"))
    assert result.returncode == 2, result.stderr
    (line,) = result.stderr.strip().splitlines()
    assert "bad.yaml" in line and "camera_matrix" in line, line
    assert not (tmp_path / "out").exists()


def test_an_image_of_another_size_than_the_calibration_is_that_images_error(tmp_path):
    small = tmp_path / "small.jpg"
    cv2.imwrite(str(small), cv2.resize(cv2.imread(str(PHOTOS[0])), (320, 240)))
    result = run_gsrwt("rectify", str(PHOTOS[0]), str(small), "--pan", "10", "--tilt", "5",
                       "--camera", str(DATA / "right_camera.yml"), "-o", str(tmp_path / "out"))
    assert result.returncode == 1
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error:")]
    assert len(errors) == 1 and "small.jpg" in errors[0]
    assert "640x480" in errors[0] and "320x240" in errors[0]


def test_a_camera_column_names_a_file_relative_to_the_sidecar(tmp_path):
    rig = tmp_path / "rig"
    rig.mkdir()
    (rig / "cam.yaml").write_text((DATA / "right_camera_ros.yaml").read_text())
    (rig / "views.csv").write_text(f"image,pan,tilt,camera\n{PHOTOS[0].name},10,5,cam.yaml\n")
    result = run_gsrwt("params", "--sidecar", str(rig / "views.csv"), "--format", "json")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout, "json")
    assert row["fx_px"] == pytest.approx(537.4531777322077)
