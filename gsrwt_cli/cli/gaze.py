"""``gsrwt gaze`` and ``gsrwt track``: pan and tilt from targets on the wall (Sec. 5.2.2-5.2.3)."""

from __future__ import annotations

import sys
from typing import Any

import click

from ..gaze import (
    fixation_point,
    pan_tilt_towards,
    wall_point_of_canonical_pixel,
)
from ..gaze import (
    track as track_object,
)
from ..geometry import gsrwt_parameters
from ..messages import quote
from ..sidecar import RecordError, view_from_values
from ..tables import write_table
from .options import (
    InputError,
    format_option,
    option_message,
    resolve_format,
    view_defaults,
    view_options,
)

GAZE_COLUMNS = ("pan_deg", "tilt_deg", "wall_x", "wall_y")
TRACK_COLUMNS = ("position", "pan_deg", "tilt_deg", "theta_deg", "foreshortening")


def _pair(name: str, text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        first, second = (float(part) for part in text.split(","))
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
    try:
        view = view_from_values(view_defaults(kwargs), "options")
    except RecordError as error:
        raise InputError(option_message(error)) from None
    distance = view.distance or 1.0
    if pixel is not None:
        if not view.has_principal_point:
            raise InputError("--to-pixel needs the image size (--width --height) or --cx --cy")
        wall_x, wall_y = wall_point_of_canonical_pixel(view, *pixel)
    elif vector is not None:
        if view.distance is None:
            raise InputError("--to-vector needs --distance (the vector's unit)")
        fix_x, fix_y = fixation_point(view.pan, view.tilt, distance)
        wall_x, wall_y = fix_x + vector[0], fix_y + vector[1]
    else:
        wall_x, wall_y = fixation_point(view.pan, view.tilt, distance)
    pan, tilt = pan_tilt_towards(wall_x, wall_y, distance)
    row = {"pan_deg": pan, "tilt_deg": tilt, "wall_x": wall_x, "wall_y": wall_y}
    write_table(sys.stdout, GAZE_COLUMNS, [row], resolve_format(fmt))


@click.command()
@click.option("--distance", type=float, required=True,
              help="Distance from the robot's path to the wall.")
@click.option("--height", type=float, default=0.0, show_default=True,
              help="Height of the object above the camera (same unit).")
@click.option("--object", "object_position", type=float, required=True,
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
        points = [float(p) for p in positions.split(",") if p.strip()]
    except ValueError:
        raise click.BadParameter(f"expected numbers separated by commas, got {quote(positions)}",
                                 param_hint="'--positions'") from None
    rows = []
    for position in points:
        pan, tilt = track_object(distance, height, object_position, position)
        parameters = gsrwt_parameters(pan, tilt, 1.0)
        rows.append({"position": position, "pan_deg": pan, "tilt_deg": tilt,
                     "theta_deg": parameters.theta_deg,
                     "foreshortening": parameters.foreshortening})
    write_table(sys.stdout, TRACK_COLUMNS, rows, resolve_format(fmt))
