"""``gsrwt gaze`` and ``gsrwt track``: pan and tilt from targets on the wall (Sec. 5.2.2-5.2.3)."""

from __future__ import annotations

import sys
from dataclasses import asdict
from typing import Any

import click

from ..base.messages import quote
from ..base.numerals import parse_decimal
from ..geometry.gaze import GazeTargetError, gaze_at, track_steps
from ..tables.rows import GAZE_COLUMNS, TRACK_COLUMNS
from ..tables.writer import write_table
from .options import (
    InputError,
    Number,
    format_option,
    resolve_format,
    view_defaults,
    view_from_options,
    view_options,
)

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


@click.command()
@click.option("--distance", type=Number(), required=True,
              help="Distance from the robot's path to the wall.")
@click.option("--height", type=Number(), default=0.0, show_default=True,
              help="Height of the object above the camera (same unit).")
@click.option("--object", "object_position", type=Number(), required=True,
              help="Position of the object along the wall (same unit).")
@click.option("--positions", required=True, metavar="P1,P2,...",
              help="Robot positions along its path; the object is ahead by OBJECT - P.")
@format_option
def track(distance: float, height: float, object_position: float, positions: str,
          fmt: str | None) -> None:
    """Pan and tilt that keep an object centred as the robot drives along the wall.

    The robot moves parallel to the wall at --distance; for each of its --positions the
    camera aims at the object, and the table gives the view's theta and foreshortening
    (thesis Sec. 5.2.3, Table 5.2).

    \b
    Example:
      gsrwt track --distance 25 --height 9.5 --object 33 --positions 0,12,18
    """
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
