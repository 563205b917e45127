"""``gsrwt params``: the GS-RWT parameter table of one view or of every row of a sidecar."""

from __future__ import annotations

import sys
from itertools import chain
from pathlib import Path
from typing import Any

import click

from .options import (
    InputError,
    PathOrUrl,
    format_option,
    guide_options,
    report_error,
    resolve_format,
    view_defaults,
    view_from_options,
    view_options,
)
from .sequence_options import frames_option, pose_file_options, video_argument


@click.command()
@video_argument
@view_options
@guide_options
@click.option(
    "--sidecar",
    type=PathOrUrl(dir_okay=False),
    help="CSV or YAML of views, one row per image (a path or a URL); options above fill "
         "fields it leaves out.",
)
@pose_file_options("the frame's view")
@frames_option
@format_option
def params(video: str | None, sidecar: Path | None, poses: str | None, time_mode: str,
           max_pose_gap: float, frame_range: tuple[int, int | None, int] | None,
           fmt: str | None, **kwargs: Any) -> None:
    """Print the GS-RWT parameters (theta, delta, a, gamma, vanishing point and line).

    For one view given by options, or for every row of a sidecar file. Rows are printed as
    they are computed; a row that is no valid view is reported on stderr (naming its line)
    and left out, and the command then exits with status 2. With a VIDEO and --poses: a row
    per frame (frame, time in front; status, error at the end), exit status 1 if any frame
    failed.

    \b
    Examples:
      gsrwt params --pan 15 --tilt 30 --focal 280 --width 320 --height 240
      gsrwt params --sidecar sample_data/views/views.csv --format json
    """
    from ..tables.writer import TableWriter

    if video is not None or poses is not None or frame_range is not None:
        _params_of_video(video, sidecar, poses, time_mode, max_pose_gap, fmt, kwargs,
                         frame_range)
        return
    defaults = view_defaults(kwargs)
    fmt = resolve_format(fmt)
    if sidecar is None:
        from ..geometry.pinhole import pinhole_numbers, pinhole_params_row
        from ..tables.columns import PARAMS_COLUMNS

        numbers = pinhole_numbers(defaults, "options")  # a plain pinhole: no numpy to load
        row = None if numbers is None else pinhole_params_row(numbers)
        if row is None:
            from ..tables.rows import params_row

            row = params_row(view_from_options(defaults))
        writer = TableWriter(sys.stdout, PARAMS_COLUMNS, fmt)
        writer.write_row(row)
        writer.close()
        return
    from ..inputs.records import RecordError
    from ..inputs.sidecar import SidecarError, iter_sidecar_chunks
    from ..tables.rows import PARAMS_COLUMNS, ParamsBlock, params_block, params_row, params_rows

    chunks = iter_sidecar_chunks(sidecar)
    try:
        first = next(chunks, None)  # a file that cannot be read at all prints no table
    except SidecarError as error:
        raise InputError(str(error)) from None
    writer = TableWriter(sys.stdout, PARAMS_COLUMNS, fmt, flush_rows=False)
    last_error, rows = None, []
    try:
        for chunk in chain([first] if first is not None else [], chunks):
            columns = chunk.text_columns()
            block = None if columns is None else params_block(columns, defaults)
            if block is not None:  # plain CSV rows: computed and written as columns
                writer.write_columns(block.columns, block.count)
                continue
            for row in params_rows((record.image, record.merged(defaults), record.where)
                                   for record in chunk.records()):
                if isinstance(row, ParamsBlock):
                    writer.write_rows(rows)
                    writer.write_columns(row.columns, row.count)
                    rows = []
                elif isinstance(row, RecordError):
                    if last_error is not None:
                        report_error(last_error)
                    last_error = str(row)
                else:
                    rows.append(row)
            writer.write_rows(rows)
            rows = []
    except SidecarError as error:
        writer.write_rows(rows)  # the rows before the fault
        writer.close()
        if last_error is not None:
            report_error(last_error)
        raise InputError(str(error)) from None
    writer.close()
    if last_error is not None:
        raise InputError(last_error)


def _params_of_video(video: str | None, sidecar: Path | None, poses: str | None,
                     time_mode: str, max_pose_gap: float, fmt: str | None,
                     kwargs: dict[str, Any],
                     frame_range: tuple[int, int | None, int] | None = None) -> None:
    """``gsrwt params VIDEO --poses FILE``: the parameters of every frame's view."""
    from ..tables.columns import PARAMS_SEQUENCE_COLUMNS
    from .sequences import (
        open_video_run,
        params_work,
        print_frame_rows,
        refuse_for_video,
        refuse_poses_without_video,
        video_input,
    )

    if video is None or video_input([video]) is None:
        if video is not None:
            raise click.UsageError(f"VIDEO {video}: not a video name (a file ending in .mp4, "
                                   ".mkv, .avi, .mov, .webm or .m4v)")
        refuse_poses_without_video(poses, frame_range)
    assert video is not None
    refuse_for_video(video, {"--sidecar": sidecar is not None})
    run = open_video_run(video, poses, time_mode, max_pose_gap, view_defaults(kwargs),
                         needs_poses="params", frame_range=frame_range)
    print_frame_rows(run, params_work(run), PARAMS_SEQUENCE_COLUMNS, fmt)
