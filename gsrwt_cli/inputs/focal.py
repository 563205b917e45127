"""Where an image's focal length comes from: the values given for it, or its EXIF."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..geometry.orientation import displayed_size, swaps_sides
from ..imaging.images import image_file_size
from ..io.storage import Location, open_input
from .exif import ExifFocal, focal_from_exif


def focal_source(values: Mapping[str, Any], where: str) -> str | None:
    """Where a job's focal length comes from: ``option``, ``sidecar`` (a sidecar row or the
    YAML beside the image), ``camera`` (a calibration file), or None: nowhere yet (EXIF)."""
    if any(values.get(name) not in (None, "") for name in ("focal", "fx", "fy", "focal_mm")):
        return "option" if where == "options" else "sidecar"
    if values.get("camera"):
        return "camera"
    return None


def exif_head(path: Path | Location) -> bytes | None:
    """The first MB of an image file, where its EXIF lives (the first 64 KB segment); None
    when it cannot be read. Read once per image for its focal length and its lens."""
    try:
        with open_input(path) as handle:
            return handle.read(1 << 20)
    except OSError:
        return None


def exif_focal(path: Path | Location, orientation: int = 1, head: bytes | None = None
               ) -> ExifFocal | None:
    """The focal length the image's EXIF gives (:func:`~gsrwt_cli.inputs.exif.focal_from_exif`),
    for the photo as its EXIF ``orientation`` displays it: the tags describe the stored
    pixels, so 5-8 swap ``fx`` and ``fy`` (the 35 mm-equivalent, by the diagonal, is the same
    either way); 1: as stored. ``head``: the file's first bytes, when already read
    (:func:`exif_head`)."""
    try:
        size = image_file_size(path)  # the stored pixels', which the EXIF tags describe
    except OSError:
        return None
    if size is None:
        return None
    head = exif_head(path) if head is None else head
    if head is None:
        return None
    found = focal_from_exif(head, *size)
    if found is None or not swaps_sides(orientation):
        return found
    return ExifFocal((found.fy, found.fx), f"{found.source}; turned by EXIF orientation "
                     f"{orientation}")


def with_focal(path: Path | Location, values: Mapping[str, Any], where: str,
               orientation: int = 1, head: bytes | None = None
               ) -> tuple[dict[str, Any], str | None]:
    """An image's values with its focal length resolved, the one way every command does it:
    the values' own (:func:`focal_source`), else the image's EXIF (``fx``, ``fy`` added;
    source ``exif``); a focal length in millimetres gets the image's size, which it needs.
    Sizes are those of the photo as its EXIF ``orientation`` displays it (1: as stored).
    Returns the values and the source, None when nothing gives a focal length. ``head``:
    the file's first bytes, when already read (:func:`exif_head`)."""
    values = dict(values)
    source = focal_source(values, where)
    if values.get("focal_mm") not in (None, "") and values.get("width") in (None, ""):
        size = image_file_size(path)  # millimetres become pixels with the image's size
        if size is not None:
            values["width"], values["height"] = displayed_size(orientation, *size)
    if source is None:
        found = exif_focal(path, orientation, head)
        if found is not None:
            values["fx"], values["fy"], source = found.fx, found.fy, "exif"
    return values, source
