"""Rectify one image in memory: the Python API behind ``gsrwt rectify``.

>>> output, info = rectify_image(image, View(pan=15, tilt=30, focal=280))  # doctest: +SKIP
>>> output, info = rectify_image(image, view, Framing(bbox="full"))  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

from ..geometry.camera import View
from ..geometry.framing import (
    DEFAULT_FRAMING,
    Framing,
    MissingDistanceError,
    Plan,
    plan_output,
)

__all__ = ["Framing", "MissingDistanceError", "Plan", "plan_image", "rectify_image",
           "view_for_image"]
from ..imaging.images import warp_image


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


def plan_image(view: View, width: int, height: int, framing: Framing = DEFAULT_FRAMING) -> Plan:
    """The geometry of rectifying a ``width x height`` image taken with ``view`` (no pixels):
    the output framed as ``framing`` says (:class:`~gsrwt_cli.geometry.framing.Framing`)."""
    return plan_output(view_for_image(view, width, height), framing)


def rectify_image(
    image: np.ndarray,
    view: View,
    framing: Framing = DEFAULT_FRAMING,
    *,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    antialias: bool = True,
) -> tuple[np.ndarray, Plan]:
    """The canonical frontal view of the wall in ``image`` (thesis Ch. 5.1).

    ``image``: an array as OpenCV reads it (H x W, H x W x 3 BGR or H x W x 4 BGRA; 8-bit,
    16-bit or float). ``view``: the camera; its size, if given, must match the image.
    ``framing``: the output's rectangle and size
    (:class:`~gsrwt_cli.geometry.framing.Framing`); by default the input's size at frontal
    resolution (one pixel = Zc/f wall units), upright and centred on where the optical axis
    meets the wall (Fig. 5.7); pan = tilt = 0 returns the input unchanged. ``antialias``:
    area-filter where the output shrinks the input
    (:meth:`~gsrwt_cli.geometry.pixelmap.PixelMap.warp`). Raises ``ValueError`` for
    impossible requests.
    """
    height, width = image.shape[:2]
    info = plan_image(view, width, height, framing)
    output = warp_image(image, info.pixel_map, interpolation, fill, alpha, antialias)
    return output, info
