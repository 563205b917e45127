"""``gsrwt gaze`` and ``gsrwt track``: pan and tilt from targets on the wall (Sec. 5.2.2-5.2.3)."""

from __future__ import annotations

import functools
import sys
from dataclasses import asdict
from pathlib import Path
from typing import Any

import click
from click.core import ParameterSource

from ..base.messages import quote
from ..base.numerals import parse_decimal
from ..geometry.gaze import GazeTargetError, gaze_at, track_steps
from ..tables.rows import GAZE_COLUMNS, TRACK_COLUMNS
from ..tables.writer import write_table
from .options import (
    VIEW_OPTIONS,
    InputError,
    Integer,
    Number,
    PathOrUrl,
    edge_threshold_option,
    field_options,
    format_option,
    resolve_format,
    view_defaults,
    view_from_options,
    view_options,
)
from .sequence_options import frames_option, pose_file_options, video_argument

#: ``gsrwt match``'s default edge threshold (vision/ght.py's, repeated here so that the
#: light ``gaze`` and ``track`` load no numpy; tests/cli/test_sequences.py checks it).
DEFAULT_MATCH_THRESHOLD = 25.0

#: The option that gives each kind of target, and the options a view needs for it.
TARGET_OPTIONS = {"pixel": "--to-pixel", "vector": "--to-vector"}
NEEDED_OPTIONS = {"pixel": "the image size (--width --height) or --cx --cy",
                  "vector": "--distance (the vector's unit)"}


