"""The forward model: what a camera at a given pan and tilt sees of a wall covered by a texture.

:func:`render_view` renders one view; :func:`plan_one_view` and :func:`plan_views` say which
views go to which files, :func:`render_views` renders and writes them, never over an input
or (unless asked) an existing file, and :func:`write_views_sidecar` writes the sidecar that
``gsrwt rectify`` reads back.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..base.messages import escape_controls, quote, shorten
from ..geometry.camera import View
from ..geometry.framing import render_map
from ..imaging.images import ImageError, check_writable, encode_image, warp_image
from ..inputs.records import RecordError, view_from_values
from ..inputs.sidecar import Record, format_sidecar
from ..io.outputs import (
    OutsideOutputError,
    relative_output,
    remove_stale_temporaries,
    write_atomic,
)
from ..io.targets import (
    DirectoryTargetError,
    NotADirectoryTargetError,
    UnwritableFileError,
    check_new_files,
    make_output_directory,
    output_target,
)


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
    (:func:`~gsrwt_cli.geometry.framing.render_map`). Backward mapping: every camera pixel
    looks up its texture pixel through the GS-RWT, i.e. the texture is warped by the inverse
    transform. Pixels that see no texture, or look above the wall's horizon, get ``fill``
    (transparent with ``alpha``).
    """
    height, width = texture.shape[:2]
    return warp_image(texture, render_map(view, (width, height)), interpolation, fill, alpha)


#: Characters of a sidecar row's description (``views.yaml record 'NAME'``) in a message.
WHERE_LIMIT = 160


@dataclass(frozen=True)
class RenderJob:
    """One view to render: the ``name`` its sidecar row gets, the view, the file to write."""

    name: str
    view: View
    target: Path


@dataclass(frozen=True)
class RenderPlan:
    """Views to render, where their sidecar goes, and the rows that cannot be rendered.

    ``root``: the directory every output stays inside (the sidecar's rows name files in it),
    or ``None`` for one file the user named, written where they said.
    """

    jobs: list[RenderJob]
    sidecar: Path
    root: Path | None = None
    errors: list[RecordError] = field(default_factory=list)


@dataclass(frozen=True)
class RenderResult:
    """What became of one job: ``error`` is ``None`` when its image was written."""

    job: RenderJob
    error: str | None = None


def plan_one_view(values: Mapping[str, Any], output: Path,
                  sidecar: Path | None = None) -> RenderPlan:
    """One view of ``values`` into the file ``output``; its sidecar ``OUTPUT-NAME.yaml`` unless
    ``sidecar`` is given. Raises :class:`DirectoryTargetError` and :class:`RecordError`."""
    if output.is_dir():
        raise DirectoryTargetError(output)
    view = view_from_values(values, "the given values")
    return RenderPlan([RenderJob(output.name, view, output)],
                      sidecar or output.with_suffix(".yaml"))


def plan_views(records: Iterable[Record], output: Path, fallback: Mapping[str, Any],
               sidecar: Path | None = None) -> RenderPlan:
    """The views of sidecar ``records`` into the directory ``output``, each at its ``image``;
    ``fallback`` fills what the records leave out, and their sidecar is ``sidecar`` (default
    ``OUTPUT/views.csv``). A row that cannot be rendered is a :class:`RecordError` in
    ``errors``; an ``output`` that is a file raises :class:`NotADirectoryTargetError`."""
    if output.exists() and not output.is_dir():
        raise NotADirectoryTargetError(output)
    sidecar = sidecar or output / "views.csv"
    plan = RenderPlan([], sidecar, root=output)
    claimed: dict[str, str] = {os.path.realpath(sidecar): "the views' sidecar"}
    for record in records:
        try:
            target = sidecar_target(output, record.image, claimed, record.where)
            plan.jobs.append(RenderJob(record.image, record.view(fallback), target))
        except RecordError as error:
            plan.errors.append(error)
    return plan


def sidecar_target(output: Path, image: str, claimed: dict[str, str], where: str) -> Path:
    """Where the sidecar row ``image`` is rendered: inside ``output``, or a :class:`RecordError`.

    The name must be relative, without ``..``, lead through no symbolic link out of
    ``output`` (:func:`~gsrwt_cli.io.targets.output_target`), and not be the file of an earlier row
    or
    of the views' sidecar: ``claimed`` maps the real paths taken so far to what took them.
    """
    where = shorten(escape_controls(where), WHERE_LIMIT)  # a YAML key may be any length
    try:
        target = output_target(output, relative_output(image))
    except OutsideOutputError as error:
        reason = str(error)
        verb = "is " if reason.startswith("not ") else ""
        raise RecordError(where, "image", f"{quote(image)} {verb}{reason}") from None
    real = os.path.realpath(target)
    if real in claimed:
        raise RecordError(where, "image",
                          f"{quote(image)} is the same file as {claimed[real]}; give another name")
    claimed[real] = where
    return target


def render_views(
    texture: np.ndarray,
    plan: RenderPlan,
    *,
    inputs: Iterable[Path] = (),
    overwrite: bool = False,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    quality: int = 95,
) -> Iterator[RenderResult]:
    """Render the plan's views of ``texture`` and write them, yielding each job's result.

    Before anything is written (here, not when the results are taken): no output, nor the
    sidecar, may be one of ``inputs`` (:class:`InputOverwriteError`) or exist unless
    ``overwrite`` (:class:`ExistingOutputError`); the plan's ``root`` is created
    (:class:`TargetError`). A view that cannot be rendered or written is a result with its
    error, and the others go on.
    """
    check_new_files([*(job.target for job in plan.jobs), plan.sidecar], inputs, overwrite)
    if plan.root is not None and plan.jobs:
        make_output_directory(plan.root)  # before the first write: the rule needs the root
    for directory in {job.target.parent for job in plan.jobs} | {plan.sidecar.parent}:
        remove_stale_temporaries(directory)  # what a killed earlier run left half-written
    return _render_each(texture, plan, interpolation, fill, alpha, quality)


def _render_each(texture: np.ndarray, plan: RenderPlan, interpolation: str, fill: float,
                 alpha: bool, quality: int) -> Iterator[RenderResult]:
    channels = 4 if alpha else (1 if texture.ndim == 2 else texture.shape[2])
    for job in plan.jobs:
        try:
            check_writable(job.target.suffix, texture.dtype, channels)
            image = render_view(texture, job.view, interpolation=interpolation, fill=fill,
                                alpha=alpha)
            write_atomic(job.target, encode_image(image, job.target.suffix, quality),
                         root=plan.root)
        except (ImageError, ValueError, OSError) as error:
            yield RenderResult(job, str(getattr(error, "strerror", None) or error))
            continue
        yield RenderResult(job)


def write_views_sidecar(path: Path, jobs: Iterable[RenderJob]) -> None:
    """Write the sidecar of the rendered ``jobs`` (CSV or YAML by ``path``'s extension).

    Raises :class:`~gsrwt_cli.inputs.sidecar.SidecarError` for an extension that is not a sidecar's
    and
    :class:`UnwritableFileError` when the file cannot be written.
    """
    rows = [{"image": job.name, **job.view.sidecar_values()} for job in jobs]
    text = format_sidecar(path, rows)
    try:
        write_atomic(path, text.encode("utf-8"))
    except OSError as error:
        raise UnwritableFileError(path, str(error.strerror or error)) from None
