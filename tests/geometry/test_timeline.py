"""Poses over time (``geometry/timeline.py``): slerp against rotations known in closed form
and against scipy's own slerp, and a pose log's moments: sorted samples, duplicates, gaps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation, Slerp

from gsrwt_cli.geometry.rotations import pose_from_rotation, rotation_from_pose
from gsrwt_cli.geometry.timeline import (
    DuplicateTimeError,
    PoseGapError,
    PoseSample,
    Timeline,
    slerp,
)


def about(axis: list[float], degrees: float) -> np.ndarray:
    """The turn by ``degrees`` about ``axis`` (Rodrigues' formula, written out here)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    angle = math.radians(degrees)
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def test_halfway_between_two_turns_about_one_axis_is_the_turn_halfway() -> None:
    start = rotation_from_pose(10, 20, 5)
    axis = [0.3, -0.5, 0.8]
    end = about(axis, 40) @ start
    np.testing.assert_allclose(slerp(start, end, 0.5), about(axis, 20) @ start, atol=1e-12)
    np.testing.assert_allclose(slerp(start, end, 0.25), about(axis, 10) @ start, atol=1e-12)
    np.testing.assert_allclose(slerp(start, end, 0.0), start, atol=1e-12)
    np.testing.assert_allclose(slerp(start, end, 1.0), end, atol=1e-12)


def test_slerp_takes_the_short_way_round() -> None:
    """Between turns of +170 and -170 degrees about one axis the short arc crosses 180."""
    axis = [0.0, 0.0, 1.0]
    np.testing.assert_allclose(slerp(about(axis, 170), about(axis, -170), 0.5),
                               about(axis, 180), atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.tuples(*[st.floats(-80, 80)] * 2, st.floats(-170, 170)),
       st.tuples(*[st.floats(-80, 80)] * 2, st.floats(-170, 170)),
       st.floats(0, 1))
def test_slerp_agrees_with_scipy(a: tuple[float, float, float], b: tuple[float, float, float],
                                 fraction: float) -> None:
    keys = Rotation.from_euler("XYZ", [a, b], degrees=True)
    expected = Slerp([0.0, 1.0], keys)([fraction]).as_matrix()[0]
    got = slerp(rotation_from_pose(*a), rotation_from_pose(*b), fraction)
    np.testing.assert_allclose(got, expected, atol=1e-9)


def sample(time: float, pan: float, tilt: float, **numbers: float) -> PoseSample:
    return PoseSample(time, rotation_from_pose(pan, tilt), numbers)


def test_a_moment_halfway_between_samples_given_out_of_order() -> None:
    timeline = Timeline([sample(2.0, 30, 10, focal=600), sample(0.0, 0, 10, focal=400),
                         sample(1.0, 10, 10, focal=500)], max_gap=0.6)
    at = timeline.at(1.5)
    expected = Slerp([1.0, 2.0], Rotation.from_euler("XYZ", [[10, 10, 0], [30, 10, 0]],
                                                       degrees=True))([1.5]).as_matrix()[0]
    np.testing.assert_allclose(at.rotation, expected, atol=1e-12)
    assert (at.before, at.after) == (1, 2) and at.fraction == pytest.approx(0.5)
    assert at.numbers["focal"] == pytest.approx(550)
    assert pose_from_rotation(timeline.at(0.0).rotation).pan == pytest.approx(0, abs=1e-9)


def test_a_moment_beyond_the_ends_holds_the_end_within_the_gap() -> None:
    timeline = Timeline([sample(1.0, 10, 5), sample(2.0, 20, 5)], max_gap=0.5)
    assert pose_from_rotation(timeline.at(0.6).rotation).pan == pytest.approx(10)
    assert pose_from_rotation(timeline.at(2.5).rotation).pan == pytest.approx(20)
    with pytest.raises(PoseGapError, match="no pose within 0.5 s of time 0.4 s"):
        timeline.at(0.4)
    with pytest.raises(PoseGapError):
        timeline.at(2.51)


def test_a_moment_in_a_hole_of_the_log_is_a_gap() -> None:
    timeline = Timeline([sample(0.0, 0, 5), sample(3.0, 30, 5)], max_gap=1.0)
    timeline.at(0.9)
    timeline.at(2.1)
    with pytest.raises(PoseGapError, match="nearest sample is 1.5 s away"):
        timeline.at(1.5)


def test_two_samples_at_one_time_are_refused_naming_both() -> None:
    with pytest.raises(DuplicateTimeError) as raised:
        Timeline([sample(0.0, 0, 5), sample(1.0, 1, 5), sample(0.0, 2, 5)], max_gap=1)
    assert (raised.value.first, raised.value.second) == (0, 2)


def test_a_number_some_samples_lack_is_interpolated_between_those_that_give_it() -> None:
    timeline = Timeline([sample(0.0, 0, 5, cx=100), sample(1.0, 0, 5),
                         sample(2.0, 0, 5, cx=200)], max_gap=1)
    assert timeline.at(1.5).numbers["cx"] == pytest.approx(175)
