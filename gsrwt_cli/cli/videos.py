"""``gsrwt rectify VIDEO --poses FILE``: a video rectified frame by frame, with a table row
per frame; and the run of any stream (a video, a bag: :mod:`.bags`).

The options are :mod:`.rectify`'s; this module checks what a video run needs (one video,
a pose file, a codec this FFmpeg encodes, options that make sense for a stream), and runs
it, or a bag's, with the same table, signals and last line as a directory batch
(:func:`run_stream_command`).
"""

from __future__ import annotations

import csv
import math
import os
import sys
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import click

from ..base.messages import one_line, quote
from ..batch.frame_sources import LogPoses, VideoSource
from ..batch.rectify_jobs import Counts, Settings, worker_context
from ..batch.reruns import made_with
from ..batch.sequence_workers import EstimatedPoses
from ..batch.video_jobs import (
    StreamJob,
    output_of,
    remove_video_temporaries,
    run_stream,
    takes_planes,
)
from ..inputs.pose_log import PoseLog, load_pose_log
from ..inputs.sidecar import SidecarError
from ..inputs.videos import VIDEO_EXTENSIONS, VideoError, import_av, is_video_name
from ..io.outputs import remove_stale_temporaries
from ..io.storage import Location
from ..io.targets import file_identity
from ..tables.columns import VIDEO_COLUMNS
from ..tables.writer import read_table
from .batch_run import Terminated, end_batch, progress_bar, recorded_rows, stop_on_signals
from .options import InputError, prepare_directory, prepare_table


def video_inputs(inputs: tuple[str, ...]) -> list[str]:
    """The INPUTs named as videos (by their extension, :data:`VIDEO_EXTENSIONS`)."""
    return [text for text in inputs if text != "-" and is_video_name(text)]


def check_video_request(inputs: tuple[str, ...], poses: str | None, auto: str | None,
                        refused: dict[str, bool]) -> None:
    """A usage error, on one line, for a video run that cannot be: a video without
    ``--poses`` (and ``--poses`` without one video), or options a video does not take
    (``refused``: the option's name and whether it was given)."""
    videos = video_inputs(inputs)
    if poses is not None and auto is not None:
        raise click.UsageError("use either --poses FILE or --auto for a video's poses, not both")
    if auto == "document":
        raise click.UsageError(f"{videos[0] if videos else inputs[0]}: --auto document does "
                               "not apply to a video; --auto lines estimates each frame's pose")
    if poses is None and auto is None:
        raise click.UsageError(f"{videos[0]}: a video needs --poses FILE (a pose per moment: "
                               "time, pan, tilt, ...; see docs/COMMANDS.md#videos) or --auto")
    if len(inputs) != 1 or len(videos) != 1:
        raise click.UsageError(
            f"{'--poses' if poses is not None else 'a video run'} takes one video as INPUT "
            f"(a file ending in {', '.join(VIDEO_EXTENSIONS)}), got "
            f"{' '.join(map(quote, inputs))}")
    for name, given in refused.items():
        if given:
            raise click.UsageError(f"{name} does not apply to a video (INPUT {inputs[0]})")


def _previous_rows(path: str, fmt: str, video: str) -> list[dict[str, Any]]:
    """The rows of ``video`` in the last run's table at ``path`` (none if unreadable)."""
    try:
        with open(path, encoding="utf-8", errors="surrogateescape", newline="") as stream:
            rows = read_table(stream, fmt)
    except (OSError, ValueError, csv.Error):
        return []
    return [row for row in rows if row.get("image") == video]


def _check_first_view(log: PoseLog, fallback: dict[str, Any], poses: str) -> None:
    """A usage error when the pose file's first sample and the options make no view (no
    focal length, say): every frame would fail alike."""
    from ..geometry.rotations import pose_from_rotation
    from ..inputs.records import RecordError, merge_values, view_from_values

    first = min(log.samples, key=lambda sample: sample.time)
    pose = pose_from_rotation(first.rotation)
    values = merge_values({**first.numbers, "pan": pose.pan, "tilt": pose.tilt,
                           "roll": pose.roll}, log.defaults, fallback)
    try:
        view_from_values(values, f"--poses {poses}")
    except RecordError as error:
        hint = (" (give --focal, or a focal column)" if error.field in ("focal", "fx")
                or "focal" in error.reason else "")
        raise InputError(f"{one_line(str(error), 300)}{hint}") from None


