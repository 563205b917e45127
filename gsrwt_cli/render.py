"""The forward model: what a camera at a given pan and tilt sees of a wall covered by a texture."""

from __future__ import annotations

import numpy as np

from .camera import View
from .framing import render_map
from .imaging import warp_image


def render_view(
    texture: np.ndarray,
    view: View,
    *,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
) -> np.ndarray:
    """The camera image of a wall covered by the frontal ``texture`` (inverse GS-RWT).

    ``view`` must know its image size. The texture's centre is at the foot of the
    perpendicular from the camera, one texture pixel per ``Zc/f`` wall units
    (:func:`~gsrwt_cli.framing.render_map`). Backward mapping: every camera pixel
    looks up its texture pixel through the GS-RWT, i.e. the texture is warped by the inverse
    transform. Pixels that see no texture, or look above the wall's horizon, get ``fill``
    (transparent with ``alpha``).
    """
    height, width = texture.shape[:2]
    return warp_image(texture, render_map(view, (width, height)), interpolation, fill, alpha)
