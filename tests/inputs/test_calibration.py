"""Calibration files: OpenCV FileStorage YAML/XML and ROS camera_info, read into Intrinsics.

The real data: OpenCV's right-camera chessboard photos (tests/data/README.md), calibrated
here with OpenCV, written in the three formats, read back and reprojected.
"""

from __future__ import annotations

import importlib.util
import math
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.inputs.calibration import (
    MAX_FILE_BYTES,
    CalibrationError,
    intrinsics_close,
    intrinsics_from_camera_info,
    load_camera,
    write_opencv_xml,
    write_opencv_yaml,
    write_ros_yaml,
)
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

CAMERA_FILES = ("right_camera.yml", "right_camera.xml", "right_camera_ros.yaml")


def _maker():
    """tests/data/make_right_calibration.py, the script that made the committed files."""
    name = "make_right_calibration"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, DATA / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up while it executes
        spec.loader.exec_module(module)
    return sys.modules[name]


@pytest.fixture(scope="module")
def maker():
    return _maker()


@pytest.fixture(scope="module")
def calibration(maker):
    return maker.calibrate()


def _poses() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    rows = read_table(DATA / "right_poses.csv")
    return {
        row["image"]: (
            np.array([float(row[f"rvec_{axis}"]) for axis in "xyz"]),
            np.array([float(row[f"tvec_{axis}"]) for axis in "xyz"]),
        )
        for row in rows
    }


# --------------------------------------------------------------------------------------------
# The real photos