def rectify_video(inputs: tuple[str, ...], outdir: Path | Location, poses: str | None,
                  time_mode: str, max_gap: float, codec: str, settings: Settings,
                  table: Any, table_given: bool, run: Any,
                  view_kwargs: dict[str, Any], steady: bool = False,
                  estimating: Any = None, smooth: float = 0.0) -> None:
    """Check, run and end a video run (the command's exit status and last line): its poses
    from the pose file ``poses``, or estimated frame by frame (``estimating``: the
    :class:`~gsrwt_cli.batch.estimate_jobs.EstimateOptions` of ``--auto``), smoothed over
    ``smooth`` seconds."""
    if isinstance(outdir, Location):
        raise InputError(f"-o {outdir}: videos are written to a local directory only")
    if codec == "bag":
        raise click.BadParameter("bag writes a ROS bag's rectified topic: it needs a bag as "
                                 f"INPUT, not the video {inputs[0]}", param_hint="'--codec'")
    check_max_pose_gap(max_gap)
    source = Path(inputs[0])
    if not source.is_file():
        raise InputError(f"{inputs[0]}: no such file" if not source.exists()
                         else f"{inputs[0]}: not a file")
    try:
        import_av()
    except VideoError as error:
        raise InputError(f"{inputs[0]}: {error}") from None
    check_codec(codec, settings)
    fallback = view_fallback(view_kwargs)
    output = output_of(source, outdir, codec)
    words = stream_words(fallback, settings, codec, output)
    given = {file_identity(source)}
    frame_poses: LogPoses | EstimatedPoses
    if poses is not None:
        log = read_pose_log(poses, max_gap)
        _check_first_view(log, fallback, poses)
        words += f" poses=sha256:{log.digest} time={time_mode}"
        frame_poses = LogPoses(log, time_mode, max_gap, fallback, {})
        given.add(file_identity(Path(poses)))
    else:
        frame_poses = _estimated_poses(source, estimating, smooth, max_gap, fallback,
                                       settings, run)
        words += (f" auto=lines wall={estimating.wall} min_confidence="
                  f"{estimating.min_confidence:g} smooth={smooth:g}")
    words += f" max_pose_gap={max_gap:g} codec={codec}" + (" steady=on" if steady else "")
    job = StreamJob(source, output, codec, frame_poses,
                    partial(VideoSource, source, settings.max_input_pixels,
                            takes_planes(codec, settings)), words.strip(), steady)
    run_stream_command(job, outdir, settings, table, table_given, run, given)


def _estimated_poses(source: Path, estimating: Any, smooth: float, max_gap: float,
                     fallback: dict[str, Any], settings: Settings, run: Any) -> EstimatedPoses:
    """The poses of ``rectify VIDEO --auto``: each frame's estimate (on the ``-j`` workers,
    as ``gsrwt estimate VIDEO``), smoothed over ``smooth`` seconds."""
    from ..batch.frame_sequences import sequence_frames
    from ..batch.sequence_workers import EstimateFrames

    jobs = run.jobs if run.jobs is not None else max(1, (os.cpu_count() or 1) - 1)
    own = {name: value for name, value in fallback.items() if name not in ("pan", "tilt",
                                                                            "roll")}
    return EstimatedPoses(partial(sequence_frames, source,
                                  max_pixels=settings.max_input_pixels),
                          EstimateFrames(estimating, own), smooth, max_gap, fallback, jobs,
                          worker_context(False))


def check_max_pose_gap(max_gap: float) -> None:
    if not (math.isfinite(max_gap) and max_gap >= 0):
        raise click.BadParameter("must be a number of seconds >= 0", param_hint="'--max-pose-gap'")


def check_codec(codec: str, settings: Settings) -> None:
    """A usage error for a video codec this PyAV's FFmpeg lacks (needs PyAV), or for
    ``--alpha`` with a codec without alpha."""
    if codec in ("png", "bag"):
        return
    try:
        import_av()
    except VideoError as error:
        raise click.BadParameter(f"{codec} needs PyAV: {error}", param_hint="'--codec'"
                                 ) from None
    from ..imaging.videos import VIDEO_CODECS, codec_available

    if not codec_available(VIDEO_CODECS[codec]):
        raise click.BadParameter(f"this PyAV's FFmpeg has no {VIDEO_CODECS[codec].encoder} "
                                 "encoder; use --codec ffv1 or png", param_hint="'--codec'")
    if settings.alpha:
        raise click.UsageError(f"--alpha needs --codec png ({codec} has no alpha channel)")


