"""Poses as other tools give them (docs/POSES.md): pan/tilt/roll, OpenCV's rvec/tvec, quaternions.

The references are independent of the module: OpenCV's own ``Rodrigues`` and ``projectPoints``,
the camera built from words in ``tests/helpers/camera.py``, a Hamilton product written
here, and hand-worked numbers.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from gsrwt_cli.geometry.gsrwt import camera_from_world
from gsrwt_cli.geometry.rotations import (
    QUATERNION_NORM_SQUARED_TOLERANCE,
    THESIS_FROM_OPENCV,
    Pose,
    PoseError,
    cross_matrix,
    cross_rows,
    distance_from_tvec,
    opencv_from_world_from_camera,
    pose_from_quaternion,
    pose_from_rotation,
    pose_from_rvec,
    quaternion_from_pose,
    quaternion_from_rotation,
    rotation_from_pose,
    rotation_from_quaternion,
    rotation_from_rvec,
    rvec_from_pose,
    rvec_from_rotation,
    world_from_camera_from_opencv,
    world_from_camera_from_ros_body,
)
from tests.helpers.camera import camera_axes, project_wall_points, rodrigues
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

pans = st.floats(-89, 89)
tilts = st.floats(-89, 89)
rolls = st.floats(-180, 180)
components = st.floats(-1, 1)

C = THESIS_FROM_OPENCV
OPENCV_SAMPLES = Path("/usr/share/doc/opencv-doc/examples/data")


def angle_difference(a: float, b: float) -> float:
    """``a - b`` in degrees, wrapped into [-180, 180)."""
    return (a - b + 180.0) % 360.0 - 180.0


def assert_same_pose(got: Pose, pan: float, tilt: float, roll: float, tol: float = 1e-8):
    assert got.pan == pytest.approx(pan, abs=tol)
    assert got.tilt == pytest.approx(tilt, abs=tol)
    assert abs(angle_difference(got.roll, roll)) < tol


def camera_matrix(fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def project(wall_points: np.ndarray, rvec, tvec, k: np.ndarray) -> np.ndarray:
    """OpenCV's own projection of OpenCV wall points (x right, y down, z = 0): ``(N, 2)`` pixels."""
    pixels, _ = cv2.projectPoints(np.asarray(wall_points, dtype=np.float64),
                                  np.asarray(rvec, dtype=np.float64).reshape(3, 1),
                                  np.asarray(tvec, dtype=np.float64).reshape(3, 1), k, None)
    return pixels.reshape(-1, 2)


def tvec_for_centre(rvec, centre_in_wall: np.ndarray) -> np.ndarray:
    """``tvec = -R c``: the translation of a camera whose centre is ``c`` in the wall frame."""
    return -cv2.Rodrigues(np.asarray(rvec, dtype=np.float64))[0] @ centre_in_wall


