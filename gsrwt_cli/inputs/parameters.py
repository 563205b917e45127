"""The camera parameters of one image, resolved in one place.

Sources, first match wins (fields it leaves out come from its defaults, then the options):

1. a row of the sidecar file (``--sidecar``), matched by relative path or unique file name;
2. ``NAME.yaml`` or ``NAME.EXT.yaml`` (or ``.yml``) beside the image: one record, or a
   sidecar mapping (as ``gsrwt render`` writes) that has the image; read by the same
   bounded YAML loader as sidecars;
3. the options (``--pan``, ``--tilt``, ``--focal`` at least).

The result is typed: :class:`Found` (values and where they came from), :class:`NotFound`
(the places looked at) or :class:`Problem` (a message naming its place). A fourth source,
asked for with ``estimate``: a pose estimated from the image, when no other source gives one
(``Origin.ESTIMATED``; the estimate itself is made where the image is read).
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from ..geometry.camera import View
from .guides import GUIDE_GIVERS, has_guides
from .records import NUMERIC_FIELDS, merge_values, view_from_values
from .sidecar import (
    Record,
    Sidecar,
    SidecarError,
    display_path,
    fields_of,
    load_yaml_file,
    sidecar_from_yaml,
)

#: The options that alone make a view: the pose; the focal length may come from --focal,
#: --fx/--fy, a --camera file or the image's EXIF.
REQUIRED_OPTIONS = ("pan", "tilt")
#: Fields that give a pose: pan/tilt, the GS-RWT's delta/a, solvePnP's rvec, a quaternion,
#: guides (:data:`~gsrwt_cli.inputs.guides.GUIDE_GIVERS`).
POSE_GIVERS = ("pan", "tilt", "delta", "a", "rvec_x", "qw", *GUIDE_GIVERS)


class Origin(enum.Enum):
    """Which kind of source gave an image its parameters."""

    SIDECAR = "sidecar"
    ADJACENT_YAML = "adjacent yaml"
    OPTIONS = "options"
    #: no source gives a pose: the values (intrinsics) are the options', and the pose is to
    #: be estimated from the image (``rectify --auto``, :mod:`~gsrwt_cli.batch.estimate_jobs`)
    ESTIMATED = "estimated"


@dataclass(frozen=True)
class Found:
    """Raw parameter values (numbers or numeric strings, not yet validated) and their place.

    ``where`` names the place for messages: ``views.csv line 4``, ``a.yaml``, ``options``.
    """

    values: dict[str, Any]
    where: str
    origin: Origin

    def view(self, orientation: int = 1) -> View:
        """Validate into a :class:`View` of the photo as its EXIF ``orientation`` displays it
        (:func:`~gsrwt_cli.inputs.records.view_from_values`); raises
        :class:`~gsrwt_cli.inputs.sidecar.RecordError`."""
        return view_from_values(self.values, self.where, orientation)


@dataclass(frozen=True)
class NotFound:
    """No source has the image; ``looked`` lists each place, e.g. ``not in views.csv``;
    ``sidecar`` names the sidecar looked in, if there was one."""

    looked: tuple[str, ...]
    sidecar: str | None = None

    @property
    def message(self) -> str:
        """``no parameters: not in views.csv, no a.yaml beside it, no --pan/--tilt; add it to
        views.csv, or estimate the pose with --auto``."""
        remedy = f"add it to {self.sidecar}" if self.sidecar else "give them in a --sidecar"
        return (f"no parameters: {', '.join(self.looked)}; {remedy}, or estimate the pose "
                "with --auto")


@dataclass(frozen=True)
class Problem:
    """A source that should have the image cannot be used; ``message`` names ``where``."""

    message: str
    where: str


Parameters = Found | NotFound | Problem


def adjacent_yaml(image: Path) -> Path | None:
    """``NAME.yaml`` or ``NAME.EXT.yaml`` (or ``.yml``) beside the image, if present."""
    for candidate in (
        image.with_suffix(".yaml"),
        image.with_name(image.name + ".yaml"),
        image.with_suffix(".yml"),
        image.with_name(image.name + ".yml"),
    ):
        if candidate.is_file():
            return candidate
    return None


def resolve_parameters(
    image: Path,
    relative: PurePosixPath | str,
    sidecar: Sidecar | None,
    fallback: Mapping[str, Any],
    estimate: bool = False,
) -> Parameters:
    """The parameters of ``image`` (``relative``: its path as a sidecar names it).

    ``fallback``: values from the options, which fill fields that the source leaves out
    and are the last source themselves when they give at least :data:`REQUIRED_OPTIONS`.
    ``estimate``: an image that no source gives a pose (:data:`POSE_GIVERS`) is
    ``Found`` with ``Origin.ESTIMATED`` and the values that source (or the options) gives.
    """
    found = _resolve(image, relative, sidecar, dict(fallback))
    if estimate and isinstance(found, NotFound):
        return Found(dict(fallback), "options", Origin.ESTIMATED)
    if estimate and isinstance(found, Found) and not any(
            found.values.get(name) not in (None, "") for name in POSE_GIVERS):
        return Found(found.values, found.where, Origin.ESTIMATED)
    return found


def _resolve(image: Path, relative: PurePosixPath | str, sidecar: Sidecar | None,
             fallback: dict[str, Any]) -> Parameters:
    if sidecar is not None:
        try:
            record = sidecar.find(PurePosixPath(relative).as_posix())
        except SidecarError as error:
            return Problem(str(error), display_path(sidecar.path))
        if record is not None:
            return Found(record.merged(fallback), record.where, Origin.SIDECAR)
    beside = adjacent_yaml(image)
    if beside is not None:
        return _from_adjacent_yaml(image, beside, fallback)
    if set(REQUIRED_OPTIONS) <= set(fallback) or has_guides(fallback):
        return Found(fallback, "options", Origin.OPTIONS)
    looked = []
    named = None if sidecar is None else display_path(sidecar.path)
    if named is not None:
        looked.append(f"not in {named}")
    looked.append(f"no {display_path(image.stem)}.yaml beside it")
    looked.append("no " + "/".join(f"--{name}" for name in REQUIRED_OPTIONS))
    return NotFound(tuple(looked), named)


def _from_adjacent_yaml(image: Path, beside: Path, fallback: dict[str, Any]) -> Parameters:
    """One record (fields at the top level), or a sidecar mapping that has the image."""
    where = display_path(beside)
    try:
        data = load_yaml_file(beside)
        if not isinstance(data, dict):
            return Problem(f"{where}: expected a mapping of field to value", where)
        fields = {name: value for name, value in fields_of(where, data).items()
                  if value is not None}
        if set(fields) & {*NUMERIC_FIELDS, *GUIDE_GIVERS}:  # one record: this image's parameters
            return Found(merge_values(fields, fallback), where, Origin.ADJACENT_YAML)
        record: Record | None = sidecar_from_yaml(beside, data).find(image.name)
    except SidecarError as error:
        return Problem(str(error), where)
    if record is None:
        return Problem(f"{where}: no record for {display_path(image.name)}", where)
    return Found(record.merged(fallback), record.where, Origin.ADJACENT_YAML)
