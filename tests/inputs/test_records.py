"""One view's raw values checked into a ``View`` (``inputs/records.py``): every way a record
may give the pose (pan and tilt, the GS-RWT's delta and a, solvePnP's rvec and tvec, a
quaternion), the focal length (pixels, millimetres and a sensor, a calibration file) and the
lens, checked against relations that hold independently of the module (the thesis's Table
5.1, OpenCV's ``Rodrigues``, the half-angle quaternion, OpenCV's own reading of a
calibration file), and how values are merged and refused."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli.inputs.records import RecordError, merge_values, view_from_values
from tests.helpers.paths import DATA

WHERE = "views.csv line 2"


def pose_of(view) -> tuple[float, float, float]:
    return view.pan, view.tilt, view.roll


def test_the_gsrwt_parameters_give_the_pose_back():
    """Table 5.1's view (pan 15, tilt 30, f 280) from its delta, a and gamma; a gamma more
    than a degree from what delta and a imply is refused, as is a pose given twice."""
    thesis = {"delta": "28.186785432", "a": "427.462304659", "focal": "280"}
    view = view_from_values({**thesis, "gamma": "-24.146"}, WHERE)
    assert (view.pan, view.tilt) == pytest.approx((15, 30), abs=1e-6)
    assert view_from_values({**thesis, "gamma": "-25"}, WHERE).pan == pytest.approx(15)
    with pytest.raises(RecordError) as off:
        view_from_values({**thesis, "gamma": "-26"}, WHERE)
    assert off.value.field == "gamma" and "imply gamma = -24.15" in str(off.value)
    with pytest.raises(RecordError, match="give pan and tilt, or delta and a, not both"):
        view_from_values({**thesis, "pan": 15, "tilt": 30}, WHERE)
    with pytest.raises(RecordError, match="missing field 'focal'"):
        view_from_values({"delta": 28.2, "a": 427.5}, WHERE)


def test_an_rvec_and_its_quaternion_are_the_same_pose():
    """A rotation by angle t about axis n as solvePnP's rvec ``t n`` and as the quaternion
    ``(cos t/2, sin t/2 n)``: the same pan, tilt and roll."""
    axis = np.array([0.3, -0.8, 0.2])
    axis /= np.linalg.norm(axis)
    angle = 0.4
    rvec = dict(zip(("rvec_x", "rvec_y", "rvec_z"), angle * axis))
    quaternion = dict(zip(("qw", "qx", "qy", "qz"),
                          (math.cos(angle / 2), *(math.sin(angle / 2) * axis))))
    from_rvec = view_from_values({**rvec, "focal": 500}, WHERE)
    from_quaternion = view_from_values({**quaternion, "focal": 500}, WHERE)
    assert pose_of(from_rvec) == pytest.approx(pose_of(from_quaternion), abs=1e-9)
    assert from_rvec.roll != 0  # a turn about a tilted axis: all three angles
    with pytest.raises(RecordError, match="give one pose, not rvec and quaternion"):
        view_from_values({**rvec, **quaternion, "focal": 500}, WHERE)
    with pytest.raises(RecordError) as partial:
        view_from_values({"rvec_x": 0.1, "rvec_y": 0.2, "focal": 500}, WHERE)
    assert partial.value.field == "rvec_z"


def test_a_tvec_gives_the_distance_along_the_walls_normal():
    """solvePnP's tvec is the wall's origin in the camera; the wall's distance is along its
    normal (the third column of ``Rodrigues(rvec)``), not the tvec's length or its z."""
    rvec, tvec = np.array([0.1, -0.5, 0.05]), np.array([0.8, -0.3, 4.0])
    values = {**dict(zip(("rvec_x", "rvec_y", "rvec_z"), rvec)),
              **dict(zip(("tvec_x", "tvec_y", "tvec_z"), tvec)), "focal": 500}
    normal = cv2.Rodrigues(rvec)[0][:, 2]
    view = view_from_values(values, WHERE)
    assert view.distance == pytest.approx(abs(normal @ tvec), rel=1e-12)
    assert abs(view.distance - tvec[2]) > 0.1
    assert view_from_values({**values, "distance": 2.5}, WHERE).distance == 2.5  # given wins
    with pytest.raises(RecordError) as alone:
        view_from_values({"pan": 1, "tilt": 2, "focal": 500,
                          **dict(zip(("tvec_x", "tvec_y", "tvec_z"), tvec))}, WHERE)
    assert alone.value.field == "tvec_x"


def test_a_focal_length_in_millimetres_needs_the_sensor_and_the_image_size():
    values = {"pan": 10, "tilt": 5, "focal_mm": 4.73, "sensor_width_mm": 6.17, "width": 400,
              "height": 300}
    square = view_from_values(values, WHERE).intrinsics
    assert square.fx == square.fy == pytest.approx(4.73 * 400 / 6.17)
    both = view_from_values({**values, "sensor_height_mm": 4.63}, WHERE).intrinsics
    assert (both.fx, both.fy) == pytest.approx((4.73 * 400 / 6.17, 4.73 * 300 / 4.63))
    for changed, field in (({"sensor_width_mm": None}, "sensor_width_mm"),
                           ({"width": None}, "width"), ({"focal": 300}, "focal_mm"),
                           ({"sensor_width_mm": 0}, "sensor_width_mm")):
        with pytest.raises(RecordError) as refused:
            view_from_values({**values, **changed}, WHERE)
        assert refused.value.field == field, refused.value