def hamilton(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The Hamilton product ``p q`` of scalar-first quaternions."""
    pw, pv, qw, qv = p[0], p[1:], q[0], q[1:]
    return np.concatenate([[pw * qw - pv @ qv], pw * qv + qw * pv + np.cross(pv, qv)])


def rotate_by_quaternion(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q v q*`` for a unit quaternion ``q``."""
    conjugate = q * np.array([1.0, -1.0, -1.0, -1.0])
    return hamilton(hamilton(q, np.concatenate([[0.0], v])), conjugate)[1:]


def camera_axes_with_roll(pan: float, tilt: float, roll: float) -> np.ndarray:
    """Rows: the camera's up, right, forward axes in the world, from the words of spec 6.

    :func:`camera_axes` for pan and tilt, then a turn about the camera's own forward
    axis whose sense makes the top lean to the right (up gains a +right component) for roll > 0.
    """
    up, right, forward = camera_axes(pan, tilt)
    sense = 1.0 if (rodrigues(forward, 0.1) @ up) @ right > 0 else -1.0
    turn = rodrigues(forward, sense * math.radians(roll))
    return np.stack([turn @ up, turn @ right, forward])


# --------------------------------------------------------------------------------------------
# pan, tilt, roll <-> world_from_camera
# --------------------------------------------------------------------------------------------


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts)
def test_roll_zero_is_exactly_the_thesis_rotation(pan, tilt):
    """roll = 0 reproduces Eq. 3.8 bit for bit: world_from_camera is camera_from_world's
    transpose (rows of camera_from_world = the camera's axes = columns of world_from_camera).
    Bit for bit on every CPU, though the two compute differently: each entry of the matrix
    products is one product of the same two sines or cosines, its other terms exact zeros,
    and Rz(0) is the identity, so no rounding (fused or not) can tell them apart."""
    assert np.array_equal(rotation_from_pose(pan, tilt, 0.0), camera_from_world(pan, tilt).T)
    assert np.array_equal(rotation_from_pose(pan, tilt), camera_from_world(pan, tilt).T)


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts)
def test_roll_zero_matches_the_camera_built_from_words(pan, tilt):
    """Columns of world_from_camera are camera_axes' rows (up, right, forward)."""
    np.testing.assert_allclose(rotation_from_pose(pan, tilt, 0.0).T, camera_axes(pan, tilt),
                               atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_roll_matches_the_camera_built_from_words(pan, tilt, roll):
    """Roll turns the camera about its own optical axis after pan and tilt, top to the right."""
    np.testing.assert_allclose(rotation_from_pose(pan, tilt, roll).T,
                               camera_axes_with_roll(pan, tilt, roll), atol=1e-12)


def test_roll_leans_the_top_to_the_right():
    """Spec 6: roll > 0, the camera's up axis (first column) gains a +Y (right) component."""
    up = rotation_from_pose(0.0, 0.0, 10.0)[:, 0]
    assert up[1] > 0 and up[0] > 0
    np.testing.assert_allclose(up, [math.cos(math.radians(10)), math.sin(math.radians(10)), 0])


@settings(max_examples=500, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_pose_rotation_round_trip(pan, tilt, roll):
    assert_same_pose(pose_from_rotation(rotation_from_pose(pan, tilt, roll)), pan, tilt, roll)


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_wall_in_front_is_cos_pan_cos_tilt_whatever_the_roll(pan, tilt, roll):
    """W[2,2] = cos(pan) cos(tilt) = R[2,2] of OpenCV's camera_from_wall: roll leaves it alone."""
    w = rotation_from_pose(pan, tilt, roll)
    expected = math.cos(math.radians(pan)) * math.cos(math.radians(tilt))
    assert w[2, 2] == pytest.approx(expected, abs=1e-15)
    assert opencv_from_world_from_camera(w)[2, 2] == pytest.approx(expected, abs=1e-15)
    assert expected > 0


@settings(max_examples=500, deadline=None)
@given(qw=components, qx=components, qy=components, qz=components)
def test_any_rotation_decomposes_exactly_when_the_wall_is_in_front(qw, qx, qy, qz):
    """A random rotation: decomposed and rebuilt when W[2,2] > 0, refused when W[2,2] <= 0."""
    q = np.array([qw, qx, qy, qz])
    assume(np.linalg.norm(q) > 0.1)
    q /= np.linalg.norm(q)
    w = rotation_from_quaternion(*q)
    if w[2, 2] > 1e-9:
        pan, tilt, roll = pose_from_rotation(w)
        assert abs(pan) < 90 and abs(tilt) < 90 and abs(roll) <= 180
        # Near edge-on (W[2,2] -> 0) the angles are ill-conditioned: atan2 of two numbers of
        # size W[2,2] loses about eps / W[2,2] of the rebuilt matrix, and no more.
        tolerance = 1e-12 + 1e-15 / w[2, 2]
        np.testing.assert_allclose(rotation_from_pose(pan, tilt, roll), w, atol=tolerance)
    elif w[2, 2] <= 0:
        with pytest.raises(PoseError, match="not in front"):
            pose_from_rotation(w)


@pytest.mark.parametrize(
    ("pan", "tilt", "roll"),
    [(120, 0, 0), (180, 0, 0), (0, 135, 10), (-100, 20, -30), (60, 150, 90), (0, 180, 0)],
)
def test_a_wall_behind_the_camera_is_refused(pan, tilt, roll):
    w = rotation_from_pose(pan, tilt, roll)
    assert w[2, 2] < 0
    with pytest.raises(PoseError, match="not in front of the camera.*away from the wall"):
        pose_from_rotation(w)
    with pytest.raises(PoseError, match="not in front"):
        pose_from_rvec(rvec_from_pose(pan, tilt, roll))
    with pytest.raises(PoseError, match="not in front"):
        pose_from_quaternion(*quaternion_from_pose(pan, tilt, roll))


@pytest.mark.parametrize(("pan", "tilt"), [(90, 0), (-90, 0), (0, 90), (0, -90), (90, 45)])
def test_an_edge_on_wall_is_refused(pan, tilt):
    """cos(90°) is 6e-17 in floating point, not 0: the angles' own range catches it."""
    with pytest.raises(PoseError, match="not in front|edge-on"):
        pose_from_rotation(rotation_from_pose(pan, tilt, 0.0))
    exactly_edge_on = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # forward along +Y
    with pytest.raises(PoseError, match="along the wall"):
        pose_from_rotation(exactly_edge_on)


@pytest.mark.parametrize(
    ("matrix", "reason"),
    [
        (2 * np.eye(3), "not orthonormal"),
        (np.diag([1.0, 1.0, -1.0]), "reflection"),
        (np.diag([-1.0, 1.0, 1.0]), "reflection"),
        (np.array([[1.0, 0.01, 0], [0, 1, 0], [0, 0, 1]]), "not orthonormal"),
        (np.eye(2), "shape"),
        (np.full((3, 3), np.nan), "finite"),
    ],
)
def test_a_matrix_that_is_no_rotation_is_refused(matrix, reason):
    with pytest.raises(PoseError, match=reason):
        pose_from_rotation(matrix)
    assert issubclass(PoseError, ValueError)


def test_a_rotation_printed_to_seven_digits_is_accepted():
    w = np.round(rotation_from_pose(20, -10, 5), 7)
    assert_same_pose(pose_from_rotation(w), 20, -10, 5, tol=1e-4)


def test_angles_come_back_as_plain_floats_without_negative_zero():
    pose = pose_from_rotation(np.eye(3))
    assert tuple(pose) == (0.0, 0.0, 0.0)
    assert all(type(a) is float and math.copysign(1, a) == 1 for a in pose)


# --------------------------------------------------------------------------------------------
# Rodrigues and quaternions against OpenCV
# --------------------------------------------------------------------------------------------


@settings(max_examples=500, deadline=None)
@given(x=st.floats(-4, 4), y=st.floats(-4, 4), z=st.floats(-4, 4))
def test_rotation_from_rvec_is_cv2_rodrigues(x, y, z):
    rvec = np.array([x, y, z])
    np.testing.assert_allclose(rotation_from_rvec(rvec), cv2.Rodrigues(rvec)[0], atol=1e-12)


@settings(max_examples=500, deadline=None)
@given(x=st.floats(-4, 4), y=st.floats(-4, 4), z=st.floats(-4, 4))
def test_rvec_from_rotation_is_cv2_rodrigues(x, y, z):
    """Both ways: ours is the same rotation, and the same vector where OpenCV's is exact.

    OpenCV returns 0 for turns below about 1e-5 rad (it tests sin theta < 1e-5); ours keeps
    them, so there the reference is the vector the matrix was made from."""
    rvec = np.array([x, y, z])
    rotation = cv2.Rodrigues(rvec)[0]
    ours, theirs = rvec_from_rotation(rotation), cv2.Rodrigues(rotation)[0].ravel()
    angle = np.linalg.norm(rvec)
    assert np.linalg.norm(ours) <= math.pi + 1e-12
    np.testing.assert_allclose(cv2.Rodrigues(ours)[0], rotation, atol=1e-12)
    if angle < 1e-4:
        np.testing.assert_allclose(ours, rvec, atol=1e-15)
    elif np.linalg.norm(theirs) < math.pi - 1e-6:  # at a half turn, k and -k are the same
        np.testing.assert_allclose(ours, theirs, atol=1e-9)


@pytest.mark.parametrize(
    "rvec",
    [[0, 0, 0], [1e-12, 0, 0], [0, -3e-9, 2e-9], [math.pi, 0, 0], [0, math.pi, 0],
     [0, 0, -math.pi], [math.pi / math.sqrt(2), -math.pi / math.sqrt(2), 0],
     [1.7, -1.2, 2.1], [0, math.pi - 1e-7, 0]],
)
def test_rodrigues_at_the_awkward_angles(rvec):
    """Zero, tiny and half turns, where arccos/sin formulas lose digits or divide by 0."""
    rvec = np.array(rvec, dtype=float)
    np.testing.assert_allclose(rotation_from_rvec(rvec), cv2.Rodrigues(rvec)[0], atol=1e-15)
    back = rvec_from_rotation(rotation_from_rvec(rvec))
    np.testing.assert_allclose(rotation_from_rvec(back), rotation_from_rvec(rvec), atol=1e-15)
    if np.linalg.norm(rvec) < math.pi - 1e-3:
        np.testing.assert_allclose(back, rvec, atol=1e-15)


def test_numpy_scalars_are_numbers():
    assert rotation_from_pose(np.float32(10), np.int64(5), np.float64(-3)) == pytest.approx(
        rotation_from_pose(10.0, 5.0, -3.0), abs=1e-15)
    assert tuple(pose_from_quaternion(*np.array(quaternion_from_pose(10, 5, -3), np.float32))) == (
        pytest.approx((10, 5, -3), abs=1e-4))
    for bad in (math.nan, math.inf, "ten", None):
        with pytest.raises(PoseError, match="pan"):
            rotation_from_pose(bad, 0, 0)


def test_rvec_shapes_opencv_returns_are_accepted():
    column = np.array([[0.1], [0.2], [-0.3]])
    assert pose_from_rvec(column) == pose_from_rvec(column.ravel()) == pose_from_rvec(
        column.T) == pose_from_rvec([0.1, 0.2, -0.3])
    for bad in ([1, 2], [[1, 2, 3], [4, 5, 6]], [0, np.nan, 0], [0, np.inf, 0], "abc"):
        with pytest.raises(PoseError):
            pose_from_rvec(bad)


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_quaternion_turns_vectors_as_cv2_rodrigues_does(pan, tilt, roll):
    """q (Hamilton, scalar first) and rvec are the same rotation, checked through q v q*."""
    q = np.array(quaternion_from_pose(pan, tilt, roll))
    rotation = cv2.Rodrigues(rvec_from_pose(pan, tilt, roll))[0]
    assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1, abs=1e-15)
    for v in np.eye(3):
        np.testing.assert_allclose(rotate_by_quaternion(q, v), rotation @ v, atol=1e-12)
    np.testing.assert_allclose(rotation_from_quaternion(*q), rotation, atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(x=st.floats(-3, 3), y=st.floats(-3, 3), z=st.floats(-3, 3))
def test_quaternion_is_the_half_angle_of_the_rvec(x, y, z):
    """q = (cos(theta/2), sin(theta/2) k) for OpenCV's rvec = theta k, up to the sign of q."""
    rvec = np.array([x, y, z])
    theta = np.linalg.norm(rvec)
    assume(theta > 1e-6)
    expected = np.concatenate([[math.cos(theta / 2)], math.sin(theta / 2) * rvec / theta])
    got = np.array(quaternion_from_rotation(cv2.Rodrigues(rvec)[0]))
    sign = 1.0 if expected @ got >= 0 else -1.0
    np.testing.assert_allclose(got, sign * expected, atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_rvec_and_quaternion_round_trips(pan, tilt, roll):
    assert_same_pose(pose_from_rvec(rvec_from_pose(pan, tilt, roll)), pan, tilt, roll)
    assert_same_pose(pose_from_quaternion(*quaternion_from_pose(pan, tilt, roll)),
                     pan, tilt, roll)


@settings(max_examples=300, deadline=None)
@given(x=st.floats(-1.5, 1.5), y=st.floats(-1.5, 1.5), z=st.floats(-3, 3))
def test_rvec_to_pose_and_back_is_the_same_rotation(x, y, z):
    rvec = np.array([x, y, z])
    rotation = cv2.Rodrigues(rvec)[0]
    assume(rotation[2, 2] > 1e-6)
    back = rvec_from_pose(*pose_from_rvec(rvec))
    np.testing.assert_allclose(cv2.Rodrigues(back)[0], rotation, atol=1e-11)


@settings(max_examples=200, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls)
def test_q_and_minus_q_are_the_same_pose(pan, tilt, roll):
    q = np.array(quaternion_from_pose(pan, tilt, roll))
    assert tuple(pose_from_quaternion(*q)) == pytest.approx(tuple(pose_from_quaternion(*-q)),
                                                        abs=1e-10)


def test_the_canonical_quaternion_of_a_half_turn():
    """qw = 0: of q and -q the one whose first non-zero component is positive comes back."""
    assert quaternion_from_rotation(np.diag([1.0, -1.0, -1.0])) == (0.0, 1.0, 0.0, 0.0)
    assert quaternion_from_rotation(np.diag([-1.0, -1.0, 1.0])) == (0.0, 0.0, 0.0, 1.0)


def test_quaternions_near_unit_length_are_normalized_others_refused():
    q = np.array(quaternion_from_pose(20, -15, 40))
    expected = pose_from_quaternion(*q)
    for scale in (0.996, 1.004, math.sqrt(1 + 0.99 * QUATERNION_NORM_SQUARED_TOLERANCE)):
        assert tuple(pose_from_quaternion(*(scale * q))) == pytest.approx(tuple(expected),
                                                                          abs=1e-10)
    rounded = np.round(q, 3)
    assert_same_pose(pose_from_quaternion(*rounded), *expected, tol=0.2)
    for scale in (0.9, 1.1, 2.0, math.sqrt(1 + 1.01 * QUATERNION_NORM_SQUARED_TOLERANCE)):
        with pytest.raises(PoseError, match="not a unit quaternion"):
            pose_from_quaternion(*(scale * q))
    with pytest.raises(PoseError, match="not a unit quaternion"):
        pose_from_quaternion(0, 0, 0, 0)
    with pytest.raises(PoseError, match="finite"):
        pose_from_quaternion(1, 0, math.nan, 0)


# --------------------------------------------------------------------------------------------
# Hand-worked examples
# --------------------------------------------------------------------------------------------


def test_a_camera_facing_the_wall_squarely():
    """rvec = 0, q = 1: the wall frame's axes are the camera's, pan = tilt = roll = 0."""
    assert tuple(pose_from_rvec([0.0, 0.0, 0.0])) == (0.0, 0.0, 0.0)
    assert tuple(pose_from_quaternion(1.0, 0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(rvec_from_pose(0, 0, 0), [0.0, 0.0, 0.0])
    assert quaternion_from_pose(0, 0, 0) == (1.0, 0.0, 0.0, 0.0)
    assert distance_from_tvec([0, 0, 0], [0.3, -0.2, 2.5]) == 2.5


def test_a_camera_turned_left_by_30_degrees():
    """Pan 30 (left, about the vertical): world_from_camera = Rx(30°), R = C^T Rx(30°)^T C, a
    turn by -30° about thesis up = OpenCV -y, i.e. by +30° about +y: rvec = (0, pi/6, 0),
    R = [[cos 30, 0, sin 30], [0, 1, 0], [-sin 30, 0, cos 30]], q = (cos 15°, 0, sin 15°, 0).

    At 2 units from the wall with the optical axis through the wall origin, the camera centre
    is c = (2 tan 30°, 0, -2) in the wall frame and tvec = -R c = (0, 0, 2 / cos 30°): tvec_z
    is the slant depth 2.309, the distance along the wall's normal is 2.
    """
    c30, s30 = math.cos(math.radians(30)), math.sin(math.radians(30))
    rvec = np.array([0.0, math.pi / 6, 0.0])
    hand_r = np.array([[c30, 0.0, s30], [0.0, 1.0, 0.0], [-s30, 0.0, c30]])
    np.testing.assert_allclose(cv2.Rodrigues(rvec)[0], hand_r, atol=1e-15)
    np.testing.assert_allclose(rvec_from_pose(30, 0, 0), rvec, atol=1e-15)
    assert_same_pose(pose_from_rvec(rvec), 30, 0, 0, tol=1e-12)
    hand_q = (math.cos(math.radians(15)), 0.0, math.sin(math.radians(15)), 0.0)
    np.testing.assert_allclose(quaternion_from_pose(30, 0, 0), hand_q, atol=1e-15)
    assert_same_pose(pose_from_quaternion(*hand_q), 30, 0, 0, tol=1e-12)
    # The wall's normal leans to the camera's right when the camera has turned left.
    np.testing.assert_allclose(hand_r @ [0, 0, 1], [0.5, 0, c30], atol=1e-15)

    centre = np.array([2 * math.tan(math.radians(30)), 0.0, -2.0])
    tvec = tvec_for_centre(rvec, centre)
    np.testing.assert_allclose(tvec, [0.0, 0.0, 2 / c30], atol=1e-15)
    assert distance_from_tvec(rvec, tvec) == pytest.approx(2.0, abs=1e-15)
    k = camera_matrix(500, 500, 320, 240)
    origin, foot = project(np.array([[0.0, 0, 0], [centre[0], 0, 0]]), rvec, tvec, k)
    np.testing.assert_allclose(origin, [320, 240], atol=1e-9)  # the optical axis meets it
    assert foot[0] > 320 and foot[1] == pytest.approx(240)  # the wall straight ahead: right


def test_tilt_and_roll_rvecs_by_hand():
    """Tilt b: a turn by -b about OpenCV x (thesis Y = x); roll r: by -r about z (= Z)."""
    np.testing.assert_allclose(rvec_from_pose(0, 30, 0), [-math.pi / 6, 0, 0], atol=1e-15)
    np.testing.assert_allclose(rvec_from_pose(0, 0, 30), [0, 0, -math.pi / 6], atol=1e-15)
    np.testing.assert_allclose(rvec_from_pose(0, 0, -30), [0, 0, math.pi / 6], atol=1e-15)
    # Tilted up, the wall's normal is below the optical axis (+y in OpenCV's camera).
    assert cv2.Rodrigues(rvec_from_pose(0, 30, 0))[0][1, 2] > 0


def test_the_opencv_and_thesis_frames():
    """C maps OpenCV (x right, y down, z forward) to the thesis (X up, Y right, Z forward)."""
    np.testing.assert_array_equal(C @ [0, -1, 0], [1, 0, 0])  # OpenCV up (-y) is thesis X
    np.testing.assert_array_equal(C @ [1, 0, 0], [0, 1, 0])  # OpenCV right (x) is thesis Y
    np.testing.assert_array_equal(C @ [0, 0, 1], [0, 0, 1])
    r = cv2.Rodrigues(np.array([0.2, -0.4, 0.9]))[0]
    np.testing.assert_allclose(world_from_camera_from_opencv(r), C @ r.T @ C.T, atol=1e-15)
    np.testing.assert_allclose(opencv_from_world_from_camera(C @ r.T @ C.T), r, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(pan=pans, tilt=tilts, roll=st.floats(-170, 170))
def test_ros_body_axes_yaw_pitch_roll_are_pan_minus_tilt_roll(pan, tilt, roll):
    """A ROS body (x forward, y left, z up) turned by yaw, pitch, roll (SciPy's intrinsic
    ZYX, as ROS's RPY) in a world whose x faces the wall is pan = yaw, tilt = -pitch, roll;
    its axes are those of the camera built from words."""
    from scipy.spatial.transform import Rotation

    world_from_body = Rotation.from_euler("ZYX", [pan, -tilt, roll], degrees=True).as_matrix()
    w = world_from_camera_from_ros_body(world_from_body)
    up, right, forward = camera_axes(pan, tilt, roll)
    np.testing.assert_allclose(w, np.column_stack([up, right, forward]), atol=1e-12)
    pose = pose_from_rotation(w)
    assert (pose.pan, pose.tilt, pose.roll) == pytest.approx((pan, tilt, roll), abs=1e-9)


# --------------------------------------------------------------------------------------------
# Projections through OpenCV's own camera
# --------------------------------------------------------------------------------------------


@settings(max_examples=200, deadline=None)
@given(pan=pans, tilt=tilts, distance=st.floats(0.5, 20), focal=st.floats(100, 3000))
def test_cv2_projection_of_rvec_matches_the_camera_built_from_words(pan, tilt, distance, focal):
    """The rvec's OpenCV camera sees the wall as the camera built from words does (roll 0).

    Thesis wall point (X up, Y right, Z = distance) = OpenCV wall point (Y, -X, 0) with the
    wall origin where the frontal optical axis meets it, the camera centre at (0, 0, -distance).
    """
    assume(math.cos(math.radians(pan)) * math.cos(math.radians(tilt)) > 0.2)
    wall_xy = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-0.7, 0.4], [0.3, -0.9]]) * (
        0.1 * distance)
    expected, depth = project_wall_points(wall_xy, distance, pan, tilt, focal, 319.5, 239.5)
    assume(np.all(depth > 0.05 * distance))
    rvec = rvec_from_pose(pan, tilt, 0.0)
    tvec = tvec_for_centre(rvec, np.array([0.0, 0.0, -distance]))
    opencv_wall = np.column_stack([wall_xy[:, 1], -wall_xy[:, 0], np.zeros(len(wall_xy))])
    got = project(opencv_wall, rvec, tvec, camera_matrix(focal, focal, 319.5, 239.5))
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-6)
    assert distance_from_tvec(rvec, tvec) == pytest.approx(distance, rel=1e-12)


@pytest.mark.parametrize("roll", [5.0, 30.0, 90.0, -20.0, 150.0, -120.0])
def test_with_roll_the_scene_turns_counter_clockwise(roll):
    """Spec 6: roll > 0, the scene appears turned counter-clockwise. A wall point straight up
    from the principal point's wall point (wall X, OpenCV -y) appears at ``roll`` degrees
    counter-clockwise from straight up on screen (rows grow downward)."""
    rvec = rvec_from_pose(0.0, 0.0, roll)
    tvec = tvec_for_centre(rvec, np.array([0.0, 0.0, -3.0]))
    centre, up = project(np.array([[0.0, 0, 0], [0.0, -1.0, 0]]), rvec, tvec,
                         camera_matrix(400, 400, 320, 240))
    np.testing.assert_allclose(centre, [320, 240], atol=1e-9)
    d_col, d_row = up - centre
    counter_clockwise_from_up = math.degrees(math.atan2(-d_col, -d_row))
    assert abs(angle_difference(counter_clockwise_from_up, roll)) < 1e-9
    if 0 < roll < 180:
        assert d_col < 0  # leaning to the left of straight up


@settings(max_examples=200, deadline=None)
@given(pan=st.floats(-60, 60), tilt=st.floats(-60, 60), roll=rolls)
def test_roll_turns_the_whole_image_about_the_principal_point(pan, tilt, roll):
    """At any pan and tilt, the rolled view is the unrolled one turned counter-clockwise by
    roll about the principal point (cv2.projectPoints of both rvecs, same camera centre)."""
    k = camera_matrix(600, 600, 320, 240)
    forward_in_wall = cv2.Rodrigues(rvec_from_pose(pan, tilt, 0.0))[0][2, :]
    centre = -5.0 * forward_in_wall / forward_in_wall[2]  # optical axis through the origin
    wall = np.array([[0.0, 0, 0], [1, 0, 0], [0, -1, 0], [0.5, 0.8, 0], [-0.9, 0.3, 0]])
    unrolled, rolled = (
        project(wall, rvec_from_pose(pan, tilt, r), tvec_for_centre(rvec_from_pose(pan, tilt, r),
                                                                    centre), k) - [320, 240]
        for r in (0.0, roll)
    )
    c, s = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    # Counter-clockwise on screen, rows down: (dc, dr) -> (dc c + dr s, -dc s + dr c).
    turned = np.column_stack([unrolled[:, 0] * c + unrolled[:, 1] * s,
                              -unrolled[:, 0] * s + unrolled[:, 1] * c])
    np.testing.assert_allclose(rolled, turned, atol=1e-7)


@pytest.mark.parametrize(("pan", "tilt", "roll"), [(20, -10, 15), (-35, 25, -160), (0, 0, 90)])
def test_the_rectifying_rotation_for_opencv_is_the_transposed_rvec_rotation(pan, tilt, roll):
    """For cv2.initUndistortRectifyMap the rotation from the camera to the frontal view is
    wall_from_camera = R^T (the frontal camera's axes are the OpenCV wall's): its map sends
    each output pixel to where cv2.projectPoints puts the same wall point."""
    k = np.array([[500.0, 1.5, 330.0], [0.0, 520.0, 250.0], [0.0, 0.0, 1.0]])
    distance, f = 4.0, math.sqrt(500.0 * 520.0)
    k_out = camera_matrix(f, f, 200.0, 150.0)
    rvec = rvec_from_pose(pan, tilt, roll)
    rotation = cv2.Rodrigues(rvec)[0]
    tvec = tvec_for_centre(rvec, np.array([0.0, 0.0, -distance]))
    map_x, map_y = cv2.initUndistortRectifyMap(k, None, rotation.T, k_out, (400, 300),
                                               cv2.CV_32FC1)
    cols, rows = np.meshgrid(np.arange(150, 260, 20), np.arange(90, 220, 20))
    cols, rows = cols.ravel(), rows.ravel()
    wall = np.column_stack([(cols - 200.0) * distance / f, (rows - 150.0) * distance / f,
                            np.zeros(len(cols))])
    in_camera = wall @ rotation.T + tvec
    assert np.all(in_camera[:, 2] > 0)
    expected = project(wall, rvec, tvec, k)
    got = np.column_stack([map_x[rows, cols], map_y[rows, cols]])
    np.testing.assert_allclose(got, expected, atol=2e-3)


# --------------------------------------------------------------------------------------------
# Distance from tvec
# --------------------------------------------------------------------------------------------


@settings(max_examples=300, deadline=None)
@given(pan=pans, tilt=tilts, roll=rolls, x=st.floats(-10, 10), y=st.floats(-10, 10),
       distance=st.floats(0.01, 100))
def test_distance_is_the_camera_centres_depth_in_front_of_the_wall(pan, tilt, roll, x, y,
                                                                    distance):
    rvec = rvec_from_pose(pan, tilt, roll)
    tvec = tvec_for_centre(rvec, np.array([x, y, -distance]))
    assert distance_from_tvec(rvec, tvec) == pytest.approx(distance, rel=1e-9, abs=1e-9)
    assert distance_from_tvec(rvec.reshape(3, 1), tvec.reshape(3, 1)) == pytest.approx(
        distance, rel=1e-9, abs=1e-9)


def test_a_camera_behind_the_wall_plane_is_refused():
    rvec = rvec_from_pose(10, 5, 0)
    with pytest.raises(PoseError, match="not in front of the wall"):
        distance_from_tvec(rvec, tvec_for_centre(rvec, np.array([0.1, 0.2, 2.0])))
    with pytest.raises(PoseError, match="not in front of the wall"):
        distance_from_tvec([0, 0, 0], [1.0, 2.0, 0.0])  # the camera on the wall's plane
    with pytest.raises(PoseError, match="tvec"):
        distance_from_tvec(rvec, [0, 0])


# --------------------------------------------------------------------------------------------
# Real photos: OpenCV's right-camera chessboards
# --------------------------------------------------------------------------------------------


def chessboard_photos() -> list[Path]:
    for folder in (DATA, OPENCV_SAMPLES):
        photos = sorted(folder.glob("right[0-9][0-9].jpg"))
        if photos:
            return photos
    return []


def undistorted_rays(pixels: np.ndarray, k: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """OpenCV camera rays ``(x, y, 1)`` of distorted pixels, iterated to convergence."""
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4
        normalized = cv2.undistortPointsIter(pixels, k, dist, None, None, criteria)
    else:  # OpenCV 5: the criteria moved into undistortPoints
        normalized = cv2.undistortPoints(pixels, k, dist, criteria=criteria)
    normalized = normalized.reshape(-1, 2)
    return np.column_stack([normalized, np.ones(len(normalized))])


def frontal_residual(rays_cv: np.ndarray, pose: Pose, distance: float, f: float,
                     wall: np.ndarray) -> tuple[np.ndarray, float]:
    """View camera rays through the thesis's frontal camera (the world frame, f pixels) and
    compare with the wall points at ``f / distance`` pixels per unit, no rotation allowed.

    Returns each point's distance from the best-placed model (px) and the angle of the wall's
    x axis in the frontal view (degrees; 0 is along the columns).
    """
    rays_world = (rotation_from_pose(*pose) @ C @ rays_cv.T).T
    frontal = np.column_stack([f * rays_world[:, 1] / rays_world[:, 2],  # col: Y right
                               -f * rays_world[:, 0] / rays_world[:, 2]])  # row: -X up
    model = wall[:, :2] * (f / distance)
    residual = np.linalg.norm(frontal - model - (frontal - model).mean(axis=0), axis=1)
    design = np.column_stack([wall[:, 0], wall[:, 1], np.ones(len(wall))])
    along_x = np.linalg.lstsq(design, frontal, rcond=None)[0][0]  # (d col, d row) per unit x
    return residual, math.degrees(math.atan2(along_x[1], along_x[0]))


@pytest.mark.skipif(not chessboard_photos(),
                    reason="no right01..14.jpg in tests/data or opencv-doc's examples")
def test_real_chessboards_come_out_square_upright_and_at_frontal_scale():
    """Calibrate on the real photos, convert each board's solvePnP rvec/tvec to pan/tilt/roll
    and distance, and view the board through the thesis's frontal camera: a square grid at
    f/distance pixels per square, its x axis along the columns, its y axis along the rows.

    The board's corners as OpenCV projects them (with the calibrated distortion) come out so
    to 1e-4 px, which checks the conversions on real poses; the detected corners to 0.6 px RMS
    (1.5 px at worst: the frontal view enlarges the far side of the most oblique board).
    The distance is checked against a plane fitted to the board's corners in the camera.
    """
    board = (9, 6)
    wall = np.zeros((board[0] * board[1], 3), np.float32)
    wall[:, :2] = np.mgrid[0:board[0], 0:board[1]].T.reshape(-1, 2)
    found, corners, size = [], [], None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 1e-3)
    for photo in chessboard_photos():
        gray = cv2.imread(str(photo), cv2.IMREAD_GRAYSCALE)
        size = gray.shape[::-1]
        ok, points = cv2.findChessboardCorners(gray, board)
        if ok:
            # (7, 7): the usual (11, 11) window straddles the foreshortened boards' squares.
            corners.append(cv2.cornerSubPix(gray, points, (7, 7), (-1, -1), criteria))
            found.append(wall)
    assert len(found) >= 10
    _, k, dist, rvecs, tvecs = cv2.calibrateCamera(found, corners, size, None, None)
    f = math.sqrt(k[0, 0] * k[1, 1])
    wall64 = wall.astype(np.float64)
    for points, rvec, tvec in zip(corners, rvecs, tvecs):
        pose = pose_from_rvec(rvec)
        distance = distance_from_tvec(rvec, tvec)
        rotation = cv2.Rodrigues(rvec)[0]
        np.testing.assert_allclose(cv2.Rodrigues(rvec_from_pose(*pose))[0], rotation,
                                   atol=1e-12)
        assert rotation[2, 2] > 0 and 5 < distance < 20

        in_camera = (rotation @ wall64.T + tvec).T
        mean = in_camera.mean(axis=0)
        normal = np.linalg.svd(in_camera - mean)[2][2]
        assert abs(normal @ mean) == pytest.approx(distance, rel=1e-9)

        projected, _ = cv2.projectPoints(wall64, rvec, tvec, k, dist)
        residual, x_axis_deg = frontal_residual(undistorted_rays(projected, k, dist), pose,
                                                distance, f, wall64)
        assert residual.max() < 1e-4 and abs(x_axis_deg) < 1e-5

        residual, x_axis_deg = frontal_residual(undistorted_rays(points, k, dist), pose,
                                                distance, f, wall64)
        rms = math.sqrt(float(np.mean(residual**2)))
        assert rms < 0.6 and residual.max() < 1.5 and abs(x_axis_deg) < 0.5, (pose, rms)


@pytest.mark.skipif(not (DATA / "right_poses.csv").exists(), reason="no tests/data/right_poses.csv")
def test_recorded_real_poses_convert_both_ways():
    """The rvec (and tvec) columns of tests/data/right_poses.csv, from real solvePnP runs."""
    rows = read_table(DATA / "right_poses.csv")
    if not rows or not {"rvec_x", "rvec_y", "rvec_z"} <= rows[0].keys():
        pytest.skip("right_poses.csv has no rvec_x, rvec_y, rvec_z columns")
    for row in rows:
        rvec = np.array([float(row[f"rvec_{axis}"]) for axis in "xyz"])
        pan, tilt, roll = pose_from_rvec(rvec)
        np.testing.assert_allclose(cv2.Rodrigues(rvec_from_pose(pan, tilt, roll))[0],
                                   cv2.Rodrigues(rvec)[0], atol=1e-9)
        for name, value in (("pan", pan), ("tilt", tilt), ("roll", roll)):
            if row.get(name):
                assert abs(angle_difference(float(row[name]), value)) < 1e-4, (row, name)
        if all(row.get(f"tvec_{axis}") for axis in "xyz"):
            tvec = np.array([float(row[f"tvec_{axis}"]) for axis in "xyz"])
            distance = distance_from_tvec(rvec, tvec)
            if row.get("distance"):
                assert float(row["distance"]) == pytest.approx(distance, rel=1e-4)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=6, max_size=6))
def test_cross_products_written_out_are_numpys(values):
    """``cross_rows`` and ``cross_matrix`` (single and batched) against numpy's ``np.cross``,
    within rounding: the estimator's fast paths compute the same products."""
    vectors = np.array(values).reshape(2, 3)
    rows = np.random.default_rng(0).normal(size=(5, 3)) * 3.0
    assert np.allclose(cross_rows(vectors[0], vectors[1]), np.cross(vectors[0], vectors[1]),
                       atol=1e-9)
    assert np.allclose(cross_rows(rows, vectors[1]), np.cross(rows, vectors[1]), atol=1e-9)
    assert np.allclose(cross_matrix(vectors[0]) @ vectors[1], np.cross(vectors[0], vectors[1]),
                       atol=1e-9)
    batched = cross_matrix(rows)
    assert batched.shape == (5, 3, 3)
    assert np.allclose(batched @ vectors[1], np.cross(rows, vectors[1]), atol=1e-9)
    assert np.allclose(batched, -batched.transpose(0, 2, 1))
