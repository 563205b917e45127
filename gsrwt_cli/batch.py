"""Batches: find the images, match their parameters, rectify them in worker processes.

Each image becomes a :class:`Job` in the main process (cheap: paths and parameter values),
and a table row in a worker (read, warp, write atomically). Only one image per worker is in
memory at a time; rows come back in input order.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

import cv2

from .camera import View
from .imaging import (
    IMAGE_EXTENSIONS,
    ImageError,
    Scratch,
    check_writable,
    encode_image,
)
from .outputs import write_atomic
from .parameters import Found, NotFound, Problem, resolve_parameters
from .rectify import plan_image
from .report import PARAMS_COLUMNS, params_row
from .sidecar import RecordError, Sidecar, view_from_values

RECTIFY_COLUMNS = (
    *PARAMS_COLUMNS,
    "output",
    "out_width",
    "out_height",
    "homography",
    "status",
    "error",
)


@dataclass(frozen=True)
class Source:
    """An input image and the relative path its output keeps."""

    path: Path
    relative: PurePosixPath


def is_image_name(path: Path) -> bool:
    return path.suffix.lower() in IMAGE_EXTENSIONS and not path.name.startswith(".")


def sources_from_directory(directory: Path, recursive: bool) -> list[Source]:
    """Images in a directory (sorted), with paths relative to it; hidden files are skipped."""
    if recursive:
        found = []
        for root, dirs, files in os.walk(directory):
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            found += [Path(root) / name for name in sorted(files)]
    else:
        found = sorted(p for p in directory.iterdir() if p.is_file())
    return [
        Source(p, PurePosixPath(p.relative_to(directory).as_posix()))
        for p in found
        if is_image_name(p)
    ]


def source_from_listed_path(text: str) -> Source:
    """A path read from standard input: relative paths keep their tree, others their name."""
    path = Path(text)
    pure = PurePosixPath(path.as_posix())
    if path.is_absolute() or ".." in pure.parts:
        return Source(path, PurePosixPath(path.name))
    return Source(path, PurePosixPath(*[part for part in pure.parts if part != "."]))


# --------------------------------------------------------------------------------------------
# Jobs: one per image, with its parameters found in the main process
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Job:
    """Everything a worker needs for one image (picklable, small)."""

    source: Path
    output: Path
    values: dict[str, Any] | None  # raw parameters from the first source that has them
    where: str  # where the parameters came from, for messages
    error: str | None = None  # known before reading the image


@dataclass(frozen=True)
class Settings:
    """The options of one ``gsrwt rectify`` run, shared by all workers."""

    bbox: str | tuple[float, float, float, float] = "frontal"
    scale: float = 1.0
    px_per_unit: float | None = None
    max_stretch: float = 4.0
    max_pixels: float = 50e6
    interpolation: str = "linear"
    fill: float = 0.0
    alpha: bool = False
    quality: int = 95
    overwrite: bool = False
    dry_run: bool = False
    threads_per_worker: int = 0  # 0: OpenCV's default


def plan_jobs(
    sources: Iterable[Source],
    outdir: Path,
    sidecar: Sidecar | None,
    fallback: dict[str, Any],
    extension: str | None,
) -> list[Job]:
    """One job per source; outputs mirror relative paths under ``outdir``."""
    jobs = []
    claimed: dict[Path, Path] = {}
    for source in sources:
        relative = Path(*source.relative.parts)
        if extension is not None:
            relative = relative.with_suffix(extension)
        output = outdir / relative
        match resolve_parameters(source.path, source.relative, sidecar, fallback):
            case Found(values=values, where=where):
                error = None
            case Problem(message=error, where=where):
                values = None
            case NotFound() as missing:
                values, where, error = None, "", missing.message
        if output in claimed:
            error = f"its output {output} is also the output of {claimed[output]}"
        claimed.setdefault(output, source.path)
        jobs.append(Job(source.path, output, values, where, error))
    return jobs


# --------------------------------------------------------------------------------------------
# Workers
# --------------------------------------------------------------------------------------------

_settings = Settings()
_scratch = Scratch()


def _init_worker(settings: Settings) -> None:
    global _settings, _scratch
    _settings, _scratch = settings, Scratch()
    if settings.threads_per_worker:
        cv2.setNumThreads(settings.threads_per_worker)


def _homography_text(matrix) -> str:
    return " ".join(f"{value:.12g}" for value in matrix.ravel())


def process_job(job: Job, settings: Settings | None = None) -> dict[str, Any]:
    """Rectify one image and return its table row; never raises for a bad image."""
    settings = settings or _settings
    row: dict[str, Any] = {"image": str(job.source), "output": str(job.output)}
    view: View | None = None
    try:
        if job.error is not None:
            raise _JobError(job.error)
        assert job.values is not None
        try:
            view = view_from_values(job.values, job.where)
        except RecordError as error:
            raise _JobError(str(error)) from None
        row.update(params_row(view, str(job.source)))
        if job.output.exists() and not settings.overwrite:
            row["status"] = "skipped"
            return row
        if not job.source.is_file():
            raise _JobError("no such file" if not job.source.exists() else "not a file")
        shape, dtype = _scratch.read(job.source)
        channels = 1 if len(shape) == 2 else shape[2]
        check_writable(
            job.output.suffix, dtype, 4 if settings.alpha and channels in (1, 3) else channels
        )
        info = plan_image(
            view,
            shape[1],
            shape[0],
            bbox=settings.bbox,
            scale=settings.scale,
            px_per_unit=settings.px_per_unit,
            max_stretch=settings.max_stretch,
            max_pixels=settings.max_pixels,
        )
        if not settings.dry_run:
            warped = _scratch.warp(
                info.homography, info.size, settings.interpolation, settings.fill,
                settings.alpha,
            )
            write_atomic(job.output, encode_image(warped, job.output.suffix, settings.quality))
        row.update(params_row(info.view, str(job.source)))
        row.update(
            out_width=info.size[0],
            out_height=info.size[1],
            homography=_homography_text(info.homography),
            status="ok",
        )
    except (_JobError, ImageError, ValueError, OSError) as error:
        row.update(status="error", error=_one_line(error))
    return row


class _JobError(Exception):
    pass


def _one_line(error: BaseException) -> str:
    if isinstance(error, OSError) and error.strerror:
        text = error.strerror + (f": {error.filename}" if error.filename else "")
    else:
        text = str(error)
    return " ".join(text.split())


def _worker_context(fork_from_caller: bool = False) -> multiprocessing.context.BaseContext:
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


def run_jobs(
    jobs: list[Job], settings: Settings, processes: int, fork_from_caller: bool = False
) -> Iterator[dict[str, Any]]:
    """Rows of all jobs, in job order, computed by ``processes`` worker processes
    (started as :func:`_worker_context` says)."""
    processes = max(1, min(processes, len(jobs)))
    if processes == 1:
        _init_worker(settings)
        for job in jobs:
            yield process_job(job, settings)
        return
    context = _worker_context(fork_from_caller)
    threads = Settings(**{**settings.__dict__, "threads_per_worker": 1})
    with context.Pool(processes, initializer=_init_worker, initargs=(threads,)) as pool:
        try:
            yield from pool.imap(process_job, jobs, chunksize=1)
        except BaseException:
            pool.terminate()
            raise


@dataclass
class Counts:
    ok: int = 0
    skipped: int = 0
    failed: int = 0

    def add(self, row: dict[str, Any]) -> None:
        if row["status"] == "ok":
            self.ok += 1
        elif row["status"] == "skipped":
            self.skipped += 1
        else:
            self.failed += 1


def run_batch(
    jobs: list[Job],
    settings: Settings,
    processes: int,
    on_row: Callable[[dict[str, Any]], None],
    fork_from_caller: bool = False,
) -> Counts:
    """Run all jobs, handing each row to ``on_row`` as it completes; returns the counts."""
    counts = Counts()
    for row in run_jobs(jobs, settings, processes, fork_from_caller):
        counts.add(row)
        on_row(row)
    return counts