def test_a_calibration_file_gives_the_intrinsics_and_the_records_fields_override_them():
    path = DATA / "right_camera.yml"
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)  # OpenCV's own reading
    matrix = storage.getNode("camera_matrix").mat()
    coefficients = storage.getNode("distortion_coefficients").mat().ravel()
    storage.release()
    view = view_from_values({"camera": str(path), "pan": 10, "tilt": 5}, WHERE)
    intrinsics = view.intrinsics
    assert (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy) == pytest.approx(
        (matrix[0, 0], matrix[1, 1], matrix[0, 2], matrix[1, 2]), rel=1e-12)
    assert (intrinsics.width, intrinsics.height) == (640, 480)
    np.testing.assert_allclose(intrinsics.lens.opencv_coefficients(), coefficients, rtol=1e-12)
    own = view_from_values({"camera": str(path), "pan": 10, "tilt": 5, "focal": 500,
                            "cx": 300, "k1": 0.0}, WHERE).intrinsics
    assert (own.fx, own.fy, own.cx, own.cy) == pytest.approx((500, 500, 300, matrix[1, 2]))
    assert own.lens is None  # the record's lens (k1 = 0: a pinhole) over the file's
    named = view_from_values({"camera": str(path), "pan": 10, "tilt": 5,
                              "distortion_model": "plumb_bob"}, WHERE)
    assert named.intrinsics.lens is None  # a model named without coefficients: none
    with pytest.raises(RecordError) as missing:
        view_from_values({"camera": str(DATA / "no_such_camera.yml"), "pan": 1, "tilt": 1},
                         WHERE)
    assert missing.value.field == "camera" and "no_such_camera.yml" in str(missing.value)


@pytest.mark.parametrize(("lens", "model"), [
    ({"k1": -0.1}, "plumb_bob"), ({"k1": -0.1, "p2": 0.001}, "plumb_bob"),
    ({"k4": 0.1}, "rational_polynomial"), ({"s1": 0.01}, "rational_polynomial"),
    ({"distortion_model": "fisheye", "k1": 0.05}, "equidistant"),
    ({"distortion_model": "radtan", "k2": 0.01}, "plumb_bob"),
])
def test_the_lens_model_is_the_one_named_or_the_least_that_has_the_coefficients(lens, model):
    view = view_from_values({"pan": 1, "tilt": 2, "focal": 500, **lens}, WHERE)
    assert view.intrinsics.lens.model == model


@pytest.mark.parametrize(("raw", "value"), [
    ("15", 15.0), (" 15.5 ", 15.5), ("-1e1", -10.0), (".5", 0.5), (np.float32(2.5), 2.5),
    (np.int64(7), 7.0), (3, 3.0),
])
def test_numbers_are_plain_decimals_or_real_numbers(raw, value):
    assert view_from_values({"pan": raw, "tilt": 0, "focal": 300}, WHERE).pan == value


@pytest.mark.parametrize(("raw", "words"), [
    ("1_5", "not a number"), ("0x10", "not a number"), ("15°", "not a number"),
    ("\u0661\u0665", "not a number"), (True, "not a number"), ("nan", "must be finite"),
    ("-Infinity", "must be finite"), ("1e400", "out of range"), (10**400, "out of range"),
    (float("inf"), "must be finite"),
])
def test_anything_else_is_an_error_naming_place_field_and_value(raw, words):
    with pytest.raises(RecordError) as refused:
        view_from_values({"pan": raw, "tilt": 0, "focal": 300}, WHERE)
    assert (refused.value.where, refused.value.field) == (WHERE, "pan")
    assert str(refused.value).startswith(f"{WHERE}, field 'pan': ") and words in str(
        refused.value)


def test_missing_pose_or_focal_length_names_what_is_missing():
    for values, missing in (({"tilt": 1, "focal": 300}, "pan"),
                            ({"pan": 1, "focal": 300}, "tilt"),
                            ({"pan": 1, "tilt": 1}, "focal")):
        with pytest.raises(RecordError) as refused:
            view_from_values(values, WHERE)
        assert str(refused.value) == f"{WHERE}: missing field '{missing}'"
        assert refused.value.field is None
    # Empty cells are not values.
    with pytest.raises(RecordError, match="missing field 'pan'"):
        view_from_values({"pan": "", "tilt": 1, "focal": 300}, WHERE)


def test_merged_values_take_the_records_own_then_the_fallbacks_in_order():
    """The record's values over the fallbacks, the earlier fallback over the later; a record
    that gives the pose one way drops the fallbacks' pose given the other way."""
    options, defaults = {"focal": 300, "pan": 1, "tilt": 2}, {"focal": 999, "width": 640}
    assert merge_values({"tilt": 5}, options, defaults) == {"focal": 300, "pan": 1,
                                                            "tilt": 5, "width": 640}
    assert merge_values({"delta": 28.2, "a": 427.5}, options) == {"focal": 300,
                                                                   "delta": 28.2, "a": 427.5}
    assert merge_values({"pan": 3}, {"delta": 28.2, "a": 427.5, "gamma": -24}) == {"pan": 3}
    own = {"pan": 4, "tilt": 4}
    assert merge_values(own) == own and merge_values(own) is not own
