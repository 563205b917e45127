"""``gsrwt estimate``: pan, tilt and roll of each image from its own lines, as sidecar rows."""

from __future__ import annotations

import os
import sys
from pathlib import Path, PurePosixPath
from typing import Any

import click

from ..api.estimate import DEFAULT_MIN_CONFIDENCE, WALL_CHOICES
from ..base.messages import one_line
from ..batch.estimate_jobs import AUTO_MODES, EstimateJob, EstimateOptions, run_estimates
from ..batch.rectify_jobs import worker_context
from ..inputs.calibration import CalibrationError
from ..inputs.records import load_camera_file
from ..inputs.sidecar import SidecarError, display_path
from ..io.storage import location
from ..io.targets import Drawings, file_identity, protected_files
from ..tables.columns import estimate_columns
from ..tables.writer import FORMATS, TableWriter, YamlRecordWriter, format_from_extension
from .options import (
    VIEW_OPTIONS,
    InputError,
    LocalPath,
    Number,
    PathOrUrl,
    auto_mode_command,
    check_lens_profile,
    field_options,
    guide_options,
    jobs_option,
    lens_from_lines_option,
    lens_profile_option,
    load_sidecar_option,
    make_output_directory,
    max_input_pixels_option,
    orientation_option,
    prepare_table,
    quiet_option,
    report_error,
    resolve_format,
    view_defaults,
)
from .rectify import (
    Terminated,
    collect_sources,
    end_batch,
    open_table,
    parse_pixel_count,
    progress_bar,
    stop_on_signals,
)
from .sequence_options import frames_option

#: The camera options of ``estimate`` (a pose is what it finds, so no --pan/--tilt/--roll).
CAMERA_OPTIONS = {
    "focal": (float, "Focal length in pixels (fx = fy) [default: from --camera, the sidecar, "
                     "EXIF, else estimated from the image]."),
    "fx": (float, "Horizontal focal length in pixels (with --fy)."),
    "fy": (float, "Vertical focal length in pixels (with --fx)."),
    "cx": VIEW_OPTIONS["cx"],
    "cy": VIEW_OPTIONS["cy"],
}


camera_options = field_options(
    CAMERA_OPTIONS, "Calibration file (OpenCV YAML/XML or ROS camera_info): intrinsics and "
    "lens (the lens is removed from the segments' end points).")


@click.command(cls=auto_mode_command(AUTO_MODES))
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option("-o", "--output", "output", default=None,
              help="Write the table to this file (.csv, .tsv, .json, .jsonl, .md, .yaml) "
                   "instead of stdout; it is a sidecar for 'gsrwt rectify --sidecar'.")
@click.option("--format", "-f", "fmt", type=click.Choice(FORMATS), default=None,
              help="Table format [default: from -o's extension; on stdout table on a "
                   "terminal, csv in a pipe].")
@click.option("-r", "--recursive", is_flag=True, help="Descend into directories.")
@click.option("--sidecar", type=PathOrUrl(dir_okay=False),
              help="CSV or YAML of per-image intrinsics (focal, cx, cy, camera, lens) or "
                   "guides (- for standard input); any pose in it is ignored.")
@camera_options
@guide_options
@click.option("--auto", type=click.Choice(AUTO_MODES), default="lines", show_default=True,
              help="How images without guides are estimated: from their lines, or "
                   "('--auto document') from the corners of the largest clear "
                   "quadrilateral of strong edges (a page, a sign, a screen), which the "
                   "'corners' column gives; refused when there is none.")
@click.option("--min-confidence", type=Number(0, 1), default=DEFAULT_MIN_CONFIDENCE,
              show_default=True,
              help="Estimates less confident than this are errors; the confidence is the "
                   "chance (0-1) that the pose is within 2 degrees, calibrated on real "
                   "photos. 0 keeps every estimate the image can make.")
@click.option("--wall", type=click.Choice(WALL_CHOICES), default="frontal", show_default=True,
              help="Which vertical plane is the wall: the most frontal (|pan| <= 45) or the "
                   "one with the most horizontal edges.")
@click.option("--draw", type=LocalPath(file_okay=False),
              help="Write a picture per image (DIR/NAME.png): segments by direction, the "
                   "horizon, the frontal view's outline.")
