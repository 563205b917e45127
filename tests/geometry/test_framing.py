"""The output frame (``geometry/framing.py``): ``Framing`` and ``plan_output`` against the camera
built from words (``tests/helpers/camera.py``), not against the package's own transform.

An output pixel of the default frame (Fig. 5.7) shows the wall point ``A + ((cy - row),
(col - cx)) Zc / f``, ``A`` where the optical axis meets the wall; a frame ``(x0, y0)`` at
``scale`` shows default-frame pixel ``(output + 0.5) / scale + (x0, y0) - 0.5``. From those
words alone the tests map output pixels to camera pixels and back, and check what each
framing promises: the full frame holds the whole image and no more, the crop has a source
for every pixel, ``scale``, ``px_per_unit`` and ``max_size`` size the output as they say.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gsrwt_cli.geometry.camera import View
from gsrwt_cli.geometry.framing import (
    EmptyOutputError,
    Frame,
    FrameOutsideImageError,
    Framing,
    MissingDistanceError,
    NothingWithinStretchError,
    OutputTooLargeError,
    fit_frame,
    plan_output,
    steady_box,
)
from gsrwt_cli.geometry.gsrwt import map_points
from tests.helpers.camera import camera_axes, project_wall_points

#: Camera to wall, in wall units: it cancels from every pixel relation below.
DISTANCE = 10.0
#: pan, tilt, focal, width, height: views whose horizon is outside the image, both signs.
VIEWS = [(15, 30, 280, 320, 240), (-25, 10, 500, 640, 480), (30, -20, 400, 480, 360),
         (-40, -25, 600, 400, 300)]


def axis_point(view: View) -> np.ndarray:
    """``A``: where the optical axis meets the wall, ``(X up, Y right)``."""
    forward = camera_axes(view.pan, view.tilt)[2]
    return DISTANCE * forward[:2] / forward[2]


def default_from_output(view: View, frame: Frame, outputs: np.ndarray) -> np.ndarray:
    """Default-frame pixels ``(col, row)`` of output pixels of ``frame``."""
    return (outputs + 0.5) / frame.scale + np.array([frame.x0, frame.y0]) - 0.5


def output_from_default(view: View, frame: Frame, default: np.ndarray) -> np.ndarray:
    return (default + 0.5 - np.array([frame.x0, frame.y0])) * frame.scale - 0.5


def camera_from_default(view: View, default: np.ndarray) -> np.ndarray:
    """Camera pixels of default-frame pixels, through the wall (the words of Fig. 5.7)."""
    unit = DISTANCE / view.focal
    wall = axis_point(view) + np.column_stack([view.cy - default[:, 1],
                                               default[:, 0] - view.cx]) * unit
    pixels, depth = project_wall_points(wall, DISTANCE, view.pan, view.tilt, view.focal,
                                        view.cx, view.cy)
    assert (depth > 0).all()
    return pixels


def default_from_camera(view: View, pixels: np.ndarray) -> np.ndarray:
    """Default-frame pixels of camera pixels: each pixel's ray meets the wall ``Z = Zc``."""
    up, right, forward = camera_axes(view.pan, view.tilt)
    x, y = view.cy - pixels[:, 1], pixels[:, 0] - view.cx
    rays = x[:, None] * up + y[:, None] * right + view.focal * forward
    assert (rays[:, 2] > 0).all()  # in front of the horizon
    wall = DISTANCE * rays[:, :2] / rays[:, 2:]
    offset = (wall - axis_point(view)) * view.focal / DISTANCE
    return np.column_stack([view.cx + offset[:, 1], view.cy - offset[:, 0]])


def corners(width: int, height: int) -> np.ndarray:
    """The image's outer pixel edges' corners, ``(col, row)``."""
    return np.array([[-0.5, -0.5], [width - 0.5, -0.5], [-0.5, height - 0.5],
                     [width - 0.5, height - 0.5]])


