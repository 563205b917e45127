"""The pixel map (``geometry/pixelmap.py``) against OpenCV's own camera: output pixels mapped to
the input through the camera built from words and ``cv2.projectPoints`` (or
``cv2.fisheye.projectPoints``), and back through the lens; the shrink by finite differences;
the region beyond the horizon where the camera's plane meets the wall."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli.geometry.camera import View
from gsrwt_cli.geometry.framing import Framing, plan_output
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.geometry.pixelmap import PixelMap
from tests.helpers.camera import camera_axes
from tests.helpers.images import phase_shift, smooth_texture

DISTANCE = 10.0
WIDTH, HEIGHT, FOCAL = 640, 480, 500.0
LENSES = {
    "plumb_bob": Lens("plumb_bob", (("k1", -0.12), ("k2", 0.03), ("p1", 0.001),
                                    ("p2", -0.0005), ("k3", -0.004))),
    "rational": Lens("rational_polynomial", (("k1", 0.3), ("k2", -0.05), ("k4", 0.35),
                                             ("k5", -0.02))),
    "fisheye": Lens("equidistant", (("k1", 0.05), ("k2", -0.01), ("k3", 0.002))),
}


def opencv_pixels(view: View, default: np.ndarray) -> np.ndarray:
    """Camera pixels of default-frame pixels: the wall point each shows (Fig. 5.7, the words
    of docs/CONVENTIONS.md), seen by OpenCV's camera with the view's lens."""
    up, right, forward = camera_axes(view.pan, view.tilt)
    axis = DISTANCE * forward[:2] / forward[2]
    unit = DISTANCE / view.focal
    wall = axis + np.column_stack([view.cy - default[:, 1], default[:, 0] - view.cx]) * unit
    points = np.column_stack([wall, np.full(len(wall), DISTANCE)])
    # OpenCV's camera frame: x right, y down, z forward.
    in_camera = np.column_stack([points @ right, -(points @ up), points @ forward])
    k = view.intrinsics.matrix()
    coefficients = view.intrinsics.lens.opencv_coefficients()
    zero = np.zeros(3)
    if view.intrinsics.lens.is_fisheye:
        pixels, _ = cv2.fisheye.projectPoints(in_camera[:, None, :], zero, zero, k,
                                              coefficients)
    else:
        pixels, _ = cv2.projectPoints(in_camera, zero, zero, k, coefficients)
    return pixels.reshape(-1, 2)


def output_grid(size: tuple[int, int], count: int = 9) -> np.ndarray:
    cols, rows = np.meshgrid(np.linspace(0, size[0] - 1, count),
                             np.linspace(0, size[1] - 1, count))
    return np.column_stack([cols.ravel(), rows.ravel()])


@pytest.mark.parametrize("name", LENSES)
def test_output_pixels_map_to_where_opencvs_camera_sees_their_wall_point(name):
    """The default frame of a view through each lens model: ``to_input`` is OpenCV's
    projection of the wall point the output pixel shows (within 1e-6 px), and ``to_output``
    brings OpenCV's pixel back to the output pixel (the lens inverted)."""
    view = View(20, -12, FOCAL, width=WIDTH, height=HEIGHT, lens=LENSES[name])
    plan = plan_output(view)
    outputs = output_grid(plan.size)
    expected = opencv_pixels(view, outputs)  # the default frame: output = default pixel
    inside = np.all((expected > 0) & (expected < [WIDTH - 1, HEIGHT - 1]), axis=1)
    assert inside.sum() > 40
    np.testing.assert_allclose(plan.pixel_map.to_input(outputs), expected, atol=1e-6)
    back = plan.pixel_map.to_output(expected[inside])
    np.testing.assert_allclose(back, outputs[inside], atol=1e-6)


