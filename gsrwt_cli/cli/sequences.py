"""``params``, ``estimate``, ``lines``, ``match`` and ``track`` on a video: the rows of each
frame, in frame order, with the frame's index and time in front.

Each command keeps its options and its per-image work; this module checks what a video run
needs (one video, PyAV, a pose file that reads), decodes the frames once, in this process
and one at a time (:func:`~gsrwt_cli.batch.frame_sequences.sequence_frames`), and writes the
rows as they come. A frame that cannot be decoded, has no pose within ``--max-pose-gap`` or
fails its command's work is an ``error`` row (and one ``Error:`` line on stderr); the others
go on; the exit status is 1 if any frame failed.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any

import click
import numpy as np

from ..base.messages import quote
from ..batch.frame_sequences import SequenceFrame, frame_canonical_view, sequence_frames
from ..batch.sequence_workers import FrameWork, rows_in_order
from ..inputs.bags import BAG_EXTENSIONS
from ..inputs.pose_log import PoseLog, load_pose_log
from ..inputs.sidecar import SidecarError
from ..inputs.videos import VIDEO_EXTENSIONS, VideoError, import_av, is_video_name
from .options import InputError, report_error

Row = dict[str, Any]


def video_input(inputs: Iterable[object]) -> str | None:
    """The video among the INPUTs (by its extension, :data:`VIDEO_EXTENSIONS`), or None when
    none is one; a usage error when a video is not the only INPUT, or when an INPUT is a ROS
    bag's file (:data:`~gsrwt_cli.inputs.bags.BAG_EXTENSIONS`), which only ``gsrwt rectify``
    reads. (A folder stays a folder of images here, whatever else it holds.)"""
    names = [str(name) for name in inputs]
    bags = [name for name in names
            if name != "-" and PurePath(name).suffix.lower() in BAG_EXTENSIONS]
    if bags:
        raise click.UsageError(
            f"{bags[0]}: {click.get_current_context().command_path} reads no ROS bags; gsrwt "
            f"rectify does, their poses from --pose-topic or --poses")
    videos = [name for name in names if name != "-" and is_video_name(name)]
    if not videos:
        return None
    if len(names) != 1:
        raise click.UsageError(
            f"a video is read frame by frame as the only INPUT, got {' '.join(map(quote, names))}")
    return videos[0]


def given_options(ctx: click.Context, names: Mapping[str, str]) -> dict[str, bool]:
    """Whether each option (its parameter's name: its flag in ``names``) was given by the
    user rather than left at its default, keyed by the flag."""
    given = {}
    for name, flag in names.items():
        source = ctx.get_parameter_source(name)
        given[flag] = source not in (None, click.core.ParameterSource.DEFAULT)
    return given


def refuse_for_video(video: str, given: Mapping[str, bool]) -> None:
    """A usage error, on one line, for the first option given that a video does not take."""
    for flag, was_given in given.items():
        if was_given:
            raise click.UsageError(f"{flag} does not apply to a video (INPUT {video})")


def refuse_poses_without_video(poses: str | None, frame_range: object = None) -> None:
    """A usage error for ``--poses`` or ``--frames`` given with still images (or no input)."""
    for flag, value in (("--poses", poses), ("--frames", frame_range)):
        if value is not None:
            raise click.UsageError(f"{flag} applies to a video INPUT (a file ending in "
                                   f"{', '.join(VIDEO_EXTENSIONS)})")


@dataclass(frozen=True)
class VideoRun:
    """A video run, checked: the video, its pose file (None without ``--poses``), how the
    pose file's times are read, and the options' view values (``fallback``)."""

    video: str
    poses: PoseLog | None
    time_mode: str = "relative"
    max_gap: float = 0.5
    fallback: Mapping[str, Any] = field(default_factory=dict)
    #: ``--frames``: (start, stop or None, step).
    frame_range: tuple[int, int | None, int] | None = None

    def frames(self) -> Iterator[SequenceFrame]:
        """The frames, decoded one at a time, with their view values."""
        return sequence_frames(Path(self.video), self.poses, time_mode=self.time_mode,
                               max_gap=self.max_gap, fallback=self.fallback,
                               frames=self.frame_range)


def open_video_run(video: str, poses: str | None, time_mode: str, max_gap: float,
                   fallback: Mapping[str, Any], needs_poses: str | None = None,
                   frame_range: tuple[int, int | None, int] | None = None) -> VideoRun:
    """Check a video run before its first frame: usage errors (exit 2) for a missing
    ``--poses`` (``needs_poses``: what the command needs them for), a bad ``--max-pose-gap``,
    a video that is no file, no PyAV, a pose file that cannot be read."""
    if poses is None and needs_poses is not None:
        raise click.UsageError(f"{video}: {needs_poses} needs --poses FILE (a pose per moment: "
                               "time, pan, tilt, ...; see docs/COMMANDS.md#videos)")
    if not (math.isfinite(max_gap) and max_gap >= 0):
        raise click.BadParameter("must be a number of seconds >= 0", param_hint="'--max-pose-gap'")
    path = Path(video)
    if not path.is_file():
        raise InputError(f"{video}: no such file" if not path.exists() else f"{video}: not a file")
    try:
        import_av()
    except VideoError as error:
        raise InputError(f"{video}: {error}") from None
    log = None
    if poses is not None:
        try:
            log = load_pose_log(poses)
            log.timeline(max_gap)  # two samples at the same time: refused before any work
        except SidecarError as error:
            raise InputError(f"--poses {error}") from None
    values = {name: value for name, value in fallback.items()
              if value is not None and not isinstance(value, bool)}
    return VideoRun(video, log, time_mode, max_gap, values, frame_range)


def frame_rows(run: VideoRun, work: FrameWork, processes: int = 1,
               context: Any = None) -> Iterator[Row]:
    """Every frame's rows, in frame order, with ``frame`` and ``time`` in front and the
    video as ``image``; a frame that failed (decoding, its pose, its work) is one ``error``
    row, reported on stderr. A file that is no video is one error row without a frame.
    ``processes`` > 1: the work is done by that many worker processes (``context``: how
    they start), the frames still decoded here."""
    try:
        for frame, rows in rows_in_order(run.frames(), work, processes, context):
            head: Row = {"frame": frame.index, "time": frame.time, "image": run.video}
            for row in rows:
                if row.get("status") == "error":
                    place = run.video if frame.end else f"{run.video} frame {frame.index}"
                    report_error(f"{place}: {row.get('error')}")
                yield {**head, **row}
    except VideoError as error:
        report_error(f"{run.video}: {error}")
        yield {"image": run.video, "status": "error", "error": str(error)}


def write_frame_rows(rows: Iterator[Row], write: Callable[[Row], None]) -> int:
    """Write every row; returns how many frames failed (rows with ``status`` ``error``)."""
    failed = 0
    for row in rows:
        failed += row.get("status") == "error"
        write(row)
    return failed


def print_frame_rows(run: VideoRun, work: FrameWork, columns: Sequence[str],
                     fmt: str | None) -> None:
    """Print every frame's rows on stdout as they come (``--format``); exit status 1 if
    any frame failed."""
    from ..tables.writer import TableWriter
    from .options import resolve_format

    writer = TableWriter(sys.stdout, tuple(columns), resolve_format(fmt))
    failed = write_frame_rows(frame_rows(run, work), writer.write_row)
    writer.close()
    if failed:
        sys.exit(1)


# --------------------------------------------------------------------------------------------
# The work of one frame, command by command
# --------------------------------------------------------------------------------------------


def params_work(run: VideoRun) -> FrameWork:
    """``params``: the GS-RWT parameters of the frame's view."""
    from ..tables.rows import params_row

    def work(frame: SequenceFrame) -> list[Row]:
        return [{**params_row(frame.view(), run.video), "status": "ok"}]
    return work


def estimate_work(run: VideoRun, options: Any) -> FrameWork:
    """``estimate``: the frame's pose from its lines, as a sidecar row with its evidence
    (``options``: :class:`~gsrwt_cli.batch.estimate_jobs.EstimateOptions`); the camera is the
    options' (``--focal``, ``--camera``...), or its focal length is estimated. Picklable, for
    ``-j``'s workers."""
    from ..batch.sequence_workers import EstimateFrames

    return EstimateFrames(options, {name: value for name, value in run.fallback.items()
                                    if name not in ("pan", "tilt", "roll")})


@dataclass(frozen=True)
class LineSearch:
    """``lines``' options: the edge threshold, the Hough transform's, the shortest segment
    (frontal pixels, or wall units when ``min_length_units`` is given) and the orientation."""

    edge_threshold: float
    theta_step: float
    min_votes: int
    max_gap: float
    min_length: float
    min_length_units: float | None
    orientation: str


def lines_work(run: VideoRun, search: LineSearch) -> FrameWork:
    """``lines``: the segments on the frame's frontal view (``none``: no segment)."""
    from ..tables.rows import line_row
    from ..vision.frontal_pixels import frontal_edges
    from ..vision.landmarks import grey8, hough_lines

    def work(frame: SequenceFrame) -> list[Row]:
        view = frame_canonical_view(Path(run.video), frame)
        shortest = search.min_length
        if search.min_length_units is not None:
            if view.units_per_pixel is None:
                raise ValueError("--min-length-units needs the camera-to-wall distance "
                                 "(--distance or a 'distance' column) and a pose")
            shortest = search.min_length_units / view.units_per_pixel
        edges = frontal_edges(grey8(view.pixels), view.pixel_map, view.source_size,
                              search.edge_threshold)
        found = hough_lines(view.pixels, edges=edges, theta_step_deg=search.theta_step,
                            min_votes=search.min_votes, max_gap=search.max_gap,
                            min_length=shortest, orientation=search.orientation)
        rows = [{**line_row(Path(run.video), line, view.to_source), "image": run.video,
                 "status": "ok"} for line in found]
        return rows or [{"status": "none"}]
    return work


@dataclass(frozen=True)
class TemplateSearch:
    """``match``'s and ``track``'s options: the templates (name, model), the scales, the
    lowest score, the matches per template and the edge threshold."""

    models: Sequence[tuple[str, Any]]
    scales: Sequence[float]
    min_score: float
    max_matches: int
    edge_threshold: float


def _matches(view: Any, search: TemplateSearch) -> Iterator[tuple[str, list[Any]]]:
    """Each template's matches on a frontal view (:class:`~gsrwt_cli.batch.canonical_views.
    CanonicalView`), as ``gsrwt match`` finds them on a still image."""
    from ..vision.frontal_pixels import frontal_edges
    from ..vision.ght import MATCH_ORIENTATION_SMOOTHING
    from ..vision.landmarks import grey8, match_template

    edges = frontal_edges(grey8(view.pixels), view.pixel_map, view.source_size,
                          search.edge_threshold, MATCH_ORIENTATION_SMOOTHING)
    for name, model in search.models:
        yield name, match_template(view.pixels, model, scales=search.scales, edges=edges,
                                   min_score=search.min_score, max_matches=search.max_matches)


def match_work(run: VideoRun, search: TemplateSearch) -> FrameWork:
    """``match``: each template's matches on the frame's frontal view (``none``: a template
    not found)."""
    from ..tables.rows import match_row

    def work(frame: SequenceFrame) -> list[Row]:
        view = frame_canonical_view(Path(run.video), frame)
        rows: list[Row] = []
        for name, found in _matches(view, search):
            rows += [{**match_row(Path(run.video), name, item, view.to_source),
                      "image": run.video, "status": "ok"} for item in found]
            if not found:
                rows.append({"template": name, "status": "none"})
        return rows
    return work


def track_work(run: VideoRun, search: TemplateSearch) -> FrameWork:
    """``track``: the landmark's best match on the frame's canonical view (its pose's), and
    the gaze command that centres it (:func:`~gsrwt_cli.geometry.gaze.gaze_at`, as ``gsrwt
    gaze --to-pixel`` computes it); ``lost`` when it is not found."""
    from ..geometry.gaze import gaze_at

    def work(frame: SequenceFrame) -> list[Row]:
        view = frame_canonical_view(Path(run.video), frame)
        name, found = next(_matches(view, search))
        if not found:
            return [{"template": name, "status": "lost",
                     "error": f"not found: no match scores {search.min_score:g} or more"}]
        best = found[0]
        row: Row = {"template": name, "x": best.x, "y": best.y, "scale": best.scale,
                    "score": best.score}
        source = view.to_source(np.array([[best.x, best.y]]))
        if source is not None:
            row.update(x_src=source[0, 0], y_src=source[0, 1])
        gaze = gaze_at(frame.view(), pixel=(best.x, best.y))
        row.update(pan_deg=gaze.pan_deg, tilt_deg=gaze.tilt_deg, wall_x=gaze.wall_x,
                   wall_y=gaze.wall_y, status="ok")
        return [row]
    return work


# --------------------------------------------------------------------------------------------
# The commands' video runs (the commands call these when INPUT is a video)
# --------------------------------------------------------------------------------------------

#: ``estimate``'s options that a video does not take: its parameter's name and its flag.
ESTIMATE_REFUSED = {"sidecar": "--sidecar", "recursive": "-r", "draw": "--draw",
                    "corners": "--corners", "aspect": "--aspect", "verticals": "--verticals",
                    "horizontals": "--horizontals", "fit": "--fit",
                    "exif_orientation": "--orientation", "lens_profile": "--lens-profile"}


def estimate_video(video: str, output: str, table_format: str, options: Any,
                   fallback: Mapping[str, Any], quiet: bool, jobs: int | None = None,
                   frame_range: tuple[int, int | None, int] | None = None) -> None:
    """``gsrwt estimate VIDEO``: every frame's pose from its lines, as sidecar rows with the
    frame and time in front (``options``: :class:`~gsrwt_cli.batch.estimate_jobs.
    EstimateOptions`), into ``output`` (``-``: stdout) as ``table_format``; ``jobs``: worker
    processes (default: the cores less one, the decoder's; 1: in this process)."""
    from ..batch.rectify_jobs import worker_context
    from ..inputs.sidecar import display_path
    from ..io.storage import location
    from ..io.targets import file_identity
    from ..tables.columns import ESTIMATE_SEQUENCE_COLUMNS
    from ..tables.writer import TableWriter, YamlRecordWriter
    from .batch_run import end_batch, open_table
    from .options import prepare_table

    ctx = click.get_current_context()
    refuse_for_video(video, given_options(ctx, ESTIMATE_REFUSED))
    if options.mode != "lines":
        raise click.UsageError(f"--auto {options.mode} does not apply to a video (INPUT {video})")
    run = open_video_run(video, None, "relative", 0.0, fallback, frame_range=frame_range)
    if output != "-" and file_identity(location(output)) == file_identity(Path(video)):
        raise InputError(f"-o {output}: would overwrite an input; choose another path")
    prepare_table(output, "-o")
    counts = {"ok": 0, "failed": 0}
    with open_table(output) as stream:
        writer: TableWriter | YamlRecordWriter = (
            YamlRecordWriter(stream, ESTIMATE_SEQUENCE_COLUMNS) if table_format == "yaml"
            else TableWriter(stream, ESTIMATE_SEQUENCE_COLUMNS, table_format))

        def write(row: Row) -> None:
            counts["ok" if row.get("status") == "ok" else "failed"] += 1
            writer.write_row(row)

        processes = jobs if jobs is not None else max(1, (os.cpu_count() or 1) - 1)
        write_frame_rows(frame_rows(run, estimate_work(run, options), processes,
                                    worker_context(False)), write)
        writer.close()
    end_batch(f"{counts['ok']} frames estimated, {counts['failed']} failed",
              "" if output == "-" else f"; table: {display_path(output)}", None,
              counts["failed"], quiet)
