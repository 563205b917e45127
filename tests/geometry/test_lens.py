"""The lens reached from the camera: :class:`Intrinsics` rays and pixels include the lens,
checked against OpenCV's own projection (``cv2.projectPoints``, ``cv2.fisheye.projectPoints``)
of the same rays, an implementation the package does not share for this direction of use;
and where each lens model folds back, from its formula worked by hand."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.lens import Lens, LensDistortion, monotonic_radius

WIDTH, HEIGHT = 640, 480
FX, FY, CX, CY = 520.0, 515.0, 322.5, 236.0

CAMERAS = {
    "plumb_bob": (("k1", -0.28), ("k2", 0.09), ("p1", 0.0012), ("p2", -0.0007), ("k3", -0.01)),
    "rational_polynomial": (("k1", 0.4), ("k2", -0.1), ("p1", 0.001), ("k4", 0.7),
                            ("k5", -0.05), ("s1", 0.002)),
    "equidistant": (("k1", -0.03), ("k2", 0.01), ("k3", -0.002), ("k4", 0.0004)),
}


def camera_of(model: str) -> Intrinsics:
    return Intrinsics(FX, FY, CX, CY, width=WIDTH, height=HEIGHT,
                      lens=Lens(model, CAMERAS[model]))


def opencv_rays_and_pixels(camera: Intrinsics, count: int = 500):
    """Random rays (OpenCV's frame: x right, y down, z forward) inside the picture, and the
    pixels OpenCV's projection of the same camera puts them on."""
    rng = np.random.default_rng(11)
    x = rng.uniform(-0.5, 0.5, count) * WIDTH / FX
    y = rng.uniform(-0.5, 0.5, count) * HEIGHT / FY
    rays = np.column_stack([x, y, np.ones(count)])
    k = np.array([[FX, 0, CX], [0, FY, CY], [0, 0, 1]], dtype=np.float64)
    zero = np.zeros(3)
    project = cv2.fisheye.projectPoints if camera.lens.is_fisheye else cv2.projectPoints
    pixels, _ = project(rays[:, None, :], zero, zero, k, camera.lens.opencv_coefficients())
    return rays, pixels.reshape(-1, 2)


def thesis_from_opencv(rays: np.ndarray) -> np.ndarray:
    """OpenCV's camera frame (x right, y down) to the thesis's (X up, Y right), Z = 1."""
    return np.column_stack([-rays[:, 1], rays[:, 0], rays[:, 2]]) / rays[:, 2:3]


@pytest.mark.parametrize("model", sorted(CAMERAS))
def test_rays_from_pixels_undo_the_lens(model: str) -> None:
    camera = camera_of(model)
    rays, pixels = opencv_rays_and_pixels(camera)
    found = camera.rays_from_pixels(pixels)
    np.testing.assert_allclose(found, thesis_from_opencv(rays), atol=1e-6)
    # A pinhole with the same K would be wrong by many pixels' worth of angle.
    pinhole = Intrinsics(FX, FY, CX, CY, width=WIDTH, height=HEIGHT).rays_from_pixels(pixels)
    assert np.max(np.abs(pinhole - thesis_from_opencv(rays))) > 1e-2


@pytest.mark.parametrize("model", sorted(CAMERAS))
def test_pixels_from_rays_apply_the_lens(model: str) -> None:
    camera = camera_of(model)
    rays, pixels = opencv_rays_and_pixels(camera)
    np.testing.assert_allclose(camera.pixels_from_rays(thesis_from_opencv(rays)), pixels,
                               atol=1e-6)


def test_a_pinhole_has_no_distortion_and_keeps_its_pixels() -> None:
    camera = Intrinsics(FX, FY, CX, CY, lens=Lens("plumb_bob", (("k1", 0.0),)))
    assert camera.lens is None and camera.distortion() is None
    pixels = np.array([[0.0, 0.0], [639.0, 479.0], [CX, CY]])
    np.testing.assert_array_equal(camera.ideal_pixels(pixels), pixels)
    rays = camera.rays_from_pixels(pixels)
    np.testing.assert_allclose(camera.pixels_from_rays(rays), pixels, atol=1e-9)
    assert rays[2].tolist() == [0.0, 0.0, 1.0]


def test_pixels_beyond_the_lens_fold_have_no_ray() -> None:
    """A barrel lens strong enough to fold back inside the picture: its pixels beyond the
    fold have no ray of their own, and come back NaN rather than a mirrored ray."""
    camera = Intrinsics(300.0, 300.0, CX, CY, width=WIDTH, height=HEIGHT,
                        lens=Lens("plumb_bob", (("k1", -0.5),)))
    fold = camera.distortion().limit  # r_d = r (1 - 0.5 r^2) turns at r = sqrt(2/3)
    assert fold == pytest.approx(math.sqrt(2 / 3), rel=1e-9)
    corner = np.array([[0.0, 0.0]])  # r_d = 1.33 there; the lens reaches at most 0.54
    assert np.isnan(camera.rays_from_pixels(corner)).any()
    assert np.all(np.isfinite(camera.rays_from_pixels(np.array([[CX + 50, CY + 40]]))))


@pytest.mark.parametrize(("coefficients", "fisheye", "radius"), [
    # r_d = r (1 + k1 r^2): d r_d / dr = 1 + 3 k1 r^2 = 0 at r^2 = -1 / (3 k1).
    ((-0.3, 0.0, 0.0, 0.0, 0.0), False, 1 / math.sqrt(0.9)),
    # r_d = r / (1 + k4 r^2): d r_d / dr has the sign of 1 - k4 r^2.
    ((0.0, 0.0, 0.0, 0.0, 0.0, 0.25, 0.0, 0.0), False, 2.0),
    # r_d = theta (1 + k1 theta^2): zero slope at theta^2 = -1 / (3 k1), r = tan theta.
    ((-0.2, 0.0, 0.0, 0.0), True, math.tan(math.sqrt(1 / 0.6))),
    # r_d grows with r everywhere: no fold.
    ((0.1, 0.01, 0.0, 0.0, 0.0), False, math.inf),
])
def test_the_radius_where_a_lens_folds_back_is_its_formulas(coefficients, fisheye, radius):
    assert monotonic_radius(coefficients, fisheye) == pytest.approx(radius, rel=1e-9)


def test_nothing_beyond_the_fold_is_distorted_or_undistorted():
    """Ideal pixels beyond the fold have no pixel of their own (NaN), those within do; a
    pixel of the image that only rays beyond the fold reach has no ideal pixel."""
    k = ((300.0, 0.0, 320.0), (0.0, 300.0, 240.0), (0.0, 0.0, 1.0))
    lens = LensDistortion(k, (-0.3, 0.0, 0.0, 0.0, 0.0))
    limit_px = 300.0 / math.sqrt(0.9)
    assert lens.limit_px == pytest.approx(limit_px)
    ideal = np.array([[320.0 + 0.99 * limit_px, 240.0], [320.0 + 1.01 * limit_px, 240.0]])
    distorted = lens.distort(ideal)
    assert np.isfinite(distorted[0]).all() and np.isnan(distorted[1]).all()
    # The largest radius the model reaches: r (1 - 0.3 r^2) at its fold, in pixels.
    r = 1 / math.sqrt(0.9)
    reach_px = 300.0 * r * (1 - 0.3 * r * r)
    pixels = np.array([[320.0 + 0.98 * reach_px, 240.0], [320.0 + 1.05 * reach_px, 240.0]])
    undistorted = lens.undistort(pixels)
    assert np.isfinite(undistorted[0]).all() and np.isnan(undistorted[1]).all()
    np.testing.assert_allclose(lens.distort(undistorted[:1]), pixels[:1], atol=1e-6)
