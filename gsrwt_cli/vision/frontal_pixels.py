"""What a frontal view knows about its own pixels: which have a source, how magnified each is.

The edge stage of :mod:`.edges` (:func:`~.edges.line_edges`) takes both: no edges where the
view borders its fill (pixels with no source pixel), and gradients compensated for the
rectification's local magnification (thesis Sec. 5.1: the far side of an oblique wall is
stretched over many output pixels). Arrays out, from a
:class:`~gsrwt_cli.geometry.pixelmap.PixelMap`.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from ..geometry.gsrwt import local_stretch
from ..geometry.pixelmap import PixelMap
from .edges import (
    DEFAULT_LINE_THRESHOLD,
    DEFAULT_ORIENTATION_SMOOTHING,
    EdgeMap,
    grey_image,
    line_edges,
)

#: Output pixels between the points where the magnification is computed (then interpolated).
MAGNIFICATION_STEP = 16

#: Source pixels this close to the image's border count as unseen: real photos often have a
#: dark rim of a few pixels (OpenCV's chessboard photos do), an edge of no landmark.
SOURCE_MARGIN = 4


def seen(pixel_map: PixelMap, source_size: tuple[int, int],
         margin: int = SOURCE_MARGIN) -> NDArray[np.bool_]:
    """The output pixels of ``pixel_map`` whose source pixel lies in an image of
    ``source_size = (width, height)``, at least ``margin`` pixels inside its border: one
    nearest-neighbour warp of a constant image through the same map as the view (so lens,
    horizon and fill are exactly the view's)."""
    width, height = source_size
    ones = np.zeros((height, width), np.uint8)
    ones[margin:height - margin, margin:width - margin] = 255
    warped = pixel_map.warp(ones, cv2.INTER_NEAREST, (0.0, 0.0, 0.0, 0.0))
    return warped > 0


def magnification(pixel_map: PixelMap) -> NDArray[np.float32]:
    """Output pixels per source pixel (the largest singular value of the source-to-output
    Jacobian of the homography, :func:`~gsrwt_cli.geometry.gsrwt.local_stretch`) at every output
    pixel, computed every :data:`MAGNIFICATION_STEP` pixels and interpolated bilinearly. The
    lens is left out: near 1 over the frame, it changes the factor by a few percent."""
    width, height = pixel_map.size
    step = MAGNIFICATION_STEP
    cols = np.arange(0, width + step, step, dtype=np.float64)
    rows = np.arange(0, height + step, step, dtype=np.float64)
    grid = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
    homography = np.asarray(pixel_map.output_from_input, dtype=np.float64)
    inverse = np.linalg.inv(homography)
    homogeneous = grid @ inverse[:2, :2].T + inverse[:2, 2]
    w = grid @ inverse[2, :2] + inverse[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        sources = homogeneous / w[:, None]
        values = local_stretch(homography, sources)
    values = np.where((w > 0) & np.isfinite(values), values, 1.0)
    coarse = values.reshape(len(rows), len(cols)).astype(np.float32)
    # Output pixel (c, r) sits at coarse position (c / step, r / step).
    map_x, map_y = np.meshgrid(np.arange(width, dtype=np.float32) / step,
                               np.arange(height, dtype=np.float32) / step)
    return cv2.remap(coarse, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def frontal_edges(
    image: np.ndarray,
    pixel_map: PixelMap | None = None,
    source_size: tuple[int, int] | None = None,
    threshold: float = DEFAULT_LINE_THRESHOLD,
    orientation_smoothing: float = DEFAULT_ORIENTATION_SMOOTHING,
) -> EdgeMap:
    """The edge stage of ``gsrwt lines`` and ``gsrwt match`` on a frontal view ``image``:
    :func:`~.edges.line_edges` with the view's :func:`seen` pixels and :func:`magnification`
    when it was rectified through ``pixel_map`` from an image of ``source_size``
    (``orientation_smoothing``: ``gsrwt match`` takes
    :data:`~.ght.MATCH_ORIENTATION_SMOOTHING`)."""
    grey = grey_image(image)
    if pixel_map is None or source_size is None:
        return line_edges(grey, threshold, orientation_smoothing=orientation_smoothing)
    return line_edges(grey, threshold, valid=seen(pixel_map, source_size),
                      magnification=magnification(pixel_map),
                      orientation_smoothing=orientation_smoothing)
