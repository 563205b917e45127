"""Gaze control and tracking on the wall (thesis Sec. 5.2.2-5.2.3): pan and tilt from wall points.

Wall coordinates here are for people: ``wall_x`` along the wall to the right, ``wall_y`` up,
from the foot of the perpendicular from the camera to the wall, in the unit of the distance
``Zc`` (the thesis's ``Y`` and ``X``). Angles are degrees, pan > 0 left, tilt > 0 up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .camera import Pose, View


class GazeTargetError(ValueError):
    """A target the view cannot place on the wall: a ``target`` ("pixel" or "vector") needs
    the ``missing`` fields of the view."""

    def __init__(self, target: str, missing: tuple[str, ...], reason: str) -> None:
        super().__init__(f"a target {target} needs {reason}")
        self.target, self.missing = target, missing


@dataclass(frozen=True)
class Gaze:
    """Pan and tilt that put the wall point ``(wall_x, wall_y)`` on the optical axis."""

    pan_deg: float
    tilt_deg: float
    wall_x: float
    wall_y: float


@dataclass(frozen=True)
class TrackStep:
    """One position of the robot (Table 5.2): the aim at the object and the view it gives."""

    position: float
    pan_deg: float
    tilt_deg: float
    theta_deg: float
    foreshortening: float


def fixation_point(pan_deg: float, tilt_deg: float, distance: float = 1.0) -> tuple[float, float]:
    """``(wall_x, wall_y)`` where the optical axis meets the wall.

    The axis is the camera's forward direction ``(sin b, -sin a cos b, cos a cos b)`` (Eq. 3.8,
    X up, Y right), which meets ``Z = Zc`` at ``Y = -Zc tan a`` and ``X = Zc tan b / cos a``.
    """
    alpha, beta = math.radians(pan_deg), math.radians(tilt_deg)
    return -distance * math.tan(alpha), distance * math.tan(beta) / math.cos(alpha)


def pan_tilt_towards(wall_x: float, wall_y: float, distance: float = 1.0) -> tuple[float, float]:
    """Pan and tilt that put the wall point ``(wall_x, wall_y)`` on the optical axis.

    Inverts :func:`fixation_point`: pan turns towards the point's horizontal direction,
    ``tan a = -wall_x / Zc``, then tilt lifts the axis to it,
    ``tan b = wall_y / sqrt(wall_x^2 + Zc^2)``.
    """
    if not distance > 0:
        raise ValueError(f"distance must be positive, got {distance}")
    pan = math.degrees(math.atan2(-wall_x, distance))
    tilt = math.degrees(math.atan2(wall_y, math.hypot(wall_x, distance)))
    return pan, tilt


def wall_point_of_canonical_pixel(view: View, col: float, row: float) -> tuple[float, float]:
    """The wall point ``(wall_x, wall_y)`` (unit: ``view.distance``, or ``Zc = 1``) shown at a
    pixel of the default canonical view (what ``gsrwt rectify`` writes unless told otherwise).

    That view shows the fixation point at the principal point, one pixel per ``Zc/f`` wall
    units, upright (Eq. 4.25 scaled by ``f / sin theta``): a vector measured on it, times
    ``Zc/f``, is a vector on the wall (the gaze control of Sec. 5.2.2).
    """
    distance = view.distance or 1.0
    fix_x, fix_y = fixation_point(view.pan, view.tilt, distance)
    unit = distance / view.focal
    return fix_x + (col - view.cx) * unit, fix_y + (view.cy - row) * unit


def track(
    distance: float, height: float, object_position: float, robot_position: float
) -> tuple[float, float]:
    """Pan and tilt that keep an object centred while the robot drives along the wall.

    Sec. 5.2.3: the robot moves parallel to the wall at ``distance``; the object is at
    ``object_position`` along the wall, ``height`` above the camera, ahead of the robot (to the
    camera's left when it faces the wall) by ``object_position - robot_position``.
    """
    ahead = object_position - robot_position
    return pan_tilt_towards(-ahead, height, distance)


def gaze_at(view: View, pixel: tuple[float, float] | None = None,
            vector: tuple[float, float] | None = None) -> Gaze:
    """The gaze that centres a target: a ``pixel`` ``(col, row)`` of the view's default
    canonical view, or a ``vector`` ``(right, up)`` on the wall from the current fixation (in
    the unit of ``view.distance``); with neither, the current fixation itself.

    Raises :class:`GazeTargetError` when the view lacks what the target needs (a principal
    point for a pixel, a distance for a vector) and :class:`ValueError` for both targets.
    """
    if pixel is not None and vector is not None:
        raise ValueError("give a target pixel or a target vector, not both")
    distance = view.distance or 1.0
    if pixel is not None:
        if not view.has_principal_point:
            raise GazeTargetError("pixel", ("cx", "cy"),
                                  "the principal point (cx, cy, or the image size)")
        wall_x, wall_y = wall_point_of_canonical_pixel(view, *pixel)
    elif vector is not None:
        if view.distance is None:
            raise GazeTargetError("vector", ("distance",), "the distance (the vector's unit)")
        fix_x, fix_y = fixation_point(view.pan, view.tilt, distance)
        wall_x, wall_y = fix_x + vector[0], fix_y + vector[1]
    else:
        wall_x, wall_y = fixation_point(view.pan, view.tilt, distance)
    pan, tilt = pan_tilt_towards(wall_x, wall_y, distance)
    return Gaze(pan, tilt, wall_x, wall_y)


def track_steps(distance: float, height: float, object_position: float,
                robot_positions: list[float]) -> list[TrackStep]:
    """:func:`track` at each of ``robot_positions``, with the theta and foreshortening of the
    view it gives (thesis Sec. 5.2.3, Table 5.2)."""
    steps = []
    for position in robot_positions:
        pan, tilt = track(distance, height, object_position, position)
        pose = Pose(pan, tilt)
        steps.append(TrackStep(position, pan, tilt, pose.theta_deg, pose.foreshortening))
    return steps
