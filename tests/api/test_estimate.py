"""The pose estimator (docs/CONVENTIONS.md, "What the estimator reports"): synthetic
segments with noise and outliers, renders of rooms and corridors through OpenCV's own camera,
the sample views, images that cannot tell."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gsrwt_cli.api.estimate import PoseEstimate, estimate_pose
from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.lens import Lens
from tests.helpers.estimate_scenes import (
    C,
    angle_between,
    random_shots,
    render_room,
    world_from_camera,
)
from tests.helpers.paths import SAMPLE_VIEWS as VIEWS
from tests.helpers.tables import read_table


def errors(estimate: PoseEstimate, truth: np.ndarray) -> tuple[float, float]:
    """Degrees between estimated and true vertical, and between the wall normals (spec 7)."""
    assert estimate.ok, estimate.error
    w = estimate.world_from_camera
    return angle_between(w[0], truth[0]), angle_between(w[2], truth[2])


def synthetic_lines(pan: float, tilt: float, roll: float, focal: float, seed: int,
                    noise_px: float = 0.3, outliers: float = 0.2, size=(640, 480),
                    distortion: np.ndarray | None = None, axes: tuple[int, ...] = (0, 1, 2)
                    ) -> np.ndarray:
    """Segments along the world axes ``axes`` in a box in front of the camera, projected by
    ``cv2.projectPoints`` (OpenCV frames: wall x = Y, y = -X (the vertical), z = Z), with
    end-point noise, plus ``outliers`` of random segments."""
    rng = np.random.default_rng(seed)
    w = world_from_camera(pan, tilt, roll)
    camera_from_wall = C.T @ w.T @ C
    rvec = cv2.Rodrigues(camera_from_wall)[0]
    matrix = np.array([[focal, 0, (size[0] - 1) / 2], [0, focal, (size[1] - 1) / 2], [0, 0, 1]])
    lines = []
    while len(lines) < 90:
        axis = axes[len(lines) % len(axes)]
        start_camera = np.array([rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(4, 12)])
        start_cv = camera_from_wall.T @ start_camera  # a point in front, in wall coordinates
        direction = np.zeros(3)
        direction[axis] = rng.uniform(0.5, 2.0)
        points = np.array([start_cv, start_cv + direction])
        if np.any((points @ camera_from_wall.T)[:, 2] < 0.5):
            continue
        pixels = cv2.projectPoints(points.reshape(-1, 1, 3), rvec, np.zeros(3), matrix,
                                   distortion)[0].reshape(-1, 2)
        if np.hypot(*(pixels[1] - pixels[0])) < 20 or np.any(np.abs(pixels) > 4000):
            continue
        lines.append(pixels.ravel() + rng.normal(0, noise_px, 4))
    for _ in range(int(outliers * len(lines))):
        start = rng.uniform([0, 0], size)
        angle = rng.uniform(0, math.pi)
        length = rng.uniform(20, 150)
        lines.append(np.r_[start, start + length * np.array([math.cos(angle), math.sin(angle)])])
    lines = np.array(lines)
    order = np.argsort(-np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1]))
    return lines[order]


BLANK = np.zeros((480, 640), np.uint8)


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(pan=st.floats(-40, 40), tilt=st.floats(-35, 35), roll=st.floats(-10, 10),
       focal=st.floats(350, 1200), seed=st.integers(0, 10_000))
def test_random_rotations_are_recovered_from_noisy_segments_with_outliers(
        pan, tilt, roll, focal, seed):
    lines = synthetic_lines(pan, tilt, roll, focal, seed)
    estimate = estimate_pose(BLANK, Intrinsics(focal, focal, width=640, height=480), lines=lines)
    vertical, normal = errors(estimate, world_from_camera(pan, tilt, roll))
    assert vertical < 1.0 and normal < 1.0  # 0.3 px of noise on segments of 20-150 px
    assert estimate.pose.tilt == pytest.approx(tilt, abs=1.0)
    assert estimate.pose.roll == pytest.approx(roll, abs=1.5)
    assert estimate.pose.pan == pytest.approx(pan, abs=1.5)
    assert estimate.directions == 3
    assert estimate.inliers >= 80  # the 90 true segments, not the 18 outliers
    assert 0.5 < estimate.confidence <= 1.0


@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(pan=st.floats(12, 40), sign=st.sampled_from([-1, 1]), tilt=st.floats(8, 30),
       tilt_sign=st.sampled_from([-1, 1]), roll=st.floats(-10, 10), focal=st.floats(350, 1200),
       seed=st.integers(0, 10_000))
def test_an_unknown_focal_length_is_found_from_two_orthogonal_vanishing_points(
        pan, sign, tilt, tilt_sign, roll, focal, seed):
    pan, tilt = pan * sign, tilt * tilt_sign
    lines = synthetic_lines(pan, tilt, roll, focal, seed)
    estimate = estimate_pose(BLANK, None, lines=lines)
    assert estimate.focal_estimated
    assert estimate.focal == pytest.approx(focal, rel=0.06)  # 0.3 px noise, 83-degree views too
    vertical, normal = errors(estimate, world_from_camera(pan, tilt, roll))
    assert vertical < 1.5 and normal < 1.5


def test_lens_distortion_is_removed_from_the_end_points():
    """Segments through a barrel lens (k1 = -0.3): with the lens given, the pose is as good
    as through a pinhole; ignoring it costs degrees (so this test can fail)."""
    distortion = np.array([-0.3, 0.08, 0.0, 0.0, 0.0])
    lens = Lens("plumb_bob", (("k1", -0.3), ("k2", 0.08)))
    truth = world_from_camera(25, -12, 6)
    worst_with, worst_without = 0.0, 0.0
    for seed in range(5):
        lines = synthetic_lines(25, -12, 6, 500, seed, noise_px=0.2, outliers=0.1,
                                distortion=distortion)
        with_lens = estimate_pose(BLANK, Intrinsics(500, 500, width=640, height=480, lens=lens),
                                  lines=lines)
        without = estimate_pose(BLANK, Intrinsics(500, 500, width=640, height=480), lines=lines)
        worst_with = max(worst_with, *errors(with_lens, truth))
        worst_without = max(worst_without, *errors(without, truth)) if without.ok else 90.0
    assert worst_with < 0.5
    assert worst_without > 1.0


def test_images_that_cannot_tell_give_an_error_and_no_pose():
    rng = np.random.default_rng(0)
    noise = rng.integers(0, 256, size=(480, 640), dtype=np.uint8)
    stripes = np.zeros((480, 640), np.uint8)
    stripes[:, ::40] = 255
    stripes = cv2.GaussianBlur(cv2.dilate(stripes, np.ones((1, 9), np.uint8)), (0, 0), 1.0)
    camera = Intrinsics(500, 500, width=640, height=480)
    for image in (BLANK, noise, np.full((480, 640, 3), 128, np.uint8)):
        estimate = estimate_pose(image, camera)
        assert estimate.pose is None and not estimate.ok
        assert estimate.error.startswith("too few straight segments")
    estimate = estimate_pose(stripes, camera)
    assert estimate.pose is None
    assert estimate.error.startswith("only 1 of 3 directions found, ")
    assert estimate.error.endswith(f"{estimate.segments} segments (each needs 5 that meet in "
                                   "it and in no other); give the pose, or guides "
                                   "(--verticals)")


def test_a_camera_of_another_size_is_refused():
    with pytest.raises(ValueError, match="640x480 pixels but the image is 320x240"):
        estimate_pose(np.zeros((240, 320), np.uint8), Intrinsics(500, 500, width=640, height=480))


def _render_errors(shots, known_focal: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The errors of the images estimated (those that cannot tell the focal length left out)."""
    vertical, normal = [], []
    for shot in shots:
        camera = Intrinsics(shot.focal, shot.focal, shot.cx, shot.cy) if known_focal else None
        estimate = estimate_pose(shot.image, camera)
        if not known_focal and estimate.error and "focal length" in estimate.error:
            continue
        a, b = errors(estimate, shot.world_from_camera)
        vertical.append(a)
        normal.append(b)
    return np.array(vertical), np.array(normal)


