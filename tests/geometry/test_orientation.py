"""EXIF orientation as geometry: the displayed photo's pixel map and camera.

The displayed camera is checked against OpenCV's own projection (``cv2.projectPoints`` and
``cv2.fisheye.projectPoints``) of the sensor's camera, its pixels then moved as the EXIF
table moves a pixel: the turned intrinsics must project the turned rays to the same pixels.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.checks import ViewError
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.geometry.orientation import (
    ORIENTATIONS,
    displayed_from_stored,
    displayed_intrinsics,
    displayed_size,
    orientation_steps,
    valid_orientation,
)

WIDTH, HEIGHT = 640, 480

# The EXIF specification's table, written out: where stored pixel (u, v) shows.
EXIF_TABLE = {
    1: lambda u, v: (u, v),
    2: lambda u, v: (WIDTH - 1 - u, v),
    3: lambda u, v: (WIDTH - 1 - u, HEIGHT - 1 - v),
    4: lambda u, v: (u, HEIGHT - 1 - v),
    5: lambda u, v: (v, u),
    6: lambda u, v: (HEIGHT - 1 - v, u),
    7: lambda u, v: (HEIGHT - 1 - v, WIDTH - 1 - u),
    8: lambda u, v: (v, WIDTH - 1 - u),
}


@pytest.mark.parametrize("orientation", ORIENTATIONS)
def test_pixel_map_is_the_exif_table(orientation):
    corners = [(0, 0), (WIDTH - 1, 0), (0, HEIGHT - 1), (17, 301)]
    matrix = displayed_from_stored(orientation, WIDTH, HEIGHT)
    for u, v in corners:
        shown = matrix @ np.array([u, v, 1.0])
        assert tuple(shown[:2]) == EXIF_TABLE[orientation](u, v)
    width, height = displayed_size(orientation, WIDTH, HEIGHT)
    assert (width, height) == ((HEIGHT, WIDTH) if orientation >= 5 else (WIDTH, HEIGHT))


def _axes(orientation: int) -> np.ndarray:
    """The 3x3 signed permutation the orientation applies to camera x (right), y (down)."""
    swap, flip_x, flip_y = orientation_steps(orientation)
    axes = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) if swap else np.eye(3)
    return np.diag([-1.0 if flip_x else 1.0, -1.0 if flip_y else 1.0, 1.0]) @ axes


def _opencv_pixels(camera: Intrinsics, rays: np.ndarray) -> np.ndarray:
    """Pixels of OpenCV-frame rays (x right, y down, z forward) by OpenCV's own projection."""
    matrix = camera.matrix()
    if camera.lens is None:
        pixels, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), matrix, None)
    elif camera.lens.is_fisheye:
        pixels, _ = cv2.fisheye.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3),
                                              matrix, camera.lens.opencv_coefficients())
    else:
        pixels, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), matrix,
                                      camera.lens.opencv_coefficients())
    return pixels.reshape(-1, 2)


LENSES = {
    "pinhole": None,
    "plumb_bob": Lens("plumb_bob", (("k1", -0.21), ("k2", 0.05), ("p1", 0.004),
                                    ("p2", -0.007), ("k3", -0.01))),
    "rational with prism": Lens("rational_polynomial", (
        ("k1", 0.1), ("k2", -0.02), ("p1", -0.003), ("p2", 0.002), ("k4", 0.05),
        ("s1", 0.004), ("s2", -0.001), ("s3", -0.006), ("s4", 0.0008))),
    "fisheye": Lens("equidistant", (("k1", 0.05), ("k2", -0.01), ("k3", 0.002))),
}


@pytest.mark.parametrize("lens", LENSES.values(), ids=LENSES)
@pytest.mark.parametrize("orientation", ORIENTATIONS)
def test_displayed_camera_sees_what_the_sensor_saw_moved(orientation, lens):
    """A ray through the sensor's camera lands at stored pixel p; the same ray, in the
    displayed camera's axes, lands at A p through the displayed camera (fx != fy, cx, cy off
    centre, a lens with non-radial terms)."""
    sensor = Intrinsics(812.0, 776.0, 301.5, 250.25, 0.0, WIDTH, HEIGHT, lens)
    shown = displayed_intrinsics(sensor, orientation)
    rng = np.random.default_rng(orientation)
    rays = np.column_stack([rng.uniform(-0.35, 0.35, (200, 2)), np.ones(200)])
    stored = _opencv_pixels(sensor, rays)
    expected = (displayed_from_stored(orientation, WIDTH, HEIGHT)
                @ np.column_stack([stored, np.ones(len(stored))]).T).T[:, :2]
    turned = _opencv_pixels(shown, rays @ _axes(orientation).T)
    np.testing.assert_allclose(turned, expected, atol=1e-9)
    assert (shown.width, shown.height) == displayed_size(orientation, WIDTH, HEIGHT)
    if orientation >= 5:
        assert (shown.fx, shown.fy) == (sensor.fy, sensor.fx)


def test_skew_survives_mirrors_but_not_quarter_turns():
    sensor = Intrinsics(800.0, 800.0, 320.0, 240.0, 3.0, WIDTH, HEIGHT)
    rays = np.array([[0.1, -0.2, 1.0], [-0.3, 0.25, 1.0]])
    for orientation in (2, 3, 4):
        shown = displayed_intrinsics(sensor, orientation)
        expected = (displayed_from_stored(orientation, WIDTH, HEIGHT)
                    @ np.column_stack([_opencv_pixels(sensor, rays), np.ones(2)]).T).T[:, :2]
        np.testing.assert_allclose(_opencv_pixels(shown, rays @ _axes(orientation).T),
                                   expected, atol=1e-9)
    with pytest.raises(ViewError, match="skewed"):
        displayed_intrinsics(sensor, 6)


def test_tilted_sensor_lens_is_refused_and_upright_is_untouched():
    lens = Lens("rational_polynomial", (("k1", 0.1), ("tau_x", 0.01)))
    sensor = Intrinsics(800.0, 800.0, 320.0, 240.0, 0.0, WIDTH, HEIGHT, lens)
    with pytest.raises(ViewError, match="tilted"):
        displayed_intrinsics(sensor, 3)
    assert displayed_intrinsics(sensor, 1) is sensor


@pytest.mark.parametrize("value, meaning", [
    (1, 1), (6, 6), (8, 8), ((3,), 3), (0, 1), (9, 1), (-6, 1), (65535, 1), ("6", 1),
    (b"\x06", 1), (True, 1), (None, 1), (6.0, 1), ((6, 3), 1),
])
def test_invalid_orientation_values_mean_upright(value, meaning):
    assert valid_orientation(value) == meaning
