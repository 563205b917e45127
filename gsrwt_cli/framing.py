"""The output frame: where the canonical view lands in output pixels (spec section 5).

Composes the GS-RWT (in the image frame) with the pixel frames of the input and the output
into one 3x3 homography, output pixel from input pixel, that an OpenCV warp applies in one pass.
Pure geometry: no I/O.
"""

from __future__ import annotations

import numpy as np

from .camera import View
from .geometry import Matrix, map_points


def canonical_from_pixel(view: View) -> Matrix:
    """Input pixel ``(col, row)`` to canonical coordinates ``(U, V)`` at frontal resolution.

    ``(U, V) = (f / sin theta) * GS-RWT(x, y)`` (Eq. 4.22 scaled as in spec section 5): the
    wall seen frontally, turned by 180 degrees (the negative scale of Eq. 4.25) and shifted.
    """
    return view.parameters.canonical_from_image() @ view.image_from_pixel()


def optical_axis_canonical(view: View) -> np.ndarray:
    """``(U, V)`` where the optical axis meets the wall (the image of the principal point)."""
    return map_points(view.parameters.canonical_from_image(), [[0.0, 0.0]])[0]


def upright_from_canonical(
    view: View, scale: float = 1.0, anchor: tuple[float, float] | None = None
) -> Matrix:
    """Canonical ``(U, V)`` to upright output pixels ``(col, row)``.

    The canonical view is turned by 180 degrees, so output columns run along ``-V`` and rows
    along ``+U`` (spec section 3). ``scale`` output pixels per frontal pixel. The optical-axis
    point lands on ``anchor`` (default: the input's principal point, so that pan = tilt = 0
    is the identity), as in the thesis's bounding box of Fig. 5.7.
    """
    u0, v0 = optical_axis_canonical(view)
    col0, row0 = anchor if anchor is not None else (view.cx, view.cy)
    return np.array(
        [[0.0, -scale, scale * v0 + col0], [scale, 0.0, -scale * u0 + row0], [0.0, 0.0, 1.0]]
    )


def output_from_input(
    view: View, scale: float = 1.0, anchor: tuple[float, float] | None = None
) -> Matrix:
    """The pixel homography: input ``(col, row)`` to the upright canonical view's ``(col, row)``.

    One output pixel is ``Zc / (f * scale)`` wall units; the optical-axis point lands on
    ``anchor`` (default: the principal point). Normalized so that ``w = 1`` at the principal
    point; ``w > 0`` on the visible side of the vanishing line and ``w = 0`` on it.
    Near the frontal view the composition cancels terms of size ``f / sin theta``: the
    result is good to about ``1e-16 f / sin theta`` pixels (1e-6 px at 1e-6 degrees).
    """
    homography = upright_from_canonical(view, scale, anchor) @ canonical_from_pixel(view)
    principal_w = homography[2] @ np.array([view.cx, view.cy, 1.0])
    return homography / principal_w