@pytest.mark.parametrize("pose", VIEWS, ids=lambda pose: f"pan{pose[0]}_tilt{pose[1]}")
def test_the_full_frame_holds_the_whole_image_and_no_more(pose):
    """``--bbox full`` with no stretch limit: every corner of the image lands inside the
    output, and each side of the output is within a pixel of the image (a homography maps
    the image's rectangle to a convex quadrilateral: its corners are its extremes)."""
    pan, tilt, focal, width, height = pose
    view = View(pan, tilt, focal, width=width, height=height)
    plan = plan_output(view, Framing(bbox="full", max_stretch=1e9))
    out_width, out_height = plan.size
    landed = output_from_default(view, plan.frame, default_from_camera(view, corners(width,
                                                                                      height)))
    low, high = landed.min(axis=0), landed.max(axis=0)
    assert (low >= -0.5 - 1e-6).all() and (high <= np.array([out_width, out_height]) - 0.5
                                            + 1e-6).all(), (landed, plan.size)
    assert (low < 0.5).all() and (high > np.array([out_width, out_height]) - 1.5).all()
    # The frontal frame is the input's size, whatever the pose; the full one is larger.
    assert plan_output(view).size == (width, height)
    assert out_width * out_height > width * height


@pytest.mark.parametrize("pose", VIEWS, ids=lambda pose: f"pan{pose[0]}_tilt{pose[1]}")
def test_every_pixel_of_the_crop_has_a_source_in_the_image(pose):
    """``--bbox crop``: every output pixel's centre, mapped through the camera built from
    words, lands between the image's outer pixel centres, and the crop is most of the
    image (not a sliver that trivially has a source)."""
    pan, tilt, focal, width, height = pose
    view = View(pan, tilt, focal, width=width, height=height)
    plan = plan_output(view, Framing(bbox="crop", max_stretch=1e9))
    out_width, out_height = plan.size
    cols, rows = np.meshgrid(np.arange(out_width, dtype=float), np.arange(out_height,
                                                                          dtype=float))
    outputs = np.column_stack([cols.ravel(), rows.ravel()])
    sources = camera_from_default(view, default_from_output(view, plan.frame, outputs))
    tolerance = 1e-6
    assert (sources >= -tolerance).all()
    assert (sources <= np.array([width - 1, height - 1]) + tolerance).all()
    assert out_width * out_height > 0.5 * width * height


@pytest.mark.parametrize("pose", VIEWS, ids=lambda pose: f"pan{pose[0]}_tilt{pose[1]}")
@pytest.mark.parametrize("aspect", ["original", 1.0, 2.5, 0.6])
def test_a_crop_of_a_given_shape_has_it_and_a_source_for_every_pixel(pose, aspect):
    """``--bbox crop --crop-aspect``: the output has the shape asked for (to its whole
    pixels), every output pixel's centre has a source in the image (the camera built from
    words), it is no larger than the crop of any shape, and most of the largest of its
    shape: grown by 3 % about its centre, it reaches outside the image."""
    pan, tilt, focal, width, height = pose
    view = View(pan, tilt, focal, width=width, height=height)
    plan = plan_output(view, Framing(bbox="crop", max_stretch=1e9, crop_aspect=aspect))
    wanted = width / height if aspect == "original" else aspect
    out_width, out_height = plan.size
    assert abs(out_width / out_height - wanted) <= 1.0 / min(out_width, out_height) * 2
    cols, rows = np.meshgrid(np.arange(out_width, dtype=float), np.arange(out_height,
                                                                          dtype=float))
    outputs = np.column_stack([cols.ravel(), rows.ravel()])
    sources = camera_from_default(view, default_from_output(view, plan.frame, outputs))
    assert (sources >= -1e-6).all()
    assert (sources <= np.array([width - 1, height - 1]) + 1e-6).all()
    unconstrained = plan_output(view, Framing(bbox="crop", max_stretch=1e9)).size
    assert out_width * out_height <= unconstrained[0] * unconstrained[1] * 1.01
    grown = (outputs - np.array([out_width, out_height]) / 2) * 1.03 + np.array(
        [out_width, out_height]) / 2
    reach = camera_from_default(view, default_from_output(view, plan.frame, grown))
    assert ((reach < -0.5) | (reach > np.array([width - 0.5, height - 0.5]))).any()