def test_a_room_seen_at_40_degrees_and_one_seen_nearly_frontal():
    for pan, tilt, roll in ((40, -15, 8), (-40, 12, -10), (2, 5, 1), (-1, -20, 0)):
        shot = render_room(pan, tilt, roll, focal=520, seed=abs(pan) + 7)
        estimate = estimate_pose(shot.image, Intrinsics(520, 520, shot.cx, shot.cy))
        vertical, normal = errors(estimate, shot.world_from_camera)
        assert vertical < 0.6 and normal < 0.7  # the back wall, not a side wall
        assert estimate.pose.tilt == pytest.approx(tilt, abs=0.7)
        assert estimate.pose.roll == pytest.approx(roll, abs=0.7)


@pytest.mark.slow
def test_renders_meet_the_accuracy_goals():
    """40 rooms and corridors (noise, blur, JPEG; pans to 40, tilts of both signs, rolls to
    10) against the issue's goals: medians 0.6 and 0.7 degrees, 90th percentiles 1.5, all
    under 4, and the wall chosen right every time (a wrong wall is ~90 degrees off)."""
    vertical, normal = _render_errors(random_shots(40, seed=11))
    assert np.median(vertical) <= 0.6 and np.median(normal) <= 0.7
    assert np.percentile(vertical, 90) <= 1.5 and np.percentile(normal, 90) <= 1.5
    assert vertical.max() < 4 and normal.max() < 4