def test_the_shrink_is_the_largest_singular_value_of_the_maps_jacobian():
    """``PixelMap.shrink``: input pixels per output pixel, against central differences of
    ``to_input`` (a pinhole's map at half scale, panned so that the near side of the wall is
    magnified and the far side shrunk: the values checked span a range)."""
    view = View(50, 20, 400, width=WIDTH, height=HEIGHT)
    pixel_map = plan_output(view, Framing(scale=0.5)).pixel_map
    step = 16
    shrink = pixel_map.shrink(step)
    width, height = pixel_map.size
    cols = np.arange(0, width + step - 1, step, dtype=float).clip(max=width - 1)
    rows = np.arange(0, height + step - 1, step, dtype=float).clip(max=height - 1)
    assert shrink.shape == (len(rows), len(cols))
    h = 1e-3
    for i in range(0, len(rows), 3):
        for j in range(0, len(cols), 3):
            point = np.array([[cols[j], rows[i]]])
            jacobian = np.column_stack([
                (pixel_map.to_input(point + [h, 0]) - pixel_map.to_input(point - [h, 0]))[0],
                (pixel_map.to_input(point + [0, h]) - pixel_map.to_input(point - [0, h]))[0],
            ]) / (2 * h)
            largest = np.linalg.svd(jacobian, compute_uv=False)[0]
            assert shrink[i, j] == pytest.approx(largest, rel=1e-5)
    assert shrink.min() < 1 and shrink.max() > 2


def test_the_region_beyond_the_horizon_starts_where_the_camera_plane_meets_the_wall():
    """A camera panned 80 degrees sees the wall to its side; the plane through the camera
    at right angles to its axis meets the wall ``Zc cot(pan)`` to the right of the foot of
    the perpendicular, and the axis meets it ``Zc tan(pan)`` to the left: in the default
    frame that is column ``cx + f (cot pan + tan pan)``. A frame reaching past it has that
    region beyond the horizon (``beyond_horizon``), and only there are sources behind the
    camera (``w <= 0``); a view facing the wall has no such region."""
    pan, focal = 80.0, 280.0
    view = View(pan, 0, focal, width=320, height=240)
    pixel_map = plan_output(view, Framing(bbox=(0, 0, 2400, 240))).pixel_map
    edge = view.cx + focal * (1 / math.tan(math.radians(pan)) + math.tan(math.radians(pan)))
    polygon = pixel_map.beyond_horizon()
    assert polygon is not None
    assert polygon[:, 0].min() == pytest.approx(edge, abs=1e-6)
    assert polygon[:, 0].max() == pytest.approx(2400 - 0.5)
    assert sorted(set(polygon[:, 1])) == [-0.5, 239.5]
    inverse = np.linalg.inv(np.asarray(pixel_map.output_from_input, dtype=float))
    cols = np.array([edge - 50, edge - 1, edge + 1, edge + 50])
    w = np.column_stack([cols, np.full(4, 120.0), np.ones(4)]) @ inverse[2]
    assert (w[:2] > 0).all() and (w[2:] < 0).all()
    facing = PixelMap(np.eye(3), (320, 240))
    assert facing.beyond_horizon() is None and facing.sees((320, 240))
    assert not facing.then(np.array([[1.0, 0, -1000], [0, 1, 0], [0, 0, 1]]),
                           (100, 100)).sees((320, 240))


# --------------------------------------------------------------------------------------------
# A reduced input (a JPEG decoded 2, 4 or 8 times smaller in the DCT)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", [None, *LENSES])
@pytest.mark.parametrize(("factor", "offset"), [(2, (0.0, 0.0)), (4, (0.75, 0.0)),
                                                (8, (0.0, 0.25))])
def test_a_reduced_map_is_the_map_in_reduced_pixels(name, factor, offset):
    """``PixelMap.reduced``: every output pixel maps to its input pixel in the reduced image's
    pixels, ``(x + 0.5) / factor - 0.5 + offset`` (pixel centres at integers), through a
    pinhole and through each lens model (the lens's camera matrix turned with the pixels);
    the output side (its size, which pixels have no source beyond the horizon) is the same."""
    view = View(20, -12, FOCAL, width=WIDTH, height=HEIGHT,
                lens=None if name is None else LENSES[name])
    pixel_map = plan_output(view, Framing(scale=0.3)).pixel_map
    reduced = pixel_map.reduced(factor, offset)
    outputs = output_grid(pixel_map.size)
    full = pixel_map.to_input(outputs)
    finite = np.all(np.isfinite(full), axis=1)
    assert finite.sum() > 40
    expected = (full[finite] + 0.5) / factor - 0.5 + np.array(offset)
    np.testing.assert_allclose(reduced.to_input(outputs)[finite], expected, atol=1e-6)
    assert reduced.size == pixel_map.size
    horizon = np.linalg.inv(np.asarray(pixel_map.output_from_input, dtype=float))[2]
    np.testing.assert_allclose(np.linalg.inv(reduced.output_from_input)[2], horizon,
                               rtol=1e-12)