def test_the_package_maps_output_pixels_where_the_words_do():
    """``Plan.pixel_map`` agrees with the camera built from words, both ways, for the
    default, a scaled and an explicit frame (within 1e-6 px: two ways of computing)."""
    view = View(25, -15, 450, width=640, height=480)
    outputs = np.array([[0.0, 0.0], [100.5, 33.25], [639.0, 479.0], [320.0, 10.0]])
    for framing in (Framing(), Framing(scale=0.5), Framing(bbox=(-100, 20, 500, 300))):
        plan = plan_output(view, framing)
        expected = camera_from_default(view, default_from_output(view, plan.frame, outputs))
        np.testing.assert_allclose(plan.pixel_map.to_input(outputs), expected, atol=1e-6)
        np.testing.assert_allclose(plan.pixel_map.to_output(expected), outputs, atol=1e-6)


def test_scale_px_per_unit_and_max_size_size_the_output_as_they_say():
    view = View(30, 20, 300, width=320, height=240, distance=2.0)
    assert plan_output(view, Framing(scale=0.5)).size == (160, 120)
    # px_per_unit N is N Zc / f output pixels per frontal pixel: 150 * 2 / 300 = 1.
    metric = plan_output(view, Framing(px_per_unit=150.0))
    assert metric.frame.scale == pytest.approx(1.0) and metric.size == (320, 240)
    assert Framing(px_per_unit=45.0).output_scale(view) == pytest.approx(45.0 * 2.0 / 300)
    with pytest.raises(MissingDistanceError):
        plan_output(View(30, 20, 300, width=320, height=240), Framing(px_per_unit=150.0))
    full = plan_output(view, Framing(bbox="full"))
    fitted = plan_output(view, Framing(bbox="full", max_size=(200, 100)))
    assert fitted.size[0] <= 200 and fitted.size[1] <= 100
    assert fitted.size[0] >= 199 or fitted.size[1] >= 99  # lowered only as far as needed
    assert fitted.frame.scale < 1.0 and (fitted.frame.x0, fitted.frame.y0) == (
        full.frame.x0, full.frame.y0)  # the same rectangle of the wall, fewer pixels
    roomy = plan_output(view, Framing(bbox="full", max_size=(100_000, 100_000)))
    assert roomy.frame.scale == 1.0 and roomy.size == full.size  # never raised


def test_fitting_a_frame_never_overshoots_and_never_raises_the_scale():
    """:func:`fit_frame` over frames of many shapes: the size fits, the scale only goes
    down, and it goes down no further than a pixel's rounding needs."""
    rng = np.random.default_rng(3)
    for _ in range(2000):
        x0, y0 = rng.uniform(-500, 500, 2)
        frame = Frame(x0, y0, x0 + rng.uniform(1, 5000), y0 + rng.uniform(1, 5000),
                      rng.uniform(0.1, 4))
        limit = (int(rng.integers(1, 3000)), int(rng.integers(1, 3000)))
        fitted = fit_frame(frame, limit)
        width, height = fitted.size
        assert width <= limit[0] and height <= limit[1]
        assert fitted.scale <= frame.scale
        if fitted.scale < frame.scale:
            span_x, span_y = frame.x1 - frame.x0, frame.y1 - frame.y0
            best = min(limit[0] / span_x, limit[1] / span_y)
            assert fitted.scale == pytest.approx(best, rel=1e-9)


def test_outputs_that_cannot_be_made_are_typed_errors_naming_their_size():
    view = View(15, 30, 280, width=320, height=240)
    with pytest.raises(EmptyOutputError) as empty:
        plan_output(view, Framing(scale=0.001))
    assert (empty.value.width, empty.value.height) == (0, 0)
    with pytest.raises(OutputTooLargeError) as large:
        plan_output(view, Framing(scale=20, max_pixels=1e6))
    assert (large.value.width, large.value.height) == (6400, 4800)
    with pytest.raises(FrameOutsideImageError) as outside:
        plan_output(view, Framing(bbox=(5000, 5000, 5100, 5100)))
    assert outside.value.bbox == "box" and not outside.value.beyond_horizon
    with pytest.raises(ValueError, match="more than any image can be"):
        _ = Frame(0, 0, 10, 10, scale=1e308).size
    for error in (empty, large, outside):
        assert "--scale" not in str(error.value) and "--max-pixels" not in str(error.value)


