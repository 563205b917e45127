"""The Python API of one image (``api/rectify.py``): ``rectify_image`` against the frontal view
of the independent pinhole camera, every interpolation, and the command's framing as one
``Framing`` object."""

from __future__ import annotations

import pytest

from gsrwt_cli import View
from gsrwt_cli.api.rectify import rectify_image
from tests.helpers.camera import expected_rectified, render_view
from tests.helpers.images import psnr, smooth_texture

TEXTURE = smooth_texture(1400, 1800, seed=1)
DISTANCE = 10.0
#: pan, tilt, focal, width, height, cx, cy: views of both signs, principal points off centre.
PAN_LEFT_TILT_UP = (-20, 25, 500, 640, 480, 300.0, 260.0)
PAN_LEFT_TILT_DOWN = (-35, -20, 400, 480, 360, 250.0, 170.0)


@pytest.mark.parametrize("flip", ["pan", "tilt"])
def test_wrong_signs_do_not_rectify(flip):
    """The PSNR comparison can fail: a view rectified with a flipped angle is far off."""
    pan, tilt, focal, width, height, cx, cy = PAN_LEFT_TILT_UP
    image, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
    expected, seen = expected_rectified(TEXTURE, pan, tilt, focal, width, height, cx, cy,
                                        DISTANCE, centre)
    right, _ = rectify_image(image, View(pan, tilt, focal, cx=cx, cy=cy))
    wrong_view = View(-pan if flip == "pan" else pan, -tilt if flip == "tilt" else tilt, focal,
                      cx=cx, cy=cy)
    wrong, _ = rectify_image(image, wrong_view)
    assert psnr(right, expected, seen) >= 30
    assert psnr(wrong, expected, seen) < 20


@pytest.mark.parametrize("interpolation", ["nearest", "linear", "cubic", "lanczos"])
def test_python_api_every_interpolation(interpolation):
    pan, tilt, focal, width, height, cx, cy = PAN_LEFT_TILT_DOWN
    image, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
    output, info = rectify_image(image, View(pan, tilt, focal, cx=cx, cy=cy),
                                 interpolation=interpolation)
    expected, seen = expected_rectified(TEXTURE, pan, tilt, focal, width, height, cx, cy,
                                        DISTANCE, centre)
    assert info.size == (width, height)
    assert psnr(output, expected, seen) >= (28 if interpolation == "nearest" else 30)


def test_the_api_frames_as_the_command_does_with_one_framing_object():
    """``rectify_image`` and ``plan_image`` take the command's whole framing (bbox, scale or
    pixels per unit, stretch, pixel and size limits) as one frozen ``Framing``: ``max_size``
    lowers the scale until the output fits, ``px_per_unit`` is N pixels per unit of the
    distance, and the default is the thesis's frame."""
    import dataclasses

    from gsrwt_cli import Framing, plan_image, rectify_image

    image = smooth_texture(240, 320, 3)
    view = View(30, 20, 300, distance=2.0)
    default, info = rectify_image(image, view)
    assert info.frame.scale == 1.0 and default.shape[:2] == (240, 320)
    fitted, info = rectify_image(image, view, Framing(bbox="full", max_size=(100, 80)))
    assert fitted.shape[0] <= 80 and fitted.shape[1] <= 100 and info.frame.scale < 1.0
    assert max(fitted.shape[1] / 100, fitted.shape[0] / 80) > 0.97  # the scale is not lowered more
    metric = plan_image(view, 320, 240, Framing(px_per_unit=150.0))
    assert metric.frame.scale == pytest.approx(150.0 * 2.0 / 300)  # N Zc / f
    with pytest.raises(dataclasses.FrozenInstanceError):
        Framing().scale = 2.0  # type: ignore[misc]
