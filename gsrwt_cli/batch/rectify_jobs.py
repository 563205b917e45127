"""Batches: find the images, match their parameters, rectify them in worker processes.

Each image becomes a :class:`Job` in the main process (cheap: paths and parameter values),
and a table row in a worker (read, warp, write atomically). Only one image per worker is in
memory at a time; rows come back in input order. Every image gets a row that tells the truth,
whatever happens to it or to its worker.

Over 400 lines: the truthful row of every kind of job (done, skipped, failed, interrupted,
its worker dead) is the module's one job.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..api.rectify import plan_image
from ..base.messages import one_line, shorten
from ..geometry.camera import View
from ..geometry.framing import Plan
from ..geometry.orientation import displayed_size
from ..imaging.images import (
    DEFAULT_MAX_INPUT_PIXELS,
    Scratch,
    Working,
    canonical_extension,
    check_writable,
    file_orientation,
    image_file_size,
    measure_image_file,
    read_image,
)
from ..inputs.focal import exif_head, with_focal
from ..inputs.guides import parse_corners
from ..inputs.lensfun import lens_source_of, needs_exif, with_lens_profile
from ..inputs.parameters import Found, NotFound, Problem, resolve_parameters
from ..inputs.records import (
    RecordError,
    guided_view_values,
    guides_give_pose,
    view_from_values,
)
from ..inputs.sidecar import Sidecar
from ..inputs.sources import Source
from ..io.outputs import OutsideOutputError, check_inside, remove_stale_temporaries, write_atomic
from ..io.storage import Location, fetched, is_url, open_input
from ..tables.columns import RECTIFY_COLUMNS  # noqa: F401  (named here too)
from ..tables.rows import params_row, plan_row
from .executor import Executor, ProcessExecutor
from .in_order import run_in_order
from .job_errors import JobError, error_text
from .reruns import differences, is_regular_file, lens_word, made_with, record_of
from .settings import Describe, Settings  # noqa: F401  (named here too)
from .workers import ProcessWorker

# --------------------------------------------------------------------------------------------
# Jobs: one per image, with its parameters found in the main process
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Job:
    """Everything a worker needs for one image (picklable, small)."""

    source: Path | Location  # a local path, or a URL (:mod:`~gsrwt_cli.io.storage`)
    output: Path | Location
    values: dict[str, Any] | None  # raw parameters from the first source that has them
    where: str  # where the parameters came from, for messages
    error: str | None = None  # known before reading the image
    existed: bool = False  # the output existed when the run began
    #: sidecar, yaml, options, or estimated (from the image: ``rectify --auto``)
    pose_source: str | None = None
    estimate: Any = None  # the EstimateOptions of an estimated pose
    #: The previous table's row of an existing output, checked (:func:`~gsrwt_cli.batch.reruns.
    #: record_of`): what made the file that is there.
    record: dict[str, Any] | None = None


def pose_from_photo(job: Job) -> bool:
    """Whether the job's pose comes from its photo: estimated (``--auto``) or shown by guides
    (corners, verticals, horizontals) rather than given as numbers."""
    return job.pose_source == "estimated" or (job.values is not None
                                              and guides_give_pose(job.values))


def plan_jobs(
    sources: Iterable[Source],
    outdir: Path | Location,
    sidecar: Sidecar | None,
    fallback: dict[str, Any],
    extension: str | None,
    auto: Any = None,
) -> list[Job]:
    """One job per source; outputs mirror relative paths under ``outdir``.

    ``auto``: the :class:`~gsrwt_cli.batch.estimate_jobs.EstimateOptions` of images whose pose no
    source gives (``rectify --auto``): their pose is estimated from the image.

    An output whose directory leads out of ``outdir`` (through a symbolic link) is an error
    of its job, as is an output that another job also claims.
    """
    jobs = []
    claimed: dict[Path | Location, Path | Location] = {}
    # On an object store, which outputs exist is one listing, not a request per image.
    present = outdir.list_objects() if isinstance(outdir, Location) else None
    for source in sources:
        relative = Path(*source.relative.parts)
        if extension is not None:
            relative = relative.with_suffix(extension)
        output = outdir / relative
        pose_source = None
        match resolve_parameters(source.path, source.relative, sidecar, fallback,
                                 estimate=auto is not None):
            case Found(values=values, where=where, origin=origin):
                error, pose_source = None, origin.value.replace("adjacent ", "")
            case Problem(message=error, where=where):
                values = None
            case NotFound() as missing:
                values, where, error = None, "", missing.message
        if output in claimed:
            error = f"its output {output} is also the output of {claimed[output]}"
        claimed.setdefault(output, source.path)
        if error is None:
            try:
                check_inside(outdir, output)
            except OutsideOutputError as problem:
                error = f"its output {output} {problem}"
        if present is not None:
            existed = error is None and str(output) in present
        else:
            existed = error is None and os.path.lexists(output)
        jobs.append(Job(source.path, output, values, where, error, existed, pose_source,
                        auto if pose_source == "estimated" else None))
    return jobs


# --------------------------------------------------------------------------------------------
# One image: the work of a worker, and the rows the parent makes itself
# --------------------------------------------------------------------------------------------


def _orientation(job: Job, settings: Settings) -> int | None:
    """The EXIF orientation the job's image is rectified in (1-8: the photo as displayed),
    None with ``--orientation ignore`` (the stored pixels)."""
    if settings.orientation == "ignore":
        return None
    return file_orientation(job.source)


def _orientation_cell(orientation: int | None) -> str:
    """The ``orientation`` column: the EXIF value applied, or ``ignored``."""
    return "ignored" if orientation is None else str(orientation)


def _view(job: Job, estimate: bool = True, orientation: int | None = None,
          lens_profile: str = "auto", lens_from_lines: bool = False,
          max_input_pixels: float | None = None
          ) -> tuple[View, str, dict[str, Any], str | None]:
    """The job's view, where its focal length came from (EXIF read here if needed), its
    ``pose_source``, ``confidence``, ``aspect`` and ``aspect_source`` columns, and the
    corners of a rectangle its pose was found from (``--corners``, or those of a document
    found by ``--auto document``; None without). An estimated pose is estimated here
    (unless not ``estimate``: then it is an error). ``orientation``: the image's EXIF
    orientation, applied (the view of the displayed photo; None or 1: of the stored
    pixels). ``lens_profile``: ``--lens-profile``'s mode (:mod:`~gsrwt_cli.inputs.lensfun`).
    ``lens_from_lines``: a given pose's image without a lens gets k1 from its lines when they
    give it (:func:`_lens_from_lines`; an estimated pose's comes with the estimate); the
    image is then decoded here (at most ``max_input_pixels``)."""
    if job.error is not None:
        raise JobError(job.error)
    assert job.values is not None
    values = job.values
    if job.pose_source == "estimated":
        if not estimate:
            raise JobError("its pose was not estimated")
        from .estimate_jobs import (  # the estimator, only when asked for
            document_values,
            estimated_view_values,
        )

        if job.estimate.mode == "document":
            values = document_values(job.source, values, job.where, job.estimate)
        else:
            values, found, confidence, lens = estimated_view_values(
                job.source, values, job.where, job.estimate)
            try:
                view = view_from_values(values, job.where, orientation or 1)
            except RecordError as error:
                raise JobError(str(error)) from None
            return view, found, {"pose_source": "estimated", "confidence": confidence,
                                 **lens}, None
    head = exif_head(job.source) if needs_exif(values, lens_profile) else None  # one read
    values, source = with_focal(job.source, values, job.where, orientation or 1, head)
    values, lens_source, profile = with_lens_profile(
        head, image_file_size(job.source) if head is not None else None, values, lens_profile)
    guided = guides_give_pose(values)
    if lens_from_lines and lens_source == "none" and source is not None and not guided:
        values, lens_source, profile = _lens_from_lines(job, values, orientation or 1,
                                                        max_input_pixels)
    if source is None and not guided:
        raise JobError(
            "no focal length: none in the parameters, no camera file, and no usable "
            "focal length in the image's EXIF"
        )
    corners = values.get("corners")
    columns: dict[str, Any] = {"pose_source": job.pose_source, "lens_source": lens_source,
                               "lens_profile": profile}
    try:
        if guided:  # the pose the guides show; the focal length too when nothing gives one
            if values.get("width") in (None, "") and values.get("cx") in (None, ""):
                size = image_file_size(job.source)
                if size is not None:
                    values["width"], values["height"] = displayed_size(orientation or 1,
                                                                          *size)
            values, found = guided_view_values(values, job.where, orientation or 1)
            source = found.pop("focal_source", source)
            columns.update(found)
        return (view_from_values(values, job.where, orientation or 1), source, columns,
                None if corners in (None, "") else str(corners))
    except RecordError as error:
        reason = None
        if job.pose_source == "estimated":  # only by --auto document here: corners it found
            from .estimate_jobs import found_corners_reason

            reason = found_corners_reason(error)
        raise JobError(reason or str(error)) from None


def _lens_from_lines(job: Job, values: dict[str, Any], orientation: int,
                     max_input_pixels: float | None) -> tuple[dict[str, Any], str, str]:
    """``values`` (a pose given, no lens) with the k1 the image's lines give
    (:func:`~gsrwt_cli.api.lens_lines.lens_from_lines`) when the gate takes it; the
    ``lens_source`` (``lines`` or ``none``) and the ``lens_profile`` cell: the evidence, or
    why the lens was refused."""
    from ..api.lens_lines import lens_from_lines  # only when asked for

    try:
        view = view_from_values(values, job.where, orientation)
    except RecordError as error:
        raise JobError(str(error)) from None
    image = read_image(job.source, max_input_pixels or DEFAULT_MAX_INPUT_PIXELS, orientation)
    height, width = image.shape[:2]
    camera = view.with_size(width, height).intrinsics  # (the principal point: the centre)
    found = lens_from_lines(image, camera)
    del image
    if not found.taken:
        return values, "none", found.summary()
    return ({**values, "distortion_model": "plumb_bob", "k1": found.k1}, "lines",
            found.summary())


def _geometry(info: Plan) -> dict[str, Any]:
    return plan_row(info)


def _made_with(job: Job, settings: Settings) -> str | None:
    """The ``made_with`` cell of the job's output (:func:`~gsrwt_cli.batch.reruns.made_with`)."""
    estimate = job.estimate
    if estimate is not None and estimate.mode == "document":
        return made_with(job.values, None, settings, job.output.suffix, auto="document")
    return made_with(job.values, estimate.wall if estimate is not None else None, settings,
                     job.output.suffix)


def _lens_change(job: Job, mode: str, lens_from_lines: bool = False) -> str | None:
    """How the lens this run gives a recorded job differs from its record's (``lens_source
    none -> lensfun``), or None: a lens profile is found in the image's EXIF, not in the
    values ``made_with`` records, so a rerun looks it up again (the EXIF read only where
    lensfun may be asked: no lens given, the extra installed). ``mode``: ``--lens-profile``'s."""
    assert job.record is not None
    if job.values is None:
        return None
    if lens_from_lines or job.record.get("lens_source") == "lines":
        return None  # the lines' lens is the image's, with the flag ``made_with`` records
    recorded_source = job.record.get("lens_source") or None
    recorded = (recorded_source or "none", job.record.get("lens_profile") or "")
    if not needs_exif(job.values, mode):
        now = (lens_source_of(job.values) or "none", "")
    else:
        head = exif_head(job.source)
        values, _ = with_focal(job.source, job.values, job.where, 1, head)
        size = image_file_size(job.source) if head is not None else None
        _, source, profile = with_lens_profile(head, size, values, mode)
        now = (source, profile or "")
    if now == recorded or (recorded_source is None and now[0] != "lensfun"):
        return None  # (a table from before lens_source: only a profile found since counts)
    if now[0] != recorded[0]:
        return f"lens_source {recorded[0]} -> {now[0]}"
    return f"lens_profile {shorten(recorded[1] or 'none', 60)} -> {shorten(now[1], 60)}"


#: The error of an existing output that no record vouches for and these options do not make.
NOT_MADE_SO = ("its output exists, not made with these options (no valid row of the previous "
               "table records it); use --overwrite to redo it")
NOT_A_FILE = "its output exists and is not a regular file; remove it or use another -o"


def _framed(settings: Settings, text: str | None) -> Settings:
    """The settings of one image: with ``--bbox corners``, its corners (``text``, as
    ``--corners`` takes them) in the framing."""
    if settings.framing.bbox != "corners":
        return settings
    if text in (None, ""):
        raise JobError("--bbox corners needs the rectangle's corners (--corners, or a "
                       "corners column) for this image")
    corners = parse_corners(str(text))
    framing = replace(settings.framing, corners=tuple(map(tuple, corners.tolist())))
    return replace(settings, framing=framing)


def _plan(view: View, width: int, height: int, settings: Settings) -> Plan:
    return plan_image(view, width, height, settings.framing)


def metadata_record(info: Plan, orientation: int | None, input_size: tuple[int, int]
                    ) -> dict[str, str]:
    """What gsrwt did to an image, as the XMP properties of its output
    (:func:`~gsrwt_cli.io.metadata.xmp_packet`; docs/COMMANDS.md): the version, the pose, the
    camera (focal lengths and principal point in pixels of the displayed photo, the lens
    undone), the EXIF orientation applied, the sizes, and the homography (row-major, output
    pixel <- input pixel, after the lens; as the table's ``homography``)."""
    from .. import __version__

    view = info.view
    intrinsics = view.intrinsics
    number = "{:.12g}".format
    return {
        "Version": __version__,
        "Pan": number(view.pan), "Tilt": number(view.tilt), "Roll": number(view.roll),
        "Fx": number(intrinsics.fx), "Fy": number(intrinsics.fy),
        "Cx": number(intrinsics.cx), "Cy": number(intrinsics.cy),
        "Lens": lens_word(intrinsics.lens),
        "Orientation": _orientation_cell(orientation),
        "InputSize": "{}x{}".format(*input_size), "OutputSize": "{}x{}".format(*info.size),
        "Homography": plan_row(info)["homography"],
    }


def _encoded(warped: Working, job: Job, settings: Settings, scratch: Scratch, info: Plan,
             orientation: int | None, input_size: tuple[int, int]) -> tuple[bytes, str]:
    """The output's bytes (:meth:`~gsrwt_cli.imaging.images.Scratch.encode`) with the input's
    EXIF and gsrwt's record (:func:`~gsrwt_cli.io.metadata.with_metadata`; a JPEG's put into
    its header with its colour profile, in one insertion), and the row's ``metadata`` cell;
    without them when the input has none, its EXIF is damaged, or the output cannot hold
    it."""
    from ..io.metadata import (
        METADATA_FORMATS,
        DamagedExifError,
        MetadataError,
        jpeg_segments,
        with_metadata,
    )

    suffix, quality = job.output.suffix, settings.quality
    extension = canonical_extension(suffix)
    encoded = None
    if not settings.metadata:
        status = "stripped"
    elif scratch.exif_problem is not None:
        status = "damaged"
    elif scratch.exif is None:
        status = "none"
    elif extension not in METADATA_FORMATS:
        status = "unsupported"
    else:
        record = metadata_record(info, orientation, input_size)
        try:
            if extension == ".jpg":
                segments = jpeg_segments(info.size, scratch.exif, record)
                return scratch.encode(warped, suffix, quality, segments), "kept"
            encoded = scratch.encode(warped, suffix, quality)
            return with_metadata(encoded, extension, info.size, scratch.exif, record), "kept"
        except DamagedExifError:
            status = "damaged"
        except MetadataError:  # too large for the format
            status = "unsupported"
    if encoded is None:
        encoded = scratch.encode(warped, suffix, quality)
    return encoded, status


def process_job(job: Job, settings: Settings, scratch: Scratch | None = None) -> dict[str, Any]:
    """Rectify one image and return its table row; never raises for a bad image.

    ``scratch``: the worker's reusable memory (a fresh one if not given). Whatever goes
    wrong, from a bad parameter to an overflow deep in the geometry, becomes the row's
    ``error``; a result that is not finite is an error, never ``ok``.

    An output that existed when the run began (without ``overwrite``; one with a valid
    record of it never comes here) is made again in memory and compared with the file:
    ``skipped`` if it is the very file these options make, else an error; never rewritten.
    """
    scratch = scratch or Scratch()
    settings = settings.of_image(pose_from_photo(job))
    row: dict[str, Any] = {"image": str(job.source), "output": str(job.output)}
    checking = job.existed and not settings.overwrite and (  # gone since: made afresh
        os.path.lexists(job.output) if isinstance(job.output, Path) else job.output.exists())
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings(), fetched(job.source):
            warnings.simplefilter("ignore")
            orientation = _orientation(job, settings)
            view, source, pose, corners = _view(job, orientation=orientation,
                                                lens_profile=settings.lens_profile,
                                                lens_from_lines=settings.lens_from_lines,
                                                max_input_pixels=settings.max_input_pixels)
            row.update(params_row(view, str(job.source)), focal_source=source, **pose,
                       orientation=_orientation_cell(orientation))
            if checking and not is_regular_file(job.output):
                raise JobError(NOT_A_FILE)
            if not checking and job.output.exists() and not settings.overwrite:
                # Written since the run began: by this run's own earlier try of the job
                # (a worker that died after writing it, its task run again), so done.
                return record_row(job, settings, "ok")
            if not job.source.is_file():
                raise JobError("no such file" if not job.source.exists() else "not a file")
            width, height = displayed_size(
                orientation or 1, *measure_image_file(job.source, settings.max_input_pixels))
            info = _plan(view, width, height, _framed(settings, corners))  # big outputs refused
            # An antialiased output smaller than the input may come from a JPEG decoded
            # reduced in the DCT (Scratch.read); at scale 1 and above, never.
            preview = info.pixel_map if settings.antialias and info.frame.scale < 1 else None
            image = scratch.read(job.source, settings.max_input_pixels, orientation or 1,
                                 preview, exif=settings.metadata)
            dtype, channels = image.dtype, 1 if image.ndim == 2 else image.shape[2]
            del image  # the scratch holds it for the warp
            check_writable(
                job.output.suffix, dtype,
                4 if settings.alpha and channels in (1, 3) else channels, info.size,
            )
            if checking or not settings.dry_run:
                warped = scratch.warp(
                    info.pixel_map, settings.interpolation, settings.fill, settings.alpha,
                    settings.antialias,
                )
                encoded, row["metadata"] = _encoded(warped, job, settings, scratch, info,
                                                    orientation, (width, height))
                del warped
                if checking:
                    with open_input(job.output) as handle:
                        if handle.read(len(encoded) + 1) != encoded:
                            raise JobError(NOT_MADE_SO)
                else:
                    write_atomic(job.output, encoded, root=settings.root)
        row.update(_geometry(info), image=str(job.source), made_with=_made_with(job, settings),
                   status="skipped" if checking else "planned" if settings.dry_run else "ok")
    except Exception as error:  # every failure of one image is that image's row
        row.update(status="error", error=error_text(error, settings.describe))
    return row


def record_row(job: Job, settings: Settings, status: str = "ok") -> dict[str, Any]:
    """The full row of an image whose output this run wrote (its worker died or the run
    was stopped before the row came back), without decoding anything.

    The geometry comes from the input's header size and these settings; if the existing
    output's size disagrees with it, ``error`` says so.
    """
    settings = settings.of_image(pose_from_photo(job))
    row: dict[str, Any] = {"image": str(job.source), "output": str(job.output)}
    try:
        with np.errstate(all="ignore"):
            orientation = _orientation(job, settings)
            view, source, pose, corners = _view(job, orientation=orientation,
                                                lens_profile=settings.lens_profile)
            row.update(params_row(view, str(job.source)), focal_source=source, **pose,
                       orientation=_orientation_cell(orientation))
            size = displayed_size(orientation or 1,
                                  *measure_image_file(job.source, settings.max_input_pixels))
            info = _plan(view, size[0], size[1], _framed(settings, corners))
        row.update(_geometry(info), image=str(job.source), status=status,
                   made_with=_made_with(job, settings))
        existing = image_file_size(job.output)
        if existing is not None and existing != info.size:
            row["error"] = (
                f"the existing output is {existing[0]}x{existing[1]}, not the "
                f"{info.size[0]}x{info.size[1]} of these options; use --overwrite to redo it"
            )
    except Exception as error:
        row.update(status=status, error=f"output exists; its geometry is unknown: "
                   f"{error_text(error, settings.describe)}")
    return row


def died_row(job: Job, reason: str, settings: Settings) -> dict[str, Any]:
    """The row of an image whose worker died while working on it."""
    row: dict[str, Any] = {"image": str(job.source), "output": str(job.output)}
    with contextlib.suppress(Exception), np.errstate(all="ignore"):
        orientation = _orientation(job, settings)
        view, source, pose, _ = _view(job, estimate=False, orientation=orientation,
                                      lens_profile=settings.lens_profile)
        row.update(params_row(view, str(job.source)), focal_source=source, **pose,
                   orientation=_orientation_cell(orientation))
    row.update(status="error", error=reason)
    return row


def _written_before_it_stopped(job: Job, settings: Settings) -> bool:
    """Whether this run wrote the job's output (whole: writes are atomic) before its worker
    died or the run was stopped, so that the image was done after all."""
    return not job.existed and not settings.dry_run and job.output.exists()


def dead_worker_row(job: Job, reason: str, settings: Settings) -> dict[str, Any]:
    """The row of an image whose worker died: ``error``, unless it was done after all."""
    if _written_before_it_stopped(job, settings):
        return record_row(job, settings, status="ok")
    return died_row(job, reason, settings)


def interrupted_row(job: Job, settings: Settings) -> dict[str, Any]:
    """The row of an image the run did not finish: ``ok`` if it wrote its output whole
    before it stopped, else ``interrupted`` (an output that existed is not described: the
    next run checks it again)."""
    if _written_before_it_stopped(job, settings):
        return record_row(job, settings, status="ok")
    row = died_row(job, "not done: the run was interrupted", settings)
    row["status"] = "interrupted"
    return row


class ImageWorker(ProcessWorker):
    """One rectify worker's state: the settings and the memory reused from image to image."""

    def __init__(self, settings: Settings, opencv_threads: int = 0) -> None:
        super().__init__(opencv_threads)
        self.settings = settings
        self.scratch = Scratch()

    def __call__(self, job: Job) -> dict[str, Any]:
        return process_job(job, self.settings, self.scratch)


# --------------------------------------------------------------------------------------------
# The batch: jobs to workers, rows back in input order
# --------------------------------------------------------------------------------------------


def worker_context(fork_from_caller: bool = False) -> multiprocessing.context.BaseContext:
    """How workers start.

    By default they fork from a fresh server that has imported this module once, never from
    the caller, whose OpenCV thread pool a fork could leave locked (spawn where there is no
    forkserver). ``fork_from_caller`` forks the caller itself, which saves the server's start
    (0.2-0.4 s a run, measured): only for a process that has run no OpenCV code and started
    no thread, such as the ``gsrwt`` command before its pool.
    """
    methods = multiprocessing.get_all_start_methods()
    if fork_from_caller and "fork" in methods:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload([__name__])
        return context
    return multiprocessing.get_context("spawn")


@dataclass
class Counts:
    ok: int = 0
    skipped: int = 0
    failed: int = 0
    interrupted: int = 0
    planned: int = 0  # --dry-run: checked, not written

    def add(self, row: dict[str, Any]) -> None:
        if row["status"] == "ok":
            self.ok += 1
        elif row["status"] == "planned":
            self.planned += 1
        elif row["status"] == "skipped":
            self.skipped += 1
        elif row["status"] == "interrupted":
            self.interrupted += 1
        else:
            self.failed += 1


def _remove_temporaries_of(job: Job, pid: int) -> None:
    remove_stale_temporaries(job.output.parent, {pid})


def job_for_elsewhere(job: Job) -> Job:
    """The job with absolute paths (its image, output and calibration file), for a worker
    whose working directory is not ours (on a cluster's machines, sharing our file system)."""
    values = job.values
    camera = (values or {}).get("camera")
    if values is not None and camera and not is_url(camera) and not os.path.isabs(str(camera)):
        values = {**values, "camera": os.path.abspath(str(camera))}
    return replace(job, source=_absolute(job.source), output=_absolute(job.output),
                   values=values)


def _absolute(path: Path | Location) -> Path | Location:
    return path if isinstance(path, Location) else Path(os.path.abspath(path))


def row_for_here(job: Job, row: dict[str, Any]) -> dict[str, Any]:
    """A row made from :func:`job_for_elsewhere`'s job, naming the files as ``job`` does."""
    return {**row, "image": str(job.source), "output": str(job.output)}


def settings_for_elsewhere(settings: Settings) -> Settings:
    """The settings with an absolute output root (:func:`job_for_elsewhere`)."""
    root = None if settings.root is None else _absolute(settings.root)
    from_photo = settings.from_photo
    return replace(settings, root=root, from_photo=None if from_photo is None
                   else replace(from_photo, root=root))


def remove_temporaries_left(jobs: Iterable[Job]) -> None:
    """Remove what workers that died left half-written beside these jobs' outputs: the
    temporaries of their file names whose process is gone (workers on other machines
    write to object stores, or their temporaries are removed by the next run there)."""
    by_directory: dict[Path, set[str]] = {}
    for job in jobs:
        if not isinstance(job.output, Location):  # object stores have no temporaries
            by_directory.setdefault(job.output.parent, set()).add(job.output.name)
    for directory, names in by_directory.items():
        remove_stale_temporaries(directory, names=names)


def run_batch(
    jobs: list[Job],
    settings: Settings,
    processes: int,
    on_row: Callable[[dict[str, Any]], None],
    *,
    on_progress: Callable[[], None] | None = None,
    previous: Mapping[tuple[str, str], Mapping[str, Any]] | None = None,
    context: multiprocessing.context.BaseContext | None = None,
    executor: Executor[Job, dict[str, Any]] | None = None,
) -> Counts:
    """Run all jobs, handing each row to ``on_row`` in job order; returns the counts.

    Images are rectified by ``executor`` (default: ``processes`` worker processes of a
    :class:`~gsrwt_cli.batch.executor.ProcessExecutor`, where a worker that dies costs only its
    image, started as ``context`` says). Jobs known to fail, and images whose output exists
    (without ``overwrite``) with a valid record in ``previous`` (the last table's rows by
    ``(image, output)``, :func:`~gsrwt_cli.batch.reruns.record_of`), are rowed here, without a
    worker: the record, ``skipped`` if it was made with what this run asks for, else an
    error naming the differences. Other existing outputs are checked by a worker
    (:func:`process_job`). If the run is stopped (an exception such as
    ``KeyboardInterrupt``), the workers are stopped, every job not done gets its row
    (:func:`interrupted_row`), and the exception goes on.
    """
    counts = Counts()
    if not settings.overwrite:
        jobs = [replace(job, record=record_of(
                    (previous or {}).get((str(job.source), str(job.output))), job.output,
                    RECTIFY_COLUMNS)) if job.existed else job for job in jobs]

    def parent_row(index: int) -> dict[str, Any]:
        job = jobs[index]
        if job.record is None:
            return process_job(job, settings)
        change = (differences(job.record["made_with"],
                              _made_with(job, settings.of_image(pose_from_photo(job))) or "")
                  or _lens_change(job, settings.lens_profile, settings.lens_from_lines))
        if change is None:
            return {**job.record, "status": "skipped", "error": None}
        error = f"its output exists from a run with other options ({change}); use " \
                "--overwrite to redo it"
        return {**job.record, "status": "error", "error": one_line(error, 500)}

    def deliver(row: dict[str, Any]) -> None:
        counts.add(row)
        on_row(row)

    parent_jobs = {index for index, job in enumerate(jobs)
                   if job.error is not None or job.record is not None}
    worker_jobs = [index for index in range(len(jobs)) if index not in parent_jobs]
    if executor is None:
        executor = ProcessExecutor(
            ImageWorker.in_own_process, (settings, 1 if processes > 1 else 0),
            max(1, min(processes, len(worker_jobs))),
            on_death=lambda job, reason: dead_worker_row(job, reason, settings),
            on_abandon=_remove_temporaries_of,
            context=context or worker_context(),
        )
    run_in_order(
        len(jobs), executor.map_unordered([jobs[index] for index in worker_jobs]), deliver,
        lambda index: interrupted_row(jobs[index], settings), index_of=worker_jobs.__getitem__,
        parent=parent_jobs, parent_row=parent_row, on_progress=on_progress,
    )
    return counts