def test_nothing_within_the_stretch_says_which_reason():
    """A frontal view is magnified alike everywhere: a ``max_stretch`` below 1 leaves
    nothing (over-stretched); a pan of 80 degrees with the stretch of the principal point
    leaves a sliver of the full frame, and the crop is refused or small."""
    frontal = View(0, 0, 300, width=320, height=240)
    with pytest.raises(NothingWithinStretchError) as stretched:
        plan_output(frontal, Framing(bbox="full", max_stretch=0.5))
    assert stretched.value.reason == NothingWithinStretchError.OVER_STRETCHED
    assert "0.5 times" in str(stretched.value)
    oblique = View(80, 0, 280, width=320, height=240)
    assert oblique.horizon_in_image()
    narrow = plan_output(oblique, Framing(bbox="full", max_stretch=1.0))
    wide = plan_output(oblique, Framing(bbox="full", max_stretch=4.0))
    assert narrow.size[0] * narrow.size[1] < wide.size[0] * wide.size[1]
    assert math.isfinite(wide.frame.x1)


def test_steady_box_puts_a_wall_point_where_the_first_view_put_it():
    """``steady_box``: a wall point lands on the same output pixel in every view of one
    focal length (the independent camera projects it), roll and principal points apart."""
    wall = np.array([[1.0, 0.5], [2.0, -1.0], [-0.5, 0.2]])
    first = View(pan=5, tilt=15, focal=300, cx=160, cy=120, width=320, height=240)
    expected = None
    for pan, tilt, roll, cx in [(5, 15, 0, 160), (12, 22, 1, 150), (-8, 18, -2, 170)]:
        view = View(pan=pan, tilt=tilt, roll=roll, focal=300, cx=cx, cy=120, width=320,
                    height=240)
        plan = plan_output(view, Framing(bbox=steady_box(view, first)))
        pixels, _ = project_wall_points(wall, 10.0, pan, tilt, 300, cx, 120, roll)
        landed = map_points(plan.homography, pixels)
        if expected is None:
            expected = landed
        np.testing.assert_allclose(landed, expected, atol=1e-6)
        assert plan.size == (320, 240)


@pytest.mark.parametrize(("pan", "tilt", "roll", "scale"),
                         [(20, 10, 0, 1.0), (-35, 25, 4, 1.0), (15, -30, -7, 0.5), (0, 0, 0, 2)])
def test_the_output_camera_sees_the_wall_where_the_output_shows_it(pan, tilt, roll, scale):
    """``Plan.output_camera()``: the camera of a bag output's camera_info. Wall points seen by
    the words-built camera land, through the plan's pixel map, where a camera with that K,
    square to the wall (its rotation the identity), sees them."""
    focal, width, height = 500.0, 640, 480
    view = View(pan=pan, tilt=tilt, roll=roll, focal=focal)
    plan = plan_output(view.with_size(width, height), Framing(scale=scale))
    k, camera_from_wall = plan.output_camera()
    np.testing.assert_allclose(camera_from_wall, np.eye(3), atol=1e-9)
    assert k[0, 0] == pytest.approx(focal * scale) and k[1, 1] == pytest.approx(focal * scale)
    assert k[0, 1] == pytest.approx(0, abs=1e-9) and k[2, 2] == 1
    grid = np.stack(np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 5)), -1).reshape(-1, 2)
    axis = 10 * camera_axes(pan, tilt, roll)[2]
    wall = grid + axis[:2] / axis[2] * 10  # around where the optical axis meets the wall
    seen, _ = project_wall_points(wall, 10.0, pan, tilt, focal, (width - 1) / 2,
                                  (height - 1) / 2, roll)
    shown = plan.pixel_map.to_output(seen)
    directions = np.column_stack([wall[:, 1], -wall[:, 0], np.full(len(wall), 10.0)])
    expected = directions @ k.T
    np.testing.assert_allclose(shown, expected[:, :2] / expected[:, 2:], atol=1e-6)
