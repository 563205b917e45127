"""Rectify one image in memory: the Python API behind ``gsrwt rectify``.

>>> output, info = rectify_image(image, View(pan=15, tilt=30, focal=280))  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

from ..geometry.camera import View
from ..geometry.framing import Plan, plan_output
from ..imaging.images import warp_image

#: What was done to one image (the view, the output frame, the pixel map): a framing Plan.
RectifyInfo = Plan


class MissingDistanceError(ValueError):
    """Metric output (pixels per unit of distance) for an image whose distance is unknown."""

    def __init__(self) -> None:
        super().__init__("metric output needs the camera-to-wall 'distance' of the image")


def view_for_image(view: View, width: int, height: int) -> View:
    """The view with the image's size; a size in the view that disagrees is an error."""
    if view.width is None and view.height is None:
        return view.with_size(width, height)
    if (view.width, view.height) != (width, height):
        raise ValueError(
            f"the parameters say {view.width}x{view.height} pixels but the image is "
            f"{width}x{height}"
        )
    return view


def resolve_scale(view: View, scale: float = 1.0, px_per_unit: float | None = None) -> float:
    """Output pixels per frontal pixel; ``px_per_unit`` asks for N pixels per unit of distance.

    One frontal pixel covers ``Zc / f`` wall units (Eq. 4.25 at frontal resolution), so N
    pixels per unit is a scale of ``N Zc / f``.
    """
    if px_per_unit is None:
        return scale
    if view.distance is None:
        raise MissingDistanceError()
    return px_per_unit * view.distance / view.focal


def plan_image(
    view: View,
    width: int,
    height: int,
    *,
    bbox: str | tuple[float, float, float, float] = "frontal",
    scale: float = 1.0,
    px_per_unit: float | None = None,
    max_stretch: float = 4.0,
    max_pixels: float = 50e6,
    max_size: tuple[int, int] | None = None,
) -> RectifyInfo:
    """The geometry of rectifying a ``width x height`` image taken with ``view`` (no pixels)."""
    sized = view_for_image(view, width, height)
    return plan_output(
        sized, bbox, resolve_scale(sized, scale, px_per_unit), max_stretch, max_pixels,
        max_size,
    )


def rectify_image(
    image: np.ndarray,
    view: View,
    *,
    bbox: str | tuple[float, float, float, float] = "frontal",
    scale: float = 1.0,
    px_per_unit: float | None = None,
    max_stretch: float = 4.0,
    max_pixels: float = 50e6,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    antialias: bool = True,
) -> tuple[np.ndarray, RectifyInfo]:
    """The canonical frontal view of the wall in ``image`` (thesis Ch. 5.1).

    ``image``: an array as OpenCV reads it (H x W, H x W x 3 BGR or H x W x 4 BGRA; 8-bit,
    16-bit or float). ``view``: the camera; its size, if given, must match the image.
    By default the output has the input's size at frontal resolution (one pixel = Zc/f wall
    units), upright and centred on where the optical axis meets the wall (Fig. 5.7);
    pan = tilt = 0 returns the input unchanged. ``antialias``: area-filter where the output
    shrinks the input (:meth:`~gsrwt_cli.geometry.pixelmap.PixelMap.warp`). Raises ``ValueError``
    for
    impossible requests.
    """
    height, width = image.shape[:2]
    info = plan_image(
        view, width, height, bbox=bbox, scale=scale, px_per_unit=px_per_unit,
        max_stretch=max_stretch, max_pixels=max_pixels,
    )
    output = warp_image(image, info.pixel_map, interpolation, fill, alpha, antialias)
    return output, info