def _pair(name: str, text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        first, second = (parse_decimal(part) for part in text.split(","))
    except ValueError:
        raise click.BadParameter(f"expected two numbers A,B, got {quote(text)}",
                                 param_hint=f"'{name}'") from None
    return first, second


@click.command()
@view_options
@click.option("--to-pixel", metavar="COL,ROW",
              help="Target: a pixel of the current canonical view (gsrwt rectify's default).")
@click.option("--to-vector", metavar="RIGHT,UP",
              help="Target: a vector on the wall from the current fixation (unit of --distance).")
@format_option
def gaze(to_pixel: str | None, to_vector: str | None, fmt: str | None, **kwargs: Any) -> None:
    """Pan and tilt that centre a target seen on the canonical view, or, with no target,
    the wall point the camera looks at.

    wall_x runs along the wall to the right and wall_y up, from the foot of the perpendicular
    from the camera, in the unit of --distance (in units of the distance when it is not given).

    \b
    Examples:
      gsrwt gaze --pan 15 --tilt 30 --focal 280 --width 320 --height 240 --to-pixel 40,200
      gsrwt gaze --pan 15 --tilt 30 --focal 280 --distance 2.5
    """
    pixel, vector = _pair("--to-pixel", to_pixel), _pair("--to-vector", to_vector)
    if pixel is not None and vector is not None:
        raise click.UsageError("give --to-pixel or --to-vector, not both")
    view = view_from_options(view_defaults(kwargs))
    try:
        row = asdict(gaze_at(view, pixel, vector))
    except GazeTargetError as error:
        needed = NEEDED_OPTIONS[error.target]
        half_size = [f"--{name}" for name in ("width", "height") if kwargs.get(name) is None]
        if error.target == "pixel" and len(half_size) == 1:  # not the option already given
            needed = f"{half_size[0]} too (the image size), or --cx --cy"
        raise InputError(f"{TARGET_OPTIONS[error.target]} needs {needed}") from None
    write_table(sys.stdout, GAZE_COLUMNS, [row], resolve_format(fmt))


#: ``track VIDEO``'s camera options (the frame gives the image's size; no pose: --poses).
TRACK_CAMERA_OPTIONS = {name: VIEW_OPTIONS[name] for name in ("focal", "fx", "fy", "cx", "cy")}


@click.command()
@video_argument
@click.option("--distance", type=Number(), default=None,
              help="Distance from the robot's path to the wall [required without VIDEO; "
                   "with one: the unit of wall_x, wall_y].")
@click.option("--height", type=Number(), default=None,
              help="Height of the object above the camera (same unit) [default: 0].")
@click.option("--object", "object_position", type=Number(), default=None,
              help="Position of the object along the wall (same unit) [required without "
                   "VIDEO].")
@click.option("--positions", default=None, metavar="P1,P2,...",
              help="Robot positions along its path; the object is ahead by OBJECT - P "
                   "[required without VIDEO].")
@click.option("--template", type=PathOrUrl(dir_okay=False), default=None,
              help="With VIDEO: a frontal image of the landmark to follow (as for "
                   "gsrwt match).")
@field_options(TRACK_CAMERA_OPTIONS, "With VIDEO: calibration file (OpenCV YAML/XML or ROS "
               "camera_info) with the intrinsics and lens.")
@pose_file_options("each frame is rectified with its pose, the landmark found on that "
                   "canonical view")
@frames_option
@click.option("--scales", default="0.9,1.1", show_default=True, metavar="MIN,MAX",
              help="With VIDEO: scale range of the landmark (as for gsrwt match).")
@click.option("--scale-steps", type=Integer(min=1), default=5, show_default=True)
@click.option("--min-score", type=Number(0, 1), default=0.6, show_default=True,
              help="With VIDEO: a frame whose best match scores less is lost.")
@functools.partial(edge_threshold_option, default=DEFAULT_MATCH_THRESHOLD,
                   text="With VIDEO: high hysteresis threshold of the edges (as for gsrwt "
                        "match).")
@format_option
def track(video: str | None, distance: float | None, height: float | None,
          object_position: float | None, positions: str | None, template: Path | None,
          poses: str | None, time_mode: str, max_pose_gap: float, scales: str,
          scale_steps: int, min_score: float, edge_threshold: float,
          frame_range: tuple[int, int | None, int] | None, fmt: str | None,
          **camera: Any) -> None:
    """Pan and tilt that keep an object centred as the robot drives along the wall.

    The robot moves parallel to the wall at --distance; for each of its --positions the
    camera aims at the object, and the table gives the view's theta and foreshortening
    (thesis Sec. 5.2.3, Table 5.2).

    With a VIDEO, --poses and --template: the robot follows a landmark through the video.
    Each frame is rectified with its pose, the landmark found on its canonical view (the
    Generalized Hough Transform of gsrwt match), and the row gives where (x_src, y_src in
    the frame), its score, and the gaze command that centres it (pan_deg, tilt_deg, as
    gsrwt gaze --to-pixel computes it); status lost when it is not found.

    \b
    Example:
      gsrwt track --distance 25 --height 9.5 --object 33 --positions 0,12,18
    """
    ctx = click.get_current_context()
    if video is not None:
        _track_video(ctx, video, distance, height, object_position, positions, template,
                     poses, time_mode, max_pose_gap, scales, scale_steps, min_score,
                     edge_threshold, fmt, camera, frame_range)
        return
    video_options = {"template": "--template", "poses": "--poses", "camera": "--camera",
                     **{name: f"--{name}" for name in TRACK_CAMERA_OPTIONS},
                     "time_mode": "--time", "max_pose_gap": "--max-pose-gap",
                     "scales": "--scales", "scale_steps": "--scale-steps",
                     "min_score": "--min-score", "edge_threshold": "--edge-threshold",
                     "frame_range": "--frames"}
    for name, flag in video_options.items():
        if ctx.get_parameter_source(name) not in (None, ParameterSource.DEFAULT):
            raise click.UsageError(f"{flag} applies to a VIDEO only (gsrwt track VIDEO "
                                   "--poses FILE --template FILE)")
    for name, value in (("distance", distance), ("object_position", object_position),
                        ("positions", positions)):
        if value is None:
            param = next(p for p in ctx.command.params if p.name == name)
            raise click.MissingParameter(ctx=ctx, param=param)
    assert distance is not None and object_position is not None and positions is not None
    height = 0.0 if height is None else height
    if not distance > 0:
        raise click.BadParameter(f"must be positive, got {distance:g}", param_hint="'--distance'")
    try:
        points = [parse_decimal(p.strip()) for p in positions.split(",") if p.strip()]
    except ValueError:
        raise click.BadParameter(f"expected numbers separated by commas, got {quote(positions)}",
                                 param_hint="'--positions'") from None
    steps = track_steps(distance, height, object_position, points)
    rows = [asdict(step) for step in steps]
    write_table(sys.stdout, TRACK_COLUMNS, rows, resolve_format(fmt))


def _track_video(ctx: click.Context, video: str, distance: float | None, height: float | None,
                 object_position: float | None, positions: str | None, template: Path | None,
                 poses: str | None, time_mode: str, max_pose_gap: float, scales: str,
                 scale_steps: int, min_score: float, edge_threshold: float, fmt: str | None,
                 camera: dict[str, Any],
                 frame_range: tuple[int, int | None, int] | None = None) -> None:
    """``gsrwt track VIDEO --poses FILE --template FILE``: the landmark and its gaze command
    in every frame."""
    from ..tables.columns import TRACK_SEQUENCE_COLUMNS
    from .landmarks import _parse_scales, template_models
    from .sequences import (
        TemplateSearch,
        open_video_run,
        print_frame_rows,
        refuse_for_video,
        track_work,
        video_input,
    )

    if video_input([video]) is None:
        raise click.UsageError(f"VIDEO {video}: not a video name (a file ending in .mp4, "
                               ".mkv, .avi, .mov, .webm or .m4v)")
    refuse_for_video(video, {"--height": height is not None,
                             "--object": object_position is not None,
                             "--positions": positions is not None})
    if template is None:
        raise click.UsageError(f"{video}: track needs --template FILE (the landmark to follow)")
    fallback = view_defaults(camera)
    if distance is not None:
        if not distance > 0:
            raise click.BadParameter(f"must be positive, got {distance:g}",
                                     param_hint="'--distance'")
        fallback["distance"] = distance
    scale_list = _parse_scales(scales, scale_steps)
    run = open_video_run(video, poses, time_mode, max_pose_gap, fallback,
                         needs_poses="track", frame_range=frame_range)
    models = template_models([template], edge_threshold)
    search = TemplateSearch([(path.name, model) for path, model in models], scale_list,
                            min_score, 1, edge_threshold)
    print_frame_rows(run, track_work(run, search), TRACK_SEQUENCE_COLUMNS, fmt)
