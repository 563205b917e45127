"""An approximate focal length (an EXIF one: ``estimate_pose(..., focal_spread=...)``) refined
by the segments where they pin it: segments projected by OpenCV's ``cv2.projectPoints`` through
a camera whose focal length the estimator is told 8 % wrong."""

from __future__ import annotations

import math

import pytest

from gsrwt_cli.api.estimate import EXIF_FOCAL_SPREAD, estimate_pose
from gsrwt_cli.geometry.camera import Intrinsics
from tests.api.test_estimate import BLANK, errors, synthetic_lines
from tests.helpers.estimate_scenes import world_from_camera

TRUE_FOCAL = 700.0


def told(focal: float) -> Intrinsics:
    return Intrinsics(focal, focal, width=640, height=480)


@pytest.mark.parametrize("off", [0.92, 1.08])
def test_an_oblique_view_refines_a_focal_length_told_8_percent_off(off):
    """Pan 30, tilt 12, four scenes: three finite vanishing points pin the focal length.
    Taken as EXIF's (5 % spread), the segments pull it most of the way back (measured within
    0.7 to 1.3 %: the prior holds it back a little; asserted 2 %) and every pose is within
    0.3 degrees (measured 0.2 at worst); the estimate says the focal length was estimated and
    how uncertain it is. Taken as exact, one of the eight scene-and-error pairs is 2.0
    degrees off (the 0.92 one of seed 2)."""
    pan, tilt, roll = 30.0, 12.0, 2.0
    truth = world_from_camera(pan, tilt, roll)
    worst_exact = 0.0
    for seed in range(4):
        lines = synthetic_lines(pan, tilt, roll, TRUE_FOCAL, seed)
        exact = estimate_pose(BLANK, told(off * TRUE_FOCAL), lines=lines)
        refined = estimate_pose(BLANK, told(off * TRUE_FOCAL), lines=lines,
                                focal_spread=EXIF_FOCAL_SPREAD)
        assert exact.focal == off * TRUE_FOCAL and not exact.focal_estimated
        assert refined.focal_estimated and abs(refined.focal / TRUE_FOCAL - 1) < 0.02
        assert 0 < refined.focal_uncertainty.sigma < EXIF_FOCAL_SPREAD
        assert max(errors(refined, truth)) < 0.3
        worst_exact = max(worst_exact, *errors(exact, truth))
    if off < 1:
        assert worst_exact > 1.0  # the error the refinement removes


def test_a_frontal_view_keeps_the_focal_length_it_was_told():
    """Nearly frontal (pan 1, tilt 1): the vanishing points are far away and the segments
    hardly tell the focal length, so the one told stands (within 1 %) and the pose, which
    hardly depends on it, is right."""
    lines = synthetic_lines(1.0, 1.0, 0.5, TRUE_FOCAL, 3)
    refined = estimate_pose(BLANK, told(1.08 * TRUE_FOCAL), lines=lines,
                            focal_spread=EXIF_FOCAL_SPREAD)
    assert abs(refined.focal / (1.08 * TRUE_FOCAL) - 1) < 0.01
    assert max(errors(refined, world_from_camera(1.0, 1.0, 0.5))) < 0.5
    assert math.isfinite(refined.focal_uncertainty.sigma)