def test_the_least_shrink_is_the_least_of_every_pixel_that_samples_the_input():
    """``PixelMap.least_shrink``: over every output pixel whose source lies inside the input
    (checked pixel by pixel, against :meth:`shrink` at step 1), never more than the least
    shrink there (it may decide a reduction), and within 2 % of it (not needlessly low);
    ``inf`` when no output pixel has a source."""
    for view, framing in [(View(50, 20, 400, width=WIDTH, height=HEIGHT),
                           Framing(bbox="full", scale=0.25)),
                          (View(-30, 35, 300, width=WIDTH, height=HEIGHT),
                           Framing(bbox="full", scale=0.2)),
                          (View(20, -25, 500, width=WIDTH, height=HEIGHT),  # the input's
                           Framing(bbox=(-245, -220, 990, 1040), scale=0.25)),  # edge inside
                          (View(0, 0, 500, width=WIDTH, height=HEIGHT), Framing(scale=0.2)),
                          (View(25, 10, FOCAL, width=WIDTH, height=HEIGHT,
                                lens=LENSES["plumb_bob"]), Framing(scale=0.3))]:
        pixel_map = plan_output(view, framing).pixel_map
        every = pixel_map.shrink(1, (WIDTH, HEIGHT))
        width, height = pixel_map.size
        cols, rows = np.meshgrid(np.arange(width, dtype=float), np.arange(height, dtype=float))
        sources = pixel_map.to_input(np.column_stack([cols.ravel(), rows.ravel()]))
        with np.errstate(invalid="ignore"):
            inside = np.all((sources >= -0.5) & (sources <= [WIDTH - 0.5, HEIGHT - 0.5]),
                            axis=1).reshape(every.shape)
        truth = every[inside].min()
        least = pixel_map.least_shrink((WIDTH, HEIGHT))
        assert truth * 0.98 <= least <= truth, (view, truth, least)
        assert every.max() > 1.3 * truth or view.pan == 0  # a shrink that varies
    far_away = PixelMap(np.array([[0.5, 0, -5000], [0, 0.5, -5000], [0, 0, 1]]), (100, 100))
    assert far_away.least_shrink((WIDTH, HEIGHT)) == math.inf


def test_a_maps_inverse_is_computed_once_and_cannot_be_changed():
    """The inverse the map's checks and antialiasing share (computed once a map): the same
    array at every use, equal to numpy's inverse of the map, and read-only, so that no use
    can change what the next one sees."""
    view = View(12.0, -7.0, FOCAL, width=WIDTH, height=HEIGHT)
    pixel_map = plan_output(view, Framing(scale=0.5)).pixel_map
    inverse = pixel_map._input_from_output
    assert inverse is pixel_map._input_from_output
    np.testing.assert_array_equal(inverse, np.linalg.inv(pixel_map.output_from_input))
    with pytest.raises(ValueError, match="read-only"):
        inverse[0, 0] = 1.0
    points = np.array([[0.0, 0.0], [100.0, 50.0], [319.0, 239.0]])
    np.testing.assert_allclose(pixel_map.to_output(pixel_map.to_input(points)), points,
                               atol=1e-9)


