"""The geometry core against the thesis's tables and the algebra the thesis relies on."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from gsrwt_cli.geometry.camera import View, ViewError
from gsrwt_cli.geometry.framing import output_from_input
from gsrwt_cli.geometry.gsrwt import (
    camera_from_world,
    gsrwt_inverse,
    gsrwt_matrix,
    gsrwt_parameters,
    homogeneous_w,
    map_lines_to_destination,
    map_lines_to_source,
    map_points,
    map_points_backward,
    pan_tilt_from_gsrwt,
    rotation_matrix,
    rwt_matrix,
    srwt_inverse,
    srwt_matrix,
)
from tests.helpers.camera import camera_axes, frontal_pixels, project_wall_points
from tests.helpers.thesis import FIG_5_2, TABLE_5_1, TABLE_5_2

angles = st.floats(min_value=-80, max_value=80, allow_nan=False)
focals = st.floats(min_value=100, max_value=3000)


@pytest.mark.parametrize(("pan", "tilt", "delta", "vp_yx", "a", "gamma"), TABLE_5_1)
def test_table_5_1(pan, tilt, delta, vp_yx, a, gamma):
    p = gsrwt_parameters(pan, tilt, 280)
    assert p.delta_deg == pytest.approx(delta, abs=1)
    assert p.shift == pytest.approx(a, abs=1)
    assert p.gamma_deg == pytest.approx(gamma, abs=1)
    x, y = p.vanishing_point
    assert (y, x) == pytest.approx(vp_yx, abs=2)


def test_fig_5_2_over_decompressed_view():
    pan, tilt, vp_yx, a = FIG_5_2
    p = gsrwt_parameters(pan, tilt, 280)
    assert p.shift == pytest.approx(a, abs=1)
    x, y = p.vanishing_point
    assert (y, x) == pytest.approx(vp_yx, abs=2)


@pytest.mark.parametrize(("pan", "tilt", "theta", "foreshortening"), TABLE_5_2)
def test_table_5_2(pan, tilt, theta, foreshortening):
    p = gsrwt_parameters(pan, tilt, 280)
    assert p.theta_deg == pytest.approx(theta, abs=0.02)
    assert p.foreshortening == pytest.approx(foreshortening, abs=0.01)


def test_rwt_swaps_slope_and_intercept_fig_4_3():
    slope, intercept = map_lines_to_destination(rwt_matrix(), 0.5, 1.0)
    assert (float(slope), float(intercept)) == pytest.approx((1.0, 0.5))


def test_eq_3_8_matches_camera_axes_built_from_words():
    for pan, tilt in [(15, 30), (-40, 10), (70, -60)]:
        np.testing.assert_allclose(camera_from_world(pan, tilt), camera_axes(pan, tilt), atol=1e-12)


@pytest.mark.parametrize("tiny", [0.0, 1e-9, -1e-9, 5e-10])
def test_frontal_view_is_identity_without_nan_or_warning(tiny):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = gsrwt_parameters(tiny, -tiny, 280)
        view = View(tiny, -tiny, 280, width=320, height=240)
        homography = output_from_input(view)
    assert p.is_frontal
    np.testing.assert_array_equal(p.matrix, np.eye(3))
    np.testing.assert_allclose(homography, np.eye(3), atol=1e-12)
    assert (p.delta_deg, p.gamma_deg) == (0, 0)
    assert (p.theta_deg, p.foreshortening) == pytest.approx((0, 1), abs=1e-8)
    assert not np.isnan(p.matrix).any() and not np.isnan(homography).any()


def test_just_off_frontal_stays_finite_and_close_to_identity():
    view = View(1e-6, 2e-6, 280, width=320, height=240)
    homography = output_from_input(view)
    corners = np.array([[0, 0], [319, 0], [319, 239], [0, 239]], dtype=float)
    np.testing.assert_allclose(map_points(homography, corners), corners, atol=1e-3)


@pytest.mark.parametrize(("pan", "tilt", "field"), [(90, 0, "pan"), (0, -90, "tilt"),
                                                    (120, 0, "pan"), (10, 95, "tilt")])
def test_camera_that_cannot_see_the_wall_is_refused(pan, tilt, field):
    with pytest.raises(ValueError, match=f"{field} must be strictly between -90 and 90"):
        gsrwt_parameters(pan, tilt, 280)
    with pytest.raises(ViewError) as info:
        View(pan, tilt, 280)
    assert info.value.field == field


@pytest.mark.parametrize("focal", [0, -3, math.nan, math.inf])
def test_bad_focal_is_refused(focal):
    with pytest.raises(ValueError, match="focal"):
        gsrwt_parameters(10, 10, focal)


def wall_points_in_view(pan, tilt, distance, count=40, seed=0):
    """Wall points ``(X, Y)`` around where the optical axis meets the wall, all in front."""
    forward = camera_axes(pan, tilt)[2]
    centre = distance * forward[:2] / forward[2]
    rng = np.random.default_rng(seed)
    spread = distance * 0.3
    points = centre + rng.uniform(-spread, spread, size=(count, 2))
    _, depth = project_wall_points(points, distance, pan, tilt, 500, 0, 0)
    return points[depth > 0.05 * distance]


@settings(max_examples=200, deadline=None)
@given(pan=angles, tilt=angles, focal=focals, distance=st.floats(0.5, 50))
def test_gsrwt_of_wall_is_similarity_eq_4_25(pan, tilt, focal, distance):
    """Eq. 4.25: u/w = -sin(theta) X / Zc + t_u and v/w = -sin(theta) Y / Zc + t_v."""
    p = gsrwt_parameters(pan, tilt, focal)
    assume(not p.is_frontal)
    wall = wall_points_in_view(pan, tilt, distance)
    assume(len(wall) >= 3)
    pixels, _ = project_wall_points(wall, distance, pan, tilt, focal, 0, 0)
    image_xy = np.column_stack([-pixels[:, 1], pixels[:, 0]])  # x = cy - row, y = col - cx
    uv = map_points(p.matrix, image_xy)
    scale = p.canonical_scale(distance)
    assert scale == pytest.approx(-math.sin(math.radians(p.theta_deg)) / distance)
    t_u, t_v = p.canonical_offsets
    expected = np.column_stack([scale * wall[:, 0] + t_u, scale * wall[:, 1] + t_v])
    np.testing.assert_allclose(uv, expected, rtol=1e-9, atol=1e-9 * (1 + np.abs(uv).max()))


@settings(max_examples=200, deadline=None)
@given(gamma=st.floats(-180, 180), delta=st.floats(-180, 180), shift=st.floats(-2000, 2000))
def test_every_transform_times_its_inverse_is_identity(gamma, delta, shift):
    pairs = [
        (rwt_matrix(), rwt_matrix()),
        (srwt_matrix(shift), srwt_inverse(shift)),
        (rotation_matrix(delta), rotation_matrix(-delta)),
        (gsrwt_matrix(gamma, shift, delta), gsrwt_inverse(gamma, shift, delta)),
    ]
    for forward, backward in pairs:
        np.testing.assert_allclose(forward @ backward, np.eye(3), atol=1e-9 * (1 + abs(shift)))
        np.testing.assert_allclose(backward @ forward, np.eye(3), atol=1e-9 * (1 + abs(shift)))


@settings(max_examples=200, deadline=None)
@given(pan=angles, tilt=angles, focal=focals)
def test_composite_is_product_of_factors_and_inverts(pan, tilt, focal):
    p = gsrwt_parameters(pan, tilt, focal)
    rot_delta, srwt, rot_minus_gamma = p.factors
    product = rot_minus_gamma @ srwt @ rot_delta
    np.testing.assert_allclose(product, p.matrix, rtol=1e-9, atol=1e-9 * np.abs(p.matrix).max())
    # Eq. 4.4: the inverse is the product of the factors' inverses in reverse order.
    inverse = np.linalg.inv(rot_delta) @ np.linalg.inv(srwt) @ np.linalg.inv(rot_minus_gamma)
    np.testing.assert_allclose(p.matrix @ inverse, np.eye(3), atol=1e-7)
    if not p.is_frontal:
        # The factors are rotations by delta and by Table 5.1's gamma: Eq. 4.21's Rot(-gamma)
        # holds the angle with the sign opposite to the tabulated one.
        np.testing.assert_allclose(rot_delta, rotation_matrix(p.delta_deg), atol=1e-12)
        np.testing.assert_allclose(rot_minus_gamma, rotation_matrix(p.gamma_deg), atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(pan=angles, tilt=angles, focal=focals)
def test_vanishing_point_lies_on_vanishing_line_where_w_is_zero(pan, tilt, focal):
    p = gsrwt_parameters(pan, tilt, focal)
    assume(not p.is_frontal and p.shift < 1e6)
    vp = p.vanishing_point
    line = p.vanishing_line
    scale = np.abs(line).max() * (1 + np.abs(vp).max())
    assert abs(line[:2] @ vp + line[2]) < 1e-9 * scale
    assert abs(homogeneous_w(p.matrix, vp)[0]) < 1e-9 * np.abs(p.matrix).max() * (1 + abs(vp).max())
    # The main vanishing point is the foot of the perpendicular: a away from the origin.
    assert np.hypot(*vp) == pytest.approx(p.shift)
    assert abs(vp[0] * line[1] - vp[1] * line[0]) < 1e-9 * scale  # vp parallel to the normal
    # Parallel wall lines perpendicular to L_y meet there: the images of far wall points along
    # the direction L'_x converge to the main vanishing point.


@settings(max_examples=200, deadline=None)
@given(
    gamma=st.floats(-180, 180), delta=st.floats(-180, 180), shift=st.floats(-500, 500),
    slope=st.floats(-20, 20), intercept=st.floats(-300, 300),
)
def test_hough_mapping_agrees_with_mapped_points(gamma, delta, shift, slope, intercept):
    """Eq. 4.6 (corrected): points of the mapped source line land on the destination line."""
    r = gsrwt_matrix(gamma, shift, delta)
    m_xy, c_xy = map_lines_to_source(r, slope, intercept)
    assume(np.isfinite(m_xy) and abs(m_xy) < 1e4)
    xs = np.linspace(-200, 200, 9)
    source = np.column_stack([xs, m_xy * xs + c_xy])
    w = homogeneous_w(r, source)
    keep = np.abs(w) > 1e-3 * np.abs(r).max() * (1 + np.abs(source).max())
    assume(keep.sum() >= 2)
    uv = map_points(r, source[keep])
    residual = (uv[:, 1] - slope * uv[:, 0] - intercept) / math.hypot(1, slope)
    scale = 1 + np.abs(uv).max()
    np.testing.assert_allclose(residual, 0, atol=1e-7 * scale)
    # And back: the destination line of the source line is the line we started from.
    m_back, c_back = map_lines_to_destination(r, m_xy, c_xy)
    assert float(m_back) == pytest.approx(slope, rel=1e-6, abs=1e-6)
    assert float(c_back) == pytest.approx(intercept, rel=1e-6, abs=1e-6 * (1 + abs(c_xy)))


@settings(max_examples=200, deadline=None)
@given(
    pan=angles, tilt=angles, focal=focals,
    cx=st.floats(0, 2000), cy=st.floats(0, 1500), distance=st.floats(0.5, 50),
)
def test_pixel_homography_matches_camera_turned_to_face_wall(pan, tilt, focal, cx, cy, distance):
    """The image of every wall point lands where a frontal pinhole camera sees it, up to a shift."""
    view = View(pan, tilt, focal, cx=cx, cy=cy)
    homography = output_from_input(view)
    wall = wall_points_in_view(pan, tilt, distance)
    assume(len(wall) >= 3)
    pixels, _ = project_wall_points(wall, distance, pan, tilt, focal, cx, cy)
    rectified = map_points(homography, pixels)
    frontal = frontal_pixels(wall, distance, focal, cx, cy)
    shift = rectified - frontal
    # Composing the GS-RWT with the shift to the principal point cancels terms of size
    # f / sin(theta): the result is good to about 1e-16 f / sin(theta) pixels near frontal.
    sin_theta = max(view.parameters.sin_theta, 1e-300)
    size = 1 + np.abs(frontal).max() + np.abs(rectified).max() + 1e-6 * focal / sin_theta
    np.testing.assert_allclose(shift - shift[0], 0, atol=1e-8 * size)
    # The point where the optical axis meets the wall lands on the principal point.
    forward = camera_axes(pan, tilt)[2]
    axis_point = distance * forward[:2] / forward[2]
    np.testing.assert_allclose(
        frontal_pixels(axis_point[None], distance, focal, cx, cy) + shift[0], [[cx, cy]],
        atol=1e-8 * size,
    )
    # Backward mapping inverts it.
    np.testing.assert_allclose(map_points_backward(homography, rectified), pixels,
                               atol=1e-7 * size)


@settings(max_examples=100, deadline=None)
@given(pan=angles, tilt=angles, focal=focals)
def test_pan_tilt_recovered_from_gsrwt_parameters(pan, tilt, focal):
    p = gsrwt_parameters(pan, tilt, focal)
    assume(not p.is_frontal and p.theta_deg > 1e-4)
    recovered = pan_tilt_from_gsrwt(p.delta_deg, p.shift, focal)
    assert recovered == pytest.approx((pan, tilt), abs=1e-6)


def test_vanishing_line_in_pixels_is_normalized_and_positive_on_visible_side():
    view = View(15, 30, 280, width=320, height=240)
    a, b, c = view.vanishing_line_pixels()
    assert a * a + b * b == pytest.approx(1)
    assert a * view.cx + b * view.cy + c > 0
    col, row = view.vanishing_point_pixels()
    assert a * col + b * row + c == pytest.approx(0, abs=1e-9)
    assert view.horizon_in_image() is False
    assert View(80, 10, 280, width=320, height=240).horizon_in_image() is True
