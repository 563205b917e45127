"""Gaze control and tracking on the wall (thesis Sec. 5.2.2-5.2.3): pan and tilt from wall points.

Wall coordinates here are for people: ``wall_x`` along the wall to the right, ``wall_y`` up,
from the foot of the perpendicular from the camera to the wall, in the unit of the distance
``Zc`` (the thesis's ``Y`` and ``X``). Angles are degrees, pan > 0 left, tilt > 0 up.
"""

from __future__ import annotations

import math

from .camera import View


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
    pixel of the default canonical view (``gsrwt rectify`` without --bbox or --scale).

    That view shows the fixation point at the principal point, one pixel per ``Zc/f`` wall
    units, upright (Eq. 4.25 and spec section 5): a vector measured on it, times ``Zc/f``, is
    a vector on the wall (the gaze control of Sec. 5.2.2).
    """
    distance = view.distance or 1.0
    fix_x, fix_y = fixation_point(view.pan, view.tilt, distance)
    unit = distance / view.focal
    return fix_x + (col - view.cx) * unit, fix_y + (view.cy - row) * unit


def canonical_pixel_of_wall_point(view: View, wall_x: float, wall_y: float) -> tuple[float, float]:
    """Inverse of :func:`wall_point_of_canonical_pixel`."""
    distance = view.distance or 1.0
    fix_x, fix_y = fixation_point(view.pan, view.tilt, distance)
    unit = distance / view.focal
    return view.cx + (wall_x - fix_x) / unit, view.cy - (wall_y - fix_y) / unit


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