def opencv_render(view: View, texture: np.ndarray) -> np.ndarray:
    """What OpenCV's camera (the view's pose, intrinsics and lens) sees of a frontal
    ``texture`` on the wall: each camera pixel's ray by ``cv2.undistortPoints``, met with the
    wall, the texture sampled there (its centre where the optical axis meets the wall, one
    texel per ``Zc / f`` wall units)."""
    up, right, forward = camera_axes(view.pan, view.tilt)
    cols, rows = np.meshgrid(np.arange(view.width, dtype=np.float64),
                             np.arange(view.height, dtype=np.float64))
    pixels = np.column_stack([cols.ravel(), rows.ravel()])[:, None, :]
    lens = view.intrinsics.lens
    coefficients = None if lens is None else lens.opencv_coefficients()
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 60, 1e-12)
    ideal = cv2.undistortPoints(pixels, view.intrinsics.matrix(), coefficients, None, None,
                                None, criteria).reshape(-1, 2)
    rays = ideal[:, :1] * right - ideal[:, 1:] * up + forward  # OpenCV's y points down
    wall = rays[:, :2] * (DISTANCE / rays[:, 2:])
    axis = DISTANCE * forward[:2] / forward[2]
    unit = DISTANCE / view.focal
    height, width = texture.shape[:2]
    map_x = (wall[:, 1] - axis[1]) / unit + (width - 1) / 2
    map_y = (height - 1) / 2 - (wall[:, 0] - axis[0]) / unit
    return cv2.remap(texture, map_x.reshape(view.height, view.width).astype(np.float32),
                     map_y.reshape(view.height, view.width).astype(np.float32),
                     cv2.INTER_LINEAR)


@pytest.mark.parametrize("name", [None, "plumb_bob"])
@pytest.mark.parametrize(("pan", "tilt", "scale", "levels"),
                         [(0, 0, 0.52, 1), (10, 30, 0.4, 2), (10, 30, 0.2, 3)])
def test_the_antialiased_warp_is_not_shifted(name, pan, tilt, scale, levels):
    """A fine texture rendered by OpenCV's camera (a pinhole, and a plumb_bob lens), rectified
    antialiased where the output shrinks it (frontally 1.9 times; tilted, its far side most,
    up to 7 times), so that 1, 2 and 3 pyramid levels are blended: its shift against the
    area-averaged reference (the same map unfiltered at 8 times the output's size, averaged
    over 8x8 blocks) is under 0.05 output pixels by phase correlation (measured: 0.004-0.015;
    0.31-0.52 when the levels were sampled as if centred like a box average's pixels,
    ``cv2.pyrDown``'s level ``l`` then ``(2^l - 1) / 2`` input pixels off)."""
    from gsrwt_cli.geometry.pixelmap import pyramid_level

    width, height = 1280, 960
    view = View(pan, tilt, 1000.0, width=width, height=height,
                lens=None if name is None else LENSES[name])
    image = opencv_render(view, smooth_texture(3 * height, 3 * width, 11, channels=1))
    pixel_map = plan_output(view, Framing(bbox="crop", scale=scale)).pixel_map
    used = pyramid_level(pixel_map.shrink(32, (width, height)))
    assert math.ceil(used.max()) == levels
    output = pixel_map.warp(image, cv2.INTER_LINEAR, (0.0,) * 4, antialias=True)
    out_width, out_height = pixel_map.size
    fine = pixel_map.then(np.array([[8.0, 0, 3.5], [0, 8.0, 3.5], [0, 0, 1]]),
                          (8 * out_width, 8 * out_height))
    reference = cv2.resize(fine.warp(image, cv2.INTER_LINEAR, (0.0,) * 4),
                           (out_width, out_height), interpolation=cv2.INTER_AREA)
    assert phase_shift(reference, output) < 0.05


@pytest.mark.parametrize("scale", [1.0, 0.9, 0.5, 0.25])
def test_the_antialiasing_filters_exactly_where_filters_says(scale: float) -> None:
    """``filters`` (the one measure a frame's three planes share): true for a map that
    shrinks the input by more than 1.5, and then the antialiased warp differs from the plain
    one; false otherwise, and then the two are the same array."""
    rng = np.random.default_rng(5)
    image = cv2.GaussianBlur(rng.integers(0, 255, (240, 320)).astype(np.uint8), (0, 0), 1.0)
    pixel_map = PixelMap(np.diag([scale, scale, 1.0]), (int(320 * scale), int(240 * scale)))
    filters = pixel_map.filters((320, 240))
    assert filters == (1 / scale > 1.5)
    plain = pixel_map.warp(image, cv2.INTER_LINEAR, (0.0,) * 4)
    filtered = pixel_map.warp(image, cv2.INTER_LINEAR, (0.0,) * 4, antialias=True)
    assert np.array_equal(plain, filtered) == (not filters)
