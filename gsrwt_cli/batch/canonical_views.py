"""Canonical views of image files for landmark search: rectified if parameters are known.

``gsrwt lines`` and ``gsrwt match`` work on frontal views (thesis Sec. 5.2.2). An image with
camera parameters (the same sources as ``gsrwt rectify``) is rectified first, and what is
found there is mapped back to its own pixels; an image with none is taken as already frontal.
Views are 8-bit whatever the file's sample type (:func:`~gsrwt_cli.vision.edges.pixels8`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np

from ..api.rectify import rectify_image
from ..geometry.pixelmap import PixelMap
from ..imaging.images import ImageError, file_orientation, read_image
from ..inputs.parameters import NotFound, Problem, resolve_parameters
from ..inputs.records import RecordError
from ..inputs.sidecar import Sidecar
from ..vision.edges import pixels8


@dataclass(frozen=True)
class CanonicalView:
    """An image's frontal view and, when it was rectified, the map from source pixels to it."""

    path: Path
    pixels: np.ndarray
    pixel_map: PixelMap | None  # canonical from source pixels; None: frontal already
    source_size: tuple[int, int] | None = None  # (width, height) of the image rectified
    units_per_pixel: float | None = None  # wall units per canonical pixel, Zc / f if known

    def to_source(self, points: np.ndarray) -> np.ndarray | None:
        """``(N, 2)`` canonical pixels in the original image, or None if there is no map."""
        if self.pixel_map is None:
            return None
        return self.pixel_map.to_input(points)


def canonical_views(
    paths: list[Path], sidecar: Sidecar | None, fallback: dict[str, Any],
    orientation: str = "exif",
) -> Iterator[CanonicalView | tuple[Path, str]]:
    """Each image's canonical view, or ``(path, reason)`` when it cannot be read or rectified.

    ``orientation``: ``exif``, the photo as its EXIF orientation displays it (its parameters
    and the ``_src`` pixels are of that photo), or ``ignore``, the pixels as stored."""
    for path in paths:
        found = resolve_parameters(path, PurePosixPath(path.name), sidecar, fallback)
        try:
            turn = 1 if orientation == "ignore" else file_orientation(path)
            image = pixels8(read_image(path, orientation=turn))  # what the edges need
        except ImageError as error:
            yield path, str(error)
            continue
        if isinstance(found, NotFound):
            yield CanonicalView(path, image, None)
            continue
        if isinstance(found, Problem):
            yield path, found.message
            continue
        try:
            view = found.view(turn)
            frontal, info = rectify_image(image, view)
        except (RecordError, ValueError) as error:
            yield path, str(error)
            continue
        units = None if view.distance is None else view.distance / view.focal
        yield CanonicalView(path, frontal, info.pixel_map, (image.shape[1], image.shape[0]),
                            units)