def read_pose_log(poses: str, max_gap: float) -> PoseLog:
    """``--poses FILE`` read, two samples at the same time refused before any work."""
    try:
        log: PoseLog = load_pose_log(poses)
        log.timeline(max_gap)
    except SidecarError as error:
        raise InputError(f"--poses {one_line(str(error), 400)}") from None
    return log


def view_fallback(view_kwargs: dict[str, Any]) -> dict[str, Any]:
    """The view options given, as every frame's fallback values."""
    return {name: value for name, value in view_kwargs.items()
            if value is not None and not isinstance(value, bool)}


def stream_words(fallback: dict[str, Any], settings: Settings, codec: str,
                 output: Path) -> str:
    """The start of a stream's ``made_with``: its view options and settings."""
    return made_with(dict(fallback), None, settings, ".png" if codec in ("png", "bag") else
                     output.suffix) or ""


def run_stream_command(job: StreamJob, outdir: Path | Location, settings: Settings,
                       table: Any, table_given: bool, run: Any, given: set[str]) -> None:
    """Run a checked stream (a video, a bag) with its table, and end the command: what
    ``given`` (the inputs' identities) names is never overwritten."""
    assert isinstance(outdir, Path)
    source, output = job.source, job.output
    if not table_given:
        default = str(outdir / f"{source.stem if source.suffix else source.name}.csv")
        table = replace(table, path=default, format="csv", default=default)
    for target, what in ((output, f"-o {outdir}: output {output}"),
                         (Path(table.path), f"--table {table.path}")):
        if table.path != "-" and file_identity(target) in given:
            raise InputError(f"{what} would overwrite an input; choose another")
    if job.codec == "bag" and os.path.lexists(output) and output.is_dir() == (
            output.suffix == ".bag"):
        raise InputError(f"-o {outdir}: {output} exists and is not a "
                         f"{'file' if output.suffix == '.bag' else 'directory'} (a bag)")
    prepare_directory(outdir, f"-o {outdir}")
    prepare_table(table.path, "--table")
    remove_video_temporaries(job)
    if table.path != "-":  # the table of a killed run
        remove_stale_temporaries(Path(table.path).parent, names={Path(table.path).name})
    previous = _previous_rows(table.path if table.path != "-" else table.default,
                              table.format if table.path != "-" else "csv", str(source))
    if click.get_current_context().params.get("jobs") is None:
        # The main process decodes and encodes (its own core); the workers take the rest.
        # On two cores, warping in the main process beside the encoder's thread is fastest
        # (benchmarks/bench_video.py: 1.32 against 1.46 times PyAV alone with two workers).
        run = replace(run, jobs=max(1, (os.cpu_count() or 1) - 1))
    counts, stopped = _run(job, settings, table, run, previous)
    summary = f"{counts.ok} frames ok, {counts.skipped} skipped, {counts.failed} failed"
    if stopped is not None:
        summary += f", {counts.interrupted} not done"
    where = "" if table.path == "-" else f"; table: {table.path}"
    # a video whose every frame failed leaves no output: the line does not name one
    written = f"output: {output}" if os.path.lexists(output) else "no output written"
    end_batch(f"{summary}; {written}", where, stopped, counts.failed, run.quiet)


def _run(job: StreamJob, settings: Settings, table: Any, run: Any,
         previous: list[dict[str, Any]]) -> tuple[Counts, BaseException | None]:
    progress = progress_bar(run.quiet, unit="frame")
    counts = Counts()
    stopped: BaseException | None = None

    def place(row: dict[str, Any]) -> str:
        frame = row.get("frame")
        return row["image"] + (f" frame {frame}" if frame is not None else "")

    try:
        with stop_on_signals(), recorded_rows(
                table.path, VIDEO_COLUMNS, table.format, counts,
                lambda line: progress.write(line, file=sys.stderr), place) as on_row:
            try:
                run_stream(job, settings, run.jobs, on_row,
                           on_progress=lambda: progress.update(1), previous=previous,
                           context=worker_context(False))
            except (KeyboardInterrupt, Terminated) as stop:
                stopped = stop
    finally:
        progress.close()
    return counts, stopped