@pytest.mark.slow
def test_renders_with_an_unknown_focal_length():
    shots = [shot for shot in random_shots(20, seed=5) if abs(shot.pan) > 12 and abs(shot.tilt) > 6]
    vertical, normal = _render_errors(shots, known_focal=False)
    assert len(vertical) >= 0.8 * len(shots)
    assert np.median(vertical) <= 1.0 and np.median(normal) <= 1.0
    assert vertical.max() < 4 and normal.max() < 4


def sample_views() -> list[dict[str, str]]:
    return read_table(VIEWS / "views.csv")


@pytest.mark.parametrize("row", sample_views(), ids=lambda row: row["image"])
def test_the_sample_views_known_poses(row):
    image = cv2.imread(str(VIEWS / row["image"]))
    focal = float(row["focal"])
    estimate = estimate_pose(image, Intrinsics(focal, focal, float(row["cx"]), float(row["cy"])))
    truth = world_from_camera(float(row["pan"]), float(row["tilt"]), 0.0)
    vertical, normal = errors(estimate, truth)
    assert vertical < 0.3
    if float(row["pan"]) == 45:  # either wall is as frontal: the choice is a coin toss
        normal = min(normal, angle_between(estimate.world_from_camera[2], truth[1]))
    assert normal < 0.3
    assert estimate.confidence > 0.5


def test_the_nearest_of_three_directions_is_numpys_argmin_and_min():
    """The estimator's element-wise nearest direction (the first among equals, as
    ``np.argmin``), on distances with ties, zeros and infinities."""
    from gsrwt_cli.api.estimate import _least_of_three, _nearest_of_three

    rng = np.random.default_rng(1)
    distance = rng.integers(0, 4, size=(400, 3)).astype(float)  # many ties
    distance[::7, 1] = np.inf
    labels, nearest = _nearest_of_three(distance)
    assert np.array_equal(labels, np.argmin(distance, axis=1))
    assert np.array_equal(nearest, distance.min(axis=1))
    stacked = rng.random((5, 40, 3))
    assert np.array_equal(_least_of_three(stacked), stacked.min(axis=2))