@max_input_pixels_option
@orientation_option
@lens_profile_option
@lens_from_lines_option
@jobs_option
@frames_option
@quiet_option("No summary on stderr.")
def estimate(inputs: tuple[str, ...], output: str | None, fmt: str | None, recursive: bool,
             sidecar: Path | None, auto: str, min_confidence: float, wall: str,
             draw: Path | None,
             max_input_pixels: str, exif_orientation: str, lens_profile: str,
             lens_from_lines: bool,
             jobs: int | None, frame_range: tuple[int, int | None, int] | None,
             quiet: bool, **camera: Any) -> None:
    """Estimate pan, tilt and roll of each image from its straight lines (thesis future work 1).

    Writes one sidecar row per image: image, pan, tilt, roll, focal, cx, cy, width,
    height (what 'gsrwt rectify --sidecar' reads), then confidence, segments, inliers,
    focal_source, focal_sd (an estimated or refined focal length's standard deviation, a
    fraction of it), aspect and aspect_source, the three vanishing points in pixels, status
    and error. With --lens-from-lines also lens_source, distortion_model and k1 (the lens the
    lines gave, which 'rectify --sidecar' reads back) and lens_lines (the evidence, or why
    the lens was refused). Images that cannot tell their pose get status error and no
    pose. With guides (--corners, --verticals, --horizontals) the pose is the one they
    show. A video as the only INPUT gives a row per frame (frame, time in front). Exit
    code 1 if any failed.

    \b
    Examples:
      gsrwt estimate sample_data/views/door_p20_t-8_f800.jpg --focal 800
      gsrwt estimate sample_data/views --sidecar sample_data/views/views.csv -o poses.csv
    """
    fork_workers = getattr(click.get_current_context().find_root().obj, "fork_workers", False)
    input_pixel_limit = parse_pixel_count(max_input_pixels, "--max-input-pixels")
    if output is not None and output != "-":
        table_format = fmt or format_from_extension(output) or ""
        if fmt is None and output.lower().endswith((".yaml", ".yml")):
            table_format = "yaml"  # a YAML sidecar
        elif table_format not in FORMATS or table_format == "table" and fmt is None:
            raise click.BadParameter("the table's name must end in .csv, .tsv, .json, .jsonl, "
                                     ".md or .yaml, or give --format", param_hint="'-o'")
    else:
        table_format, output = resolve_format(fmt), "-"
    from .sequences import refuse_poses_without_video, video_input

    video = video_input(inputs)
    if video is None:
        refuse_poses_without_video(None, frame_range)
    if video is not None:
        from .sequences import estimate_video

        check_lens_profile(lens_profile)
        if lens_from_lines:
            raise click.UsageError(f"{video}: --lens-from-lines does not apply to a video yet")
        estimate_video(video, output, table_format, EstimateOptions(
            min_confidence, wall, input_pixel_limit, exif_orientation, auto, lens_profile),
            view_defaults(camera), quiet, jobs, frame_range)
        return
    if str(sidecar) == "-" and "-" in inputs:
        raise InputError("--sidecar - and INPUT - cannot both read standard input")
    loaded = load_sidecar_option(sidecar)
    if camera.get("camera"):
        try:
            load_camera_file(str(camera["camera"]))
        except CalibrationError as error:
            raise InputError(str(error)) from None
    sources, unreadable = collect_sources(inputs, recursive)
    if not sources and not unreadable:
        raise InputError(f"no images found in {' '.join(inputs)}")
    given = protected_files([*(source.path for source in sources), sidecar])
    if output != "-" and file_identity(location(output)) in given:
        raise InputError(f"-o {output}: would overwrite an input; choose another path")
    prepare_table(output, "-o")
    drawings = None
    if draw is not None:
        make_output_directory("--draw", draw)
        drawings = Drawings(draw, [source.path for source in sources]
                            + ([sidecar] if sidecar else []))
    fallback = view_defaults(camera)
    job_list = []
    for source in sources:
        values, where, error = dict(fallback), "options", None
        if loaded is not None:
            try:
                record = loaded.find(PurePosixPath(source.relative).as_posix())
            except SidecarError as problem:
                record, error = None, str(problem)
            if record is not None:
                values, where = record.merged(fallback), record.where
        picture = None
        if drawings is not None and error is None:
            try:
                picture = drawings.target(source.path)
            except ValueError as problem:
                error = f"--draw: {problem}"
        job_list.append(EstimateJob(source.path, PurePosixPath(source.relative).as_posix(),
                                    values, where, picture, error))
    check_lens_profile(lens_profile)
    options = EstimateOptions(min_confidence, wall, input_pixel_limit, exif_orientation, auto,
                              lens_profile, lens_from_lines)
    for problem in unreadable:
        report_error(problem)
    counts = {"ok": 0, "failed": len(unreadable), "interrupted": 0}
    stopped: BaseException | None = None
    progress = progress_bar(quiet, total=len(job_list), unit="img")
    with stop_on_signals(), open_table(output) as stream:
        writer: TableWriter | YamlRecordWriter = (
            YamlRecordWriter(stream, estimate_columns(lens_from_lines))
            if table_format == "yaml"
            else TableWriter(stream, estimate_columns(lens_from_lines), table_format))

        def on_row(row: dict[str, Any]) -> None:
            writer.write_row(row)
            if row.get("status") == "ok":
                counts["ok"] += 1
            elif row.get("status") == "interrupted":
                counts["interrupted"] += 1
            else:
                counts["failed"] += 1
                progress.write(f"Error: {one_line(row['image'])}: {row.get('error')}",
                               file=sys.stderr)

        try:
            run_estimates(job_list, options, jobs or os.cpu_count() or 1, on_row,
                          picture_root=draw, context=worker_context(fork_workers),
                          on_progress=lambda: progress.update(1))
        except (KeyboardInterrupt, Terminated) as stop:
            stopped = stop  # every job has its row: the table is still written whole
        finally:
            progress.close()
        writer.close()
    summary = f"{counts['ok']} estimated, {counts['failed']} failed"
    if stopped is not None:
        summary += f", {counts['interrupted']} not done"
    end_batch(summary, "" if output == "-" else f"; table: {display_path(output)}", stopped,
              counts["failed"], quiet)
