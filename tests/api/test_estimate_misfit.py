"""The frame's misfit (:func:`gsrwt_cli.api.estimate.frame_misfit`), the confidence's measure
of how far the vertical's and the wall normal's own segments point from the orthogonal frame:
exact on constructed interpretation planes, and on segments projected by OpenCV's
``cv2.projectPoints`` it stays small through the right camera and grows, taking the confidence
below the refusal bar, when the estimator is given a focal length 30 % off (the scene's edges
are then not orthogonal in the camera it assumes)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli.api.estimate import (
    DEFAULT_MIN_CONFIDENCE,
    UNSEEN_NORMAL_LOGIT,
    confidence_features,
    confidence_of,
    estimate_pose,
    frame_misfit,
)
from gsrwt_cli.geometry.camera import Intrinsics
from tests.api.test_estimate import BLANK, errors, synthetic_lines
from tests.helpers.estimate_scenes import world_from_camera
from tests.helpers.paths import DATA


def planes_of(direction: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Unit normals of ``count`` random planes through ``direction`` (segments meeting in it)."""
    normals = np.cross(direction, rng.normal(size=(count, 3)))
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


@pytest.mark.parametrize("lean", [0.0, 0.7, 2.0, 4.0])
def test_the_misfit_is_the_angle_between_an_axis_and_where_its_own_segments_meet(lean):
    rng = np.random.default_rng(3)
    frame = np.eye(3)
    angle = math.radians(lean)  # the vertical segments meet 'lean' degrees off the frame's X
    leaning = np.array([math.cos(angle), math.sin(angle), 0.0])
    normals = np.vstack([planes_of(leaning, 40, rng), planes_of(frame[:, 1], 40, rng),
                         planes_of(frame[:, 2], 40, rng)])
    labels = np.repeat([0, 1, 2], 40)
    half = rng.uniform(20, 80, len(labels))
    assert frame_misfit(normals, half, frame, labels, (0, 2)) == pytest.approx(
        lean, abs=1e-6)
    # the wall's horizontal (axis 1) is not weighed; too few segments cannot tell a direction
    assert frame_misfit(normals, half, frame, labels, (1, 2)) == pytest.approx(
        0.0, abs=1e-6)
    few = labels.copy()
    few[4:40] = -1
    assert frame_misfit(normals, half, frame, few, (0, 2)) == pytest.approx(
        0.0, abs=1e-6)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_wrong_focal_length_shows_in_the_misfit_and_lowers_the_confidence(seed):
    pan, tilt, roll, focal = 25.0, 15.0, 3.0, 600.0
    lines = synthetic_lines(pan, tilt, roll, focal, seed)
    right = estimate_pose(BLANK, Intrinsics(focal, focal, width=640, height=480), lines=lines)
    wrong = estimate_pose(BLANK, Intrinsics(1.3 * focal, 1.3 * focal, width=640, height=480),
                          lines=lines)
    assert right.misfit < 0.5 and right.confidence > 0.9
    assert max(errors(right, world_from_camera(pan, tilt, roll))) < 1.0
    assert wrong.misfit > 3 * max(right.misfit, 0.3)
    assert wrong.confidence < DEFAULT_MIN_CONFIDENCE
    features = confidence_features(wrong)
    assert features[2] == wrong.misfit
    assert confidence_of(*features, wrong.upright, wrong.normal_seen) == pytest.approx(
        wrong.confidence)


def test_the_confidence_is_the_rotations_whichever_wall_is_reported():
    """A facade seen at 59 degrees (``tests/data/facade``): ``wall="dominant"`` reports the
    facade, ``frontal`` the building's end; the misfit weighs the frontal wall's normal in
    both (the facade's own horizontal edges), so the confidence is the same (the end wall's
    few edges, taken alone, point 7.5 degrees off: weighed, they would refuse the facade)."""
    image = cv2.imread(str(DATA / "facade" / "building.jpg"), cv2.IMREAD_COLOR)
    frontal = estimate_pose(image, None, wall="frontal")
    dominant = estimate_pose(image, None, wall="dominant")
    assert abs(frontal.pose.pan - dominant.pose.pan) > 80  # the two walls, 90 degrees apart
    assert dominant.misfit == frontal.misfit < 1.0
    assert dominant.confidence == frontal.confidence > DEFAULT_MIN_CONFIDENCE


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_wall_seen_frontally_is_judged_by_its_horizontals(seed):
    """A wall whose edges all run along it (verticals and horizontals through
    ``cv2.projectPoints``, no edge receding from the camera) pins its pan by the slight
    convergence of its horizontals alone. Turned 4 degrees in the image from square with the
    verticals (a wall out of true, a camera model a little off), they take the pan 8 to 17
    degrees off while the vertical's own segments still agree with the frame: the frontal
    wall's normal has no segments to weigh, so the misfit weighs the wall's horizontal
    instead, which points 7 to 15 degrees from the frame, and the estimate is refused. The
    square wall keeps its confidence."""
    camera = Intrinsics(600.0, 600.0, width=640, height=480)
    verticals = synthetic_lines(25.0, 12.0, 3.0, 600.0, seed, axes=(1,), outliers=0.0)
    square = synthetic_lines(25.0, 12.0, 3.0, 600.0, seed + 50, axes=(0,), outliers=0.0)[:20]
    turned = synthetic_lines(25.0, 12.0, 7.0, 600.0, seed + 50, axes=(0,), outliers=0.0)[:20]
    right = estimate_pose(BLANK, camera, lines=np.vstack([verticals, square]))
    assert max(errors(right, world_from_camera(25.0, 12.0, 3.0))) < 0.5
    assert right.misfit < 0.5 and right.confidence > 0.9
    wrong = estimate_pose(BLANK, camera, lines=np.vstack([verticals, turned]))
    assert abs(wrong.pose.pan - 25.0) > 5.0  # the pan the horizontals give is far off
    assert wrong.misfit > 5.0 and wrong.confidence < 0.1
    assert not right.normal_seen and not wrong.normal_seen  # no edge recedes


def test_a_wall_seen_frontally_is_less_sure_than_its_measures_say():
    """The confidence of a wall whose normal has no edges of its own is its measures' logit
    lowered by ``UNSEEN_NORMAL_LOGIT`` (such views made from the York Urban photos were within
    2 degrees less often than the measures said); a room whose edges recede keeps its
    measures' confidence."""
    camera = Intrinsics(600.0, 600.0, width=640, height=480)
    wall = synthetic_lines(20.0, 10.0, 2.0, 600.0, 3, axes=(0, 1), outliers=0.0)
    room = synthetic_lines(20.0, 10.0, 2.0, 600.0, 3)
    frontal = estimate_pose(BLANK, camera, lines=wall)
    receding = estimate_pose(BLANK, camera, lines=room)
    assert not frontal.normal_seen and receding.normal_seen
    for estimate in (frontal, receding):
        features = confidence_features(estimate)
        measured = confidence_of(*features, estimate.upright)
        logit = math.log(measured / (estimate.upright - measured))
        expected = estimate.upright / (1.0 + math.exp(-(
            logit + (0.0 if estimate.normal_seen else UNSEEN_NORMAL_LOGIT))))
        assert estimate.confidence == pytest.approx(expected, rel=1e-9)
    assert UNSEEN_NORMAL_LOGIT < 0 and frontal.confidence < confidence_of(
        *confidence_features(frontal), frontal.upright)