def test_the_committed_files_are_what_calibrating_the_photos_gives(maker, calibration):
    assert len(calibration.corners) == 13 and calibration.size == (640, 480)
    assert calibration.rms < 0.3
    loaded = load_camera(DATA / "right_camera.yml")
    # Another OpenCV build may round differently: agreement to 1e-6 of the values.
    np.testing.assert_allclose(loaded.matrix(), calibration.camera_matrix, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(
        loaded.lens.opencv_coefficients(), calibration.distortion, rtol=1e-5, atol=1e-6
    )
    poses = _poses()
    assert list(poses) == list(maker.IMAGES)
    for name, corners in calibration.corners.items():
        rvec, tvec = maker.board_pose(corners, calibration.camera_matrix, calibration.distortion)
        np.testing.assert_allclose(poses[name][0], rvec, atol=1e-6)
        np.testing.assert_allclose(poses[name][1], tvec, rtol=1e-6, atol=1e-6)


def test_the_committed_left_poses_are_what_opencvs_own_calibration_gives(maker):
    """``left/left_poses.csv`` (tests/data/make_left_poses.py): each left photo's board pose
    by ``cv2.solvePnP`` with OpenCV's calibration of that camera, which reprojects the 54
    detected corners of every photo within 0.6 px RMS (OpenCV's own file says 0.39 over all)."""
    spec = importlib.util.spec_from_file_location("make_left_poses", DATA / "make_left_poses.py")
    left = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(left)  # it imports make_right_calibration: loaded by ``maker``
    rows = read_table(DATA / "left" / "left_poses.csv")
    assert [row["image"] for row in rows] == list(left.IMAGES)
    matrix, distortion = left.opencv_calibration()
    for row in rows:
        rvec = np.array([float(row[f"rvec_{axis}"]) for axis in "xyz"])
        tvec = np.array([float(row[f"tvec_{axis}"]) for axis in "xyz"])
        corners = maker.detect_corners(DATA / "left" / row["image"])
        again = maker.board_pose(corners, matrix, distortion)
        np.testing.assert_allclose(rvec, again[0], atol=1e-6)
        np.testing.assert_allclose(tvec, again[1], rtol=1e-6, atol=1e-6)
        projected = cv2.projectPoints(maker.board_points(), rvec, tvec, matrix,
                                      distortion)[0].reshape(-1, 2)
        assert math.sqrt(((projected - corners) ** 2).sum(axis=1).mean()) < 0.6, row["image"]


def test_the_three_formats_read_back_to_the_same_intrinsics():
    cameras = [load_camera(DATA / name) for name in CAMERA_FILES]
    first = cameras[0]
    assert (first.width, first.height) == (640, 480)
    assert first.lens is not None and first.lens.model == "plumb_bob"
    assert first.skew == 0.0
    # The values calibrateCamera gave for these photos (make_right_calibration.py's output).
    assert first.fx == pytest.approx(537.453, abs=0.01)
    assert first.fy == pytest.approx(536.969, abs=0.01)
    assert first.cx == pytest.approx(327.586, abs=0.01)
    assert first.cy == pytest.approx(248.882, abs=0.01)
    assert first.lens.value("k1") == pytest.approx(-0.2975, abs=1e-3)
    for other in cameras[1:]:
        assert intrinsics_close(first, other, 1e-9), other
    # and to what OpenCV itself reads from its own files
    storage = cv2.FileStorage(str(DATA / "right_camera.xml"), cv2.FILE_STORAGE_READ)
    np.testing.assert_array_equal(first.matrix(), storage.getNode("camera_matrix").mat())
    np.testing.assert_array_equal(
        first.lens.opencv_coefficients(), storage.getNode("distortion_coefficients").mat().ravel()
    )
    storage.release()


@pytest.mark.parametrize("name", CAMERA_FILES)
def test_projecting_the_board_with_a_loaded_camera_gives_the_detected_corners(name, calibration):
    camera = load_camera(DATA / name)
    objects = _maker().board_points()
    poses = _poses()
    squared = []
    pinhole_squared = []
    for image, corners in calibration.corners.items():
        rvec, tvec = poses[image]
        projected, _ = cv2.projectPoints(
            objects, rvec, tvec, camera.matrix(), camera.lens.opencv_coefficients()
        )
        squared.append(np.sum((projected.reshape(-1, 2) - corners) ** 2, axis=1))
        pinhole, _ = cv2.projectPoints(objects, rvec, tvec, camera.matrix(), np.zeros(5))
        pinhole_squared.append(np.sum((pinhole.reshape(-1, 2) - corners) ** 2, axis=1))
    rms = math.sqrt(np.mean(np.concatenate(squared)))
    assert rms < 0.6
    assert max(math.sqrt(np.mean(errors)) for errors in squared) < 0.6  # every photo
    # The lens matters: the same poses without the distortion miss by pixels.
    assert math.sqrt(np.mean(np.concatenate(pinhole_squared))) > 3.0


def test_every_board_faces_the_camera_in_the_poses_file():
    for rvec, tvec in _poses().values():
        rotation, _ = cv2.Rodrigues(rvec)
        assert rotation[2, 2] > 0.5  # the board's z axis (into it) points away from the camera
        assert 10 < tvec[2] < 20  # squares: the board is 10-20 squares away


def test_a_file_written_by_opencv_4s_calibration_sample_reads():
    # OpenCV's samples/cpp/calibration.cpp output as OpenCV ships it: %YAML:1.0, a 5x1
    # distortion column and keys gsrwt does not use (extrinsics, reprojection errors).
    camera = load_camera(DATA / "opencv4_left_intrinsics.yml")
    assert (camera.width, camera.height) == (640, 480)
    assert camera.fx == camera.fy == pytest.approx(535.91573396163199, rel=1e-15)
    assert camera.cx == pytest.approx(342.28315473308373, rel=1e-15)
    assert camera.cy == pytest.approx(235.57082909788173, rel=1e-15)
    assert camera.lens.model == "plumb_bob"
    assert camera.lens.value("k1") == pytest.approx(-0.26637260909660682, rel=1e-15)
    assert camera.lens.value("k3") == pytest.approx(0.23839153080878486, rel=1e-15)


# --------------------------------------------------------------------------------------------
# Round trips through the writers, every model


def _lens(model: str, count: int) -> Lens:
    from gsrwt_cli.geometry.lens import LENS_MODELS

    values = [0.1 * (-1) ** index / (index + 1) for index in range(count)]
    return Lens(model, tuple(zip(LENS_MODELS[model][:count], values)))


@pytest.mark.parametrize(
    "lens",
    [None, _lens("plumb_bob", 5), _lens("plumb_bob", 4), _lens("rational_polynomial", 8),
     _lens("rational_polynomial", 12), _lens("rational_polynomial", 14),
     _lens("equidistant", 4)],
    ids=["pinhole", "plumb_bob5", "plumb_bob4", "rational8", "rational12", "rational14",
         "equidistant"],
)
@pytest.mark.parametrize("writer", [write_opencv_yaml, write_opencv_xml, write_ros_yaml])
def test_every_model_round_trips_through_every_format(tmp_path, writer, lens):
    camera = Intrinsics(fx=1234.5, fy=1200.25, cx=640.75, cy=470.5, skew=1.5, width=1280,
                        height=960, lens=lens)
    path = tmp_path / ("camera.xml" if writer is write_opencv_xml else "camera.yaml")
    writer(path, camera)
    loaded = load_camera(path)
    assert loaded.skew == 1.5  # skew kept as skew
    assert intrinsics_close(loaded, camera, 1e-12)
    assert (loaded.lens is None) == (lens is None)
    if lens is not None:
        assert loaded.lens.model == lens.model


def test_opencv_sample_spellings_and_the_interactive_calibration_layout(tmp_path):
    # opencv_interactive-calibration: cameraMatrix, dist_coeffs, cameraResolution [w, h].
    path = tmp_path / "interactive.xml"
    path.write_text(
        '<?xml version="1.0"?>\n<opencv_storage>\n<calibrationDate>"today"</calibrationDate>\n'
        "<cameraResolution>\n  1920 1080</cameraResolution>\n"
        '<cameraMatrix type_id="opencv-matrix">\n  <rows>3</rows>\n  <cols>3</cols>\n'
        "  <dt>d</dt>\n  <data>\n    1500. 0. 959.5 0. 1490. 539.5 0. 0. 1.</data></cameraMatrix>\n"
        '<dist_coeffs type_id="opencv-matrix">\n  <rows>1</rows>\n  <cols>4</cols>\n'
        "  <dt>d</dt>\n  <data>\n    -0.1 0.02 0.001 -0.002</data></dist_coeffs>\n"
        "</opencv_storage>\n"
    )
    camera = load_camera(path)
    assert (camera.width, camera.height) == (1920, 1080)
    assert (camera.fx, camera.fy, camera.cx, camera.cy) == (1500.0, 1490.0, 959.5, 539.5)
    assert camera.lens.model == "plumb_bob"
    assert dict(camera.lens.coefficients) == {"k1": -0.1, "k2": 0.02, "p1": 0.001, "p2": -0.002}
    # No size at all (OpenCV's aruco sample camera files): the size stays unknown.
    bare = tmp_path / "bare.yml"
    bare.write_text(
        "%YAML:1.0\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
        "   data: [ 628.158, 0., 324.099, 0., 628.156, 260.908, 0., 0., 1. ]\n"
        "distortion_coefficients: !!opencv-matrix\n   rows: 5\n   cols: 1\n   dt: d\n"
        "   data: [ 0.0995485, -0.206384, 0.00754589, 0.00336531, 0 ]\n"
    )
    camera = load_camera(bare)
    assert camera.width is None and camera.cx == 324.099
    assert camera.lens.value("k2") == -0.206384


def test_a_ros_file_without_distortion_is_a_pinhole(tmp_path):
    path = tmp_path / "ros.yaml"
    path.write_text(
        "image_width: 640\nimage_height: 480\ncamera_name: cam\n"
        "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 319.5, 0, 500, 239.5, 0, 0, 1]}\n"
        "distortion_model: plumb_bob\ndistortion_coefficients: {rows: 1, cols: 0, data: []}\n"
    )
    camera = load_camera(path)
    assert camera.lens is None and camera.fx == 500.0 and isinstance(camera.fx, float)
    path.write_text(path.read_text().replace("{rows: 1, cols: 0, data: []}",
                                             "{rows: 1, cols: 4, data: [0.1, 0, 0, 0.2]}")
                    .replace("plumb_bob", "fisheye"))
    camera = load_camera(path)
    assert camera.lens.model == "equidistant" and camera.lens.value("k4") == 0.2


# --------------------------------------------------------------------------------------------
# Bad files: the file and the key named, never a crash

_K = "[500, 0, 319.5, 0, 500, 239.5, 0, 0, 1]"


def _ros(**changes: str) -> str:
    fields = {
        "image_width": "640", "image_height": "480",
        "camera_matrix": f"{{rows: 3, cols: 3, data: {_K}}}",
        "distortion_model": "plumb_bob",
        "distortion_coefficients": "{rows: 1, cols: 5, data: [-0.2, 0.05, 0, 0, 0]}",
    }
    fields.update(changes)
    return "".join(f"{key}: {value}\n" for key, value in fields.items() if value is not None)


def _opencv(matrix: str = "rows: 3\n   cols: 3\n   dt: d\n   data: " + _K,
            distortion: str = "rows: 1\n   cols: 5\n   dt: d\n   data: [ -0.2, 0.05, 0., 0., 0. ]",
            extra: str = "image_width: 640\nimage_height: 480\n") -> str:
    return (f"%YAML:1.0\n---\n{extra}camera_matrix: !!opencv-matrix\n   {matrix}\n"
            f"distortion_coefficients: !!opencv-matrix\n   {distortion}\n")


BAD = {
    "ros-2x3": (_ros(camera_matrix="{rows: 2, cols: 3, data: [1, 0, 0, 0, 1, 0]}"),
                "camera_matrix", "expected 3x3 numbers, got 2x3"),
    "ros-count": (_ros(camera_matrix="{rows: 3, cols: 3, data: [1, 2, 3]}"),
                  "camera_matrix", "its data holds 3 values, not rows x cols = 9"),
    "ros-nan": (_ros(camera_matrix="{rows: 3, cols: 3, data: [.nan, 0, 1, 0, 1, 1, 0, 0, 1]}"),
                "camera_matrix", "not a finite number"),
    "ros-string": (_ros(camera_matrix="{rows: 3, cols: 3, data: [a, 0, 1, 0, 1, 1, 0, 0, 1]}"),
                   "camera_matrix.data", "expected a number, got 'a'"),
    "ros-bool": (_ros(image_width="true"), "image_width", "expected a number, got .True."),
    "ros-huge-int": (_ros(image_width="1" + "0" * 400), "image_width", "expected a finite"),
    "ros-negative-f": (_ros(camera_matrix="{rows: 3, cols: 3, data: [-500, 0, 319.5, 0, 500, "
                                          "239.5, 0, 0, 1]}"),
                       "camera_matrix", "fx must be positive, got -500"),
    "ros-absurd-f": (_ros(camera_matrix="{rows: 3, cols: 3, data: [1.0e+12, 0, 319.5, 0, 500, "
                                        "239.5, 0, 0, 1]}"),
                     "camera_matrix", "fx must be below 1e\\+07 pixels"),
    "ros-lower-row": (_ros(camera_matrix="{rows: 3, cols: 3, data: [500, 0, 319.5, 0, 500, "
                                         "239.5, 0.5, 0, 1]}"),
                      "camera_matrix",
                      r"expected \[\[fx, skew, cx\], \[0, fy, cy\], \[0, 0, 1\]\], "
                      r"got rows 2 and 3 \[0, 500, 239.5\] \[0.5, 0, 1\]"),
    "ros-far-principal-point": (_ros(camera_matrix="{rows: 3, cols: 3, data: [500, 0, 5000, "
                                                   "0, 500, 239.5, 0, 0, 1]}"),
                                "camera_matrix", "cx = 5000 lies more than 1 image side"),
    "ros-zero-width": (_ros(image_width="0"), "image_width", "width must be positive"),
    "ros-fraction-width": (_ros(image_width="640.5"), "image_width", "whole number"),
    "ros-no-height": (_ros(image_height=None), "image_height", "missing"),
    "ros-no-matrix": (_ros(camera_matrix=None), "camera_matrix", "missing"),
    "ros-no-model": (_ros(distortion_model=None), "distortion_model", "missing"),
    "ros-unknown-model": (_ros(distortion_model="division"), "distortion_model",
                          "unknown lens model 'division'"),
    "ros-model-not-string": (_ros(distortion_model="[1]"), "distortion_model", "expected a string"),
    "ros-fisheye-5": (_ros(distortion_model="equidistant"), "distortion_coefficients",
                      "the equidistant model takes 4 coefficients, got 5"),
    "ros-rational-5": (_ros(distortion_model="rational_polynomial"), "distortion_coefficients",
                       "takes 8 or 12 or 14 coefficients, got 5"),
    "ros-distortion-6": (_ros(distortion_coefficients="{rows: 1, cols: 6, data: [1, 2, 3, 4, 5, "
                                                      "6]}"),
                         "distortion_coefficients", "takes 4 or 5 coefficients, got 6"),
    "ros-distortion-3x3": (_ros(distortion_coefficients=f"{{rows: 3, cols: 3, data: {_K}}}"),
                           "distortion_coefficients", "one row or column"),
    "ros-absurd-k1": (_ros(distortion_coefficients="{rows: 1, cols: 5, data: [1.0e+9, 0, 0, 0, "
                                                   "0]}"),
                      "distortion_coefficients", "k1 must be within 1e6"),
    "ros-empty-rows": (_ros(camera_matrix=f"{{rows: , cols: 3, data: {_K}}}"), "camera_matrix",
                       "expected numbers for rows and cols"),
    "ros-matrix-list": (_ros(camera_matrix=_K), "camera_matrix",
                        "expected a mapping with rows, cols and data, got a list"),
    "opencv-2x3": (_opencv(matrix="rows: 2\n   cols: 3\n   dt: d\n   data: [1, 0, 0, 0, 1, 0]"),
                   "camera_matrix", "expected 3x3 numbers, got 2x3"),
    "opencv-count": (_opencv(matrix="rows: 3\n   cols: 3\n   dt: d\n   data: [1, 0, 0]"),
                     "camera_matrix", "its data holds 3 values, not rows x cols = 9"),
    "opencv-inf": (_opencv(matrix="rows: 3\n   cols: 3\n   dt: d\n   data: [.Inf, 0, 1, 0, 1, "
                                  "1, 0, 0, 1]"),
                   "camera_matrix", "not a finite number"),
    "opencv-huge-matrix": (_opencv(distortion="rows: 100000\n   cols: 100000\n   dt: d\n"
                                              "   data: [1, 2]"),
                           "distortion_coefficients", "one row or column of at most 14"),
    "opencv-distortion-7": (_opencv(distortion="rows: 1\n   cols: 7\n   dt: d\n   data: [1, 0, "
                                               "0, 0, 0, 0, 0]"),
                            "distortion_coefficients", "rational_polynomial model takes 8"),
    "opencv-width-string": (_opencv(extra="image_width: wide\nimage_height: 480\n"),
                            "image_width", "expected a number"),
    "opencv-plain-list": ("%YAML:1.0\ncamera_matrix: [500, 0, 319.5, 0, 500, 239.5, 0, 0, 1]\n",
                          "camera_matrix", "expected an opencv-matrix"),
    "opencv-two-spellings": (_opencv() + "dist_coeffs: !!opencv-matrix\n   rows: 1\n   cols: 4\n"
                                         "   dt: d\n   data: [0, 0, 0, 0]\n",
                             "dist_coeffs", "given besides 'distortion_coefficients'"),
    "opencv-twice": (_opencv() + "image_width: 320\n", "image_width", "given twice"),
    "opencv-no-matrix": ("%YAML:1.0\nimage_width: 640\n", "camera_matrix", "missing"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_a_bad_file_is_refused_naming_the_file_and_the_key(tmp_path, case):
    text, key, reason = BAD[case]
    path = tmp_path / "camera.yaml"
    path.write_text(text)
    with pytest.raises(CalibrationError) as caught:
        load_camera(path)
    error = caught.value
    assert isinstance(error, ValueError)
    assert (error.path, error.key) == (str(path), key)
    assert str(error).startswith(f"{path}: key '{key}': ")
    assert "\n" not in str(error)
    assert re.search(reason, error.reason), error.reason


def test_the_message_reads_as_the_file_the_key_and_the_reason(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("camera.yaml").write_text(BAD["ros-2x3"][0])
    with pytest.raises(CalibrationError) as caught:
        load_camera("camera.yaml")
    assert str(caught.value) == "camera.yaml: key 'camera_matrix': expected 3x3 numbers, got 2x3"


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        (b"", "empty file"),
        (b"\xff\xd8\xff\xe0 a JPEG", "not UTF-8 text"),
        (b"%YAML:1.0\na: 1\x00\n", "NUL"),
        (b"- 1\n- 2\n", "expected a mapping .* got a list"),
        (b"just words", "expected a mapping"),
        (b"camera_matrix: [1, 2\n", "not valid YAML \\(line"),
        (b"a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n" + b"".join(
            f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]\n".encode()
            for i in range(8)), "aliases expand the document"),
        (b"%YAML:1.0\ncamera_matrix: !!opencv-matrix\n  rows: [1, 2\n", "line \\d+: "),
        (b'<?xml version="1.0"?>\n<opencv_storage>\n<a>3</a>\n<b>\n</opencv_storage>\n',
         "not a valid OpenCV FileStorage file \\(line 5: mismatched tag\\)"),
        (b"%YAML:1.0\na: " + b"[" * 100_000 + b"]" * 100_000 + b"\n", "nested deeper than 64"),
        (b'<?xml version="1.0"?>\n<opencv_storage>' + b"<a>" * 100_000 + b"</a>" * 100_000
         + b"</opencv_storage>\n", "nested deeper than 64"),
        (b"%YAML:1.0\n" + b"".join(b" " * i + b"k:\n" for i in range(300)), "indented"),
        (b"%YAML:1.0\n# " + b"x" * MAX_FILE_BYTES + b"\n", "larger than"),
    ],
    ids=["empty", "binary", "nul", "list", "scalar", "bad-yaml", "alias-bomb", "bad-opencv-yaml",
         "bad-xml", "deep-brackets", "deep-xml", "deep-indent", "huge"],
)
def test_a_file_that_is_no_calibration_is_refused_naming_the_file(tmp_path, content, reason):
    path = tmp_path / "camera.yml"
    path.write_bytes(content)
    with pytest.raises(CalibrationError) as caught:
        load_camera(path)
    assert caught.value.path == str(path)
    assert re.search(reason, caught.value.reason), caught.value.reason
    assert "\n" not in str(caught.value) and len(str(caught.value)) < 600


def test_deep_nesting_that_crashes_opencvs_parser_is_refused_in_a_real_process(tmp_path):
    # OpenCV's parser itself dies of a segmentation fault on this file; load_camera must
    # refuse it before. A subprocess, so that a crash fails the test instead of the run.
    path = tmp_path / "deep.yml"
    path.write_bytes(b"%YAML:1.0\na: " + b"[" * 200_000 + b"]" * 200_000 + b"\n")
    code = (
        "import sys\nfrom gsrwt_cli.inputs.calibration import load_camera, CalibrationError\n"
        "try:\n    load_camera(sys.argv[1])\nexcept CalibrationError as e:\n    print(e.reason)\n"
    )
    done = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "nested deeper than 64 levels"


def test_missing_and_directory_paths(tmp_path):
    with pytest.raises(CalibrationError, match="cannot read"):
        load_camera(tmp_path / "absent.yml")
    with pytest.raises(CalibrationError, match="is a directory"):
        load_camera(tmp_path)


def test_opencv_json_filestorage_reads_too(tmp_path):
    camera = load_camera(DATA / "right_camera.yml")
    storage = cv2.FileStorage("camera.json", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY)
    storage.write("image_width", 640)
    storage.write("image_height", 480)
    storage.write("camera_matrix", camera.matrix())
    storage.write("distortion_coefficients", camera.lens.opencv_coefficients())  # 1-D
    text = storage.releaseAndGetString()
    assert '"type_id": "opencv-nd-matrix"' in text and '"sizes": [ 5 ]' in text
    path = tmp_path / "camera.json"
    path.write_text(text)
    assert intrinsics_close(load_camera(path), camera, 0)
    # The same in YAML, where OpenCV 5 writes "%YAML 1.2" and the matrix tags say whose it is
    yaml_path = tmp_path / "nd.yml"
    storage = cv2.FileStorage("nd.yml", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY)
    storage.write("camera_matrix", camera.matrix())
    storage.write("distortion_coefficients", camera.lens.opencv_coefficients())
    yaml_path.write_text(storage.releaseAndGetString())
    assert yaml_path.read_text().startswith("%YAML 1.2")
    unsized = Intrinsics(fx=camera.fx, fy=camera.fy, cx=camera.cx, cy=camera.cy, lens=camera.lens)
    assert intrinsics_close(load_camera(yaml_path), unsized, 0)


def test_a_loaded_camera_makes_a_view():
    from gsrwt_cli.geometry.camera import Pose, View

    camera = load_camera(DATA / "right_camera_ros.yaml")
    view = View(intrinsics=camera, pose=Pose(20.0, -10.0), distance=14.0)
    assert view.intrinsics is camera
    assert view.focal == pytest.approx(math.sqrt(camera.fx * camera.fy), rel=1e-15)
    assert (view.width, view.height, view.cx, view.cy) == (640, 480, camera.cx, camera.cy)


_FUZZ = """
import collections, os, sys, tempfile
import numpy as np
from gsrwt_cli.inputs.calibration import CalibrationError, load_camera
rng = np.random.default_rng(11)
sources = [open(name, "rb").read() for name in sys.argv[1:]]
alphabet = b"[]{}<>/:,- \\n\\t0123456789.eE+!%\\"'&*abcdefxyz"
counts = collections.Counter()
folder = tempfile.mkdtemp()
for trial in range(1200):
    data = bytearray(sources[trial % len(sources)])
    for _ in range(int(rng.integers(1, 10))):
        position = int(rng.integers(0, len(data)))
        byte = alphabet[int(rng.integers(0, len(alphabet)))] if rng.random() < 0.8 else int(
            rng.integers(0, 256))
        operation = int(rng.integers(0, 3))
        if operation == 0:
            data[position] = byte
        elif operation == 1:
            data.insert(position, byte)
        else:
            del data[position]
    path = os.path.join(folder, "camera" + os.path.splitext(sys.argv[1 + trial % len(sources)])[1])
    open(path, "wb").write(data)
    try:
        load_camera(path)
        counts["read"] += 1
    except CalibrationError:
        counts["refused"] += 1
print(counts["read"], counts["refused"])
"""


def test_damaged_calibration_files_are_read_or_refused_never_a_crash():
    # 1200 copies of the four real files with bytes changed, inserted or deleted: each reads
    # or raises CalibrationError (any other exception fails the run), in a subprocess so
    # that a crash inside OpenCV's parser fails the test instead of ending the run.
    names = [str(DATA / name) for name in (*CAMERA_FILES, "opencv4_left_intrinsics.yml")]
    done = subprocess.run([sys.executable, "-c", _FUZZ, *names], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stderr == ""  # OpenCV printed nothing either
    read, refused = map(int, done.stdout.split())
    assert read + refused == 1200 and read > 20 and refused > 600


def test_camera_info_fields_are_checked_as_a_camera_info_file_is():
    """A CameraInfo message's fields (as a bag holds them) go through the file's checks."""
    k = [500.0, 0.5, 320.0, 0.0, 510.0, 240.0, 0.0, 0.0, 1.0]
    camera = intrinsics_from_camera_info("walk.bag /cam/camera_info", k,
                                         [0.1, -0.2, 0.0, 0.0, 0.05], "plumb_bob", 640, 480)
    assert (camera.fx, camera.fy, camera.cx, camera.cy, camera.skew) == (500, 510, 320, 240,
                                                                         0.5)
    assert (camera.width, camera.height) == (640, 480)
    assert camera.lens.model == "plumb_bob" and camera.lens.value("k2") == -0.2
    pinhole = intrinsics_from_camera_info("bag", k, [], "", 0, 0)
    assert pinhole.lens is None and pinhole.width is None
    assert intrinsics_from_camera_info("bag", k, [0.0] * 5, "plumb_bob", 0, 0).lens is None
    assert intrinsics_from_camera_info("bag", k, [0.1] * 4, "fisheye", 0, 0).lens.is_fisheye
    faults = [
        (([0.0] * 9, [], "", 0, 0), "key 'K': all zeros: an uncalibrated camera"),
        ((k[:6], [], "", 0, 0), "key 'K': expected 9 numbers, got 6"),
        ((k, [0.1] * 6, "plumb_bob", 0, 0), "key 'D': the plumb_bob model takes 4 or 5"),
        ((k, [0.1] * 4, "kannala", 0, 0), "key 'distortion_model': unknown lens model"),
        ((k, [], "", 640, 0), "key 'height': missing"),
        ((k[:2] + [5000.0] + k[3:], [], "", 640, 480), "principal point"),
    ]
    for fields, message in faults:
        with pytest.raises(CalibrationError, match=re.escape(message)) as error:
            intrinsics_from_camera_info("walk.bag /cam/camera_info", *fields)
        assert str(error.value).startswith("walk.bag /cam/camera_info: ")
