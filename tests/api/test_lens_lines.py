"""``--lens-from-lines``'s estimate (``gsrwt_cli/api/lens_lines.py``): k1 and the pose from
renders through OpenCV's own lens model (``cv2.projectPoints`` with k1,
:mod:`tests.helpers.lens_renders`), refusals where the lines cannot tell, and the York Urban
training photos (pinhole photos with true orientations), whose errors it must never grow.
"""

from __future__ import annotations

import math
import sys
import warnings

import cv2
import numpy as np
import pytest

from gsrwt_cli.api.estimate import estimate_pose
from gsrwt_cli.api.lens_lines import (
    MAX_K1_SIGMA,
    estimate_with_lens_from_lines,
    lens_doubt,
    lens_from_lines,
    undistort_k1,
)
from gsrwt_cli.geometry.camera import Intrinsics
from tests.helpers.estimate_scenes import angle_between
from tests.helpers.lens_renders import render_distorted_room
from tests.helpers.paths import ROOT
from tests.helpers.tables import read_table

#: The issue's figure: k1 within this of the truth (normalised, OpenCV's convention).
K1_TOLERANCE = 0.02
#: The pose with the lens: vertical and wall normal within this many degrees of the truth.
POSE_TOLERANCE_DEG = 0.5

YORK = ROOT.parent / "shared" / "data" / "york-urban-train"
needs_york = pytest.mark.skipif(not (YORK / "truth.csv").is_file(),
                                reason=f"no York Urban data at {YORK}")


def _pose_errors(estimate, shot) -> tuple[float, float]:
    assert estimate.world_from_camera is not None, estimate.error
    return (angle_between(estimate.world_from_camera[0], shot.vertical),
            angle_between(estimate.world_from_camera[2], shot.wall_normal))


def _camera(shot) -> Intrinsics:
    height, width = shot.image.shape[:2]
    return Intrinsics(shot.focal, shot.focal, shot.cx, shot.cy, width=width, height=height)


def test_undistort_k1_agrees_with_opencvs_inverse():
    rng = np.random.default_rng(3)
    pixels = rng.uniform([0, 0], [640, 480], size=(200, 2))
    for k1 in (-0.3, -0.1, 0.05, 0.1):
        ours = undistort_k1(pixels, (319.5, 239.5), 700.0, 650.0, k1)
        matrix = np.array([[700.0, 0, 319.5], [0, 650.0, 239.5], [0, 0, 1]])
        theirs = cv2.undistortPoints(
            pixels.reshape(-1, 1, 2), matrix, np.array([k1, 0, 0, 0, 0.0]), P=matrix,
            criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)
        ).reshape(-1, 2)
        assert np.abs(ours - theirs).max() < 1e-4


def test_undistort_k1_gives_nan_beyond_a_barrel_lens_fold():
    # k1 = -0.5 folds at r_d = 2 / (3 sqrt(1.5)) = 0.544: a pixel at r_d = 0.6 has no ray
    ideal = undistort_k1(np.array([[0.6 * 500 + 320, 240.0], [0.5 * 500 + 320, 240.0]]),
                         (320.0, 240.0), 500.0, 500.0, -0.5)
    assert np.isnan(ideal[0]).all() and np.isfinite(ideal[1]).all()


@pytest.mark.slow
@pytest.mark.parametrize("k1, pan, tilt, roll, focal, seed", [
    (-0.3, 15, -8, 3, 700, 0),
    (-0.2, -25, 10, -5, 650, 1),
    (-0.1, 5, 5, 0, 700, 2),
    (-0.1, -30, -12, 6, 760, 5),
    (0.1, -10, 6, 4, 700, 4),
])
def test_k1_and_pose_recovered_from_a_render_with_the_focal_length_given(
        k1, pan, tilt, roll, focal, seed):
    shot = render_distorted_room(pan, tilt, roll, k1=k1, focal=focal, seed=seed)
    estimate, found = estimate_with_lens_from_lines(shot.image, _camera(shot))
    assert found.taken, found.summary()
    assert abs(found.k1 - k1) < K1_TOLERANCE, found.summary()
    assert found.sigma <= MAX_K1_SIGMA
    assert max(_pose_errors(estimate, shot)) < POSE_TOLERANCE_DEG


@pytest.mark.slow
def test_k1_recovered_without_a_focal_length_converted_to_the_true_one():
    shot = render_distorted_room(15, -8, 3, k1=-0.3, focal=700, seed=0)
    estimate, found = estimate_with_lens_from_lines(shot.image, None)
    assert found.taken, found.summary()
    assert found.focal == estimate.focal
    assert abs(found.at_focal(700.0).k1 - (-0.3)) < K1_TOLERANCE, found.summary()
    assert max(_pose_errors(estimate, shot)) < POSE_TOLERANCE_DEG


