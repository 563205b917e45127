"""Gaze control (Sec. 5.2.2): the wall point of a canonical pixel and the pan and tilt that
centre it, against the independent camera model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsrwt_cli import View
from gsrwt_cli.geometry.gaze import (
    GazeTargetError,
    fixation_point,
    gaze_at,
    pan_tilt_towards,
    wall_point_of_canonical_pixel,
)
from tests.helpers.camera import camera_axes

angles = st.floats(-70, 70)


@settings(max_examples=200, deadline=None)
@given(pan=angles, tilt=angles, focal=st.floats(100, 3000), distance=st.floats(0.5, 20),
       col=st.floats(-500, 1500), row=st.floats(-500, 1500))
def test_gaze_round_trip(pan, tilt, focal, distance, col, row):
    view = View(pan, tilt, focal, width=1024, height=768, distance=distance)
    wall = wall_point_of_canonical_pixel(view, col, row)
    new_pan, new_tilt = pan_tilt_towards(*wall, distance)
    # The new optical axis (independent model) meets the wall at the target...
    forward = camera_axes(new_pan, new_tilt)[2]
    hit_up, hit_right = distance * forward[:2] / forward[2]
    assert (hit_right, hit_up) == pytest.approx(wall, abs=1e-9 * (1 + np.abs(wall).max()))
    assert fixation_point(new_pan, new_tilt, distance) == pytest.approx(wall, rel=1e-9,
                                                                         abs=1e-9)
    # ...which is the target pixel of the original canonical view (the old fixation at the
    # principal point, one pixel per distance/focal wall units, upright), within 0.01 px.
    old_x, old_y = fixation_point(pan, tilt, distance)
    new_x, new_y = fixation_point(new_pan, new_tilt, distance)
    back = (view.cx + (new_x - old_x) * focal / distance,
            view.cy - (new_y - old_y) * focal / distance)
    assert back == pytest.approx((col, row), abs=0.01)


def test_a_target_the_view_cannot_place_is_a_typed_error_without_options():
    view = View(15, 30, 280)
    with pytest.raises(GazeTargetError) as pixel:
        gaze_at(view, pixel=(1.0, 2.0))
    with pytest.raises(GazeTargetError) as vector:
        gaze_at(view, vector=(1.0, 2.0))
    assert (pixel.value.target, pixel.value.missing) == ("pixel", ("cx", "cy"))
    assert (vector.value.target, vector.value.missing) == ("vector", ("distance",))
    assert "--" not in str(pixel.value) + str(vector.value)
    here = gaze_at(view)
    assert (here.pan_deg, here.tilt_deg) == pytest.approx((15, 30))