@pytest.mark.slow
def test_the_lens_check_searches_k1_again_where_the_straightened_lines_put_the_focal_length():
    """A render through k1 -0.2 at 800 px (OpenCV's lens model), given no camera: the bent
    edges make the pinhole estimate 949 px, 3.1 degrees off, and k1 searched at 949 px
    comes out short (-0.17), its straightened pose turning under 2 degrees: it was written
    ``ok``. Searched again at the focal length the straightened lines give, k1 is near the lens's
    and the pose turns by more than 2 degrees: refused, the lens named."""
    shot = render_distorted_room(30, 5, 2, k1=-0.2, focal=800, seed=1)
    pinhole = estimate_pose(shot.image, None)
    assert pinhole.ok and max(_pose_errors(pinhole, shot)) > 3.0  # the bent pose, 3.1 off
    doubt = lens_doubt(shot.image, pinhole)
    assert doubt is not None and doubt.startswith("the straight edges bend"), doubt
    k1 = float(doubt.split("k1 ")[1].split()[0])
    assert abs(k1 - (-0.2)) < K1_TOLERANCE, doubt  # normalised near 800 px again


@pytest.mark.slow
@pytest.mark.parametrize("pan, tilt, roll, focal, seed", [
    (20, -10, 2, 700, 3), (-5, 3, -4, 600, 8), (35, 8, 0, 800, 9)])
def test_a_pinhole_render_keeps_its_pose(pan, tilt, roll, focal, seed):
    shot = render_distorted_room(pan, tilt, roll, k1=0.0, focal=focal, seed=seed)
    camera = _camera(shot)
    estimate, found = estimate_with_lens_from_lines(shot.image, camera)
    pinhole = estimate_pose(shot.image, camera)
    if not found.taken:  # then the very pinhole estimate
        assert estimate.pose == pinhole.pose
    else:
        assert abs(found.k1) < K1_TOLERANCE
        for mine, theirs in zip(_pose_errors(estimate, shot), _pose_errors(pinhole, shot)):
            assert abs(mine - theirs) < 0.1


def test_a_photo_without_straight_structure_is_refused_with_a_reason():
    rng = np.random.default_rng(0)
    noise = cv2.GaussianBlur(rng.normal(128, 60, (480, 640)).astype(np.float32), (0, 0), 6)
    image = np.clip(noise, 0, 255).astype(np.uint8)
    for _ in range(40):  # blobs and curves: edges, none of them straight for long
        centre = (int(rng.integers(0, 640)), int(rng.integers(0, 480)))
        cv2.circle(image, centre, int(rng.integers(10, 90)), int(rng.integers(0, 255)), 3)
    found = lens_from_lines(image, Intrinsics(600, 600, 319.5, 239.5, width=640, height=480))
    assert not found.taken
    assert found.lens() is None
    assert found.reason and ("segments" in found.reason or "pin k1" in found.reason)
    assert found.summary().startswith("refused: ")


@needs_york
@pytest.mark.slow
def test_york_photos_errors_never_grow_and_nearly_all_are_refused():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import bench_lens_lines

    from gsrwt_cli.imaging.images import read_image

    truth = read_table(YORK / "truth.csv")
    taken = 0
    for row in truth:
        image = read_image(YORK / "images" / row["image"])
        height, width = image.shape[:2]
        focal = float(row["focal_px"])
        camera = Intrinsics(focal, focal, float(row["cx"]), float(row["cy"]), width=width,
                            height=height)
        estimate, found = estimate_with_lens_from_lines(image, camera)
        pinhole = estimate_pose(image, camera)
        true = bench_lens_lines.york.true_directions(row)
        before = bench_lens_lines._errors(pinhole, true)
        after = bench_lens_lines._errors(estimate, true)
        if found.taken:
            taken += 1
            assert after.vertical <= before.vertical + 0.05, row["image"]
            assert after.wall <= before.wall + 0.05, row["image"]
        else:
            assert estimate.pose == pinhole.pose
    assert taken <= math.ceil(0.1 * len(truth))


def test_segments_all_beyond_the_lens_fold_are_refused_with_a_reason():
    """Found by fuzzing: segments whose every end point lies beyond the fold of the grid's
    strongest barrel k1 (none of any length left) made the frame search draw from NaN
    probabilities (an exception); now a reason, and no warning."""
    far = np.random.default_rng(5).uniform(-5000, 5000, (60, 4))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = lens_from_lines(np.zeros((480, 640), np.uint8),
                                Intrinsics(700, 700, 319.5, 239.5, width=640, height=480),
                                lines=far)
    assert not math.isfinite(found.k1) and found.reason
