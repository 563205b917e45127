"""One square-pixel pinhole view as plain numbers: the check of a record that gives only
those, and its ``gsrwt params`` row by the :mod:`math` module alone.

No numpy: one ``gsrwt params --pan ... --tilt ... --focal ...`` in a shell loop starts in
half the time without it. The row is exactly (float for float, tested) what
:func:`~gsrwt_cli.tables.rows.params_row` gives for the :class:`~gsrwt_cli.geometry.camera.View`,
whose
:class:`~gsrwt_cli.geometry.gsrwt.GsrwtParameters` compute the same Sec. 4.5 formulas with the same
functions in the same order; any other view goes that way.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from .bounds import (
    DISTANCE_RANGE,
    FRONTAL_TOLERANCE_DEG,
    MAX_FOCAL_PX,
    MAX_PRINCIPAL_POINT_PX,
    MAX_SIDE_PX,
    MIN_HORIZON_OFFSET_PX,
)

#: The fields of a record of a square-pixel pinhole with no roll, the common case that
#: :func:`pinhole_numbers` reads (for tables of many views computed together, and for one
#: view given by options).
SIMPLE_PINHOLE_FIELDS = frozenset({"pan", "tilt", "focal", "cx", "cy", "width", "height",
                                   "distance"})


def _plain_number(where: str, name: str, raw: Any) -> float:
    """A plain Python int or float as a float; ValueError for anything else."""
    if type(raw) not in (int, float):
        raise ValueError(f"{where}, field {name!r}: not a plain number")
    return float(raw)  # OverflowError (an int beyond floating point) is an ArithmeticError


def pinhole_numbers(values: Mapping[str, Any], where: str,
                    number: Callable[[str, str, Any], float] = _plain_number,
                    ) -> tuple[float, ...] | None:
    """``(pan, tilt, focal, cx, cy, width, height)`` of a record that gives only
    :data:`SIMPLE_PINHOLE_FIELDS`, each well inside what
    :func:`~gsrwt_cli.inputs.records.view_from_values` accepts (``nan`` for an unknown principal
    point or size); None for any other record, whose view (or error) that gives. ASCII
    decimal text is read by ``float``, other values by ``number`` (which raises ValueError
    for what it does not take). The view's own last check (the horizon at least
    :data:`~gsrwt_cli.geometry.bounds.MIN_HORIZON_OFFSET_PX` from the principal point) is
    :func:`pinhole_params_row`'s."""
    given = {name: raw for name, raw in values.items() if raw is not None and raw != ""}
    if not given.keys() <= SIMPLE_PINHOLE_FIELDS or not {"pan", "tilt", "focal"} <= given.keys():
        return None
    found = {}
    for name, raw in given.items():
        try:
            # ASCII without underscores: what float() then reads is what the records read,
            # or not finite (refused below); any other text goes the long way.
            if type(raw) is str and raw.isascii() and "_" not in raw:
                found[name] = float(raw)
            else:
                found[name] = number(where, name, raw)
        except (ValueError, ArithmeticError):
            return None
    if not all(math.isfinite(value) for value in found.values()):
        return None
    pan, tilt, focal = found["pan"], found["tilt"], found["focal"]
    if not (abs(pan) < 90 and abs(tilt) < 90 and 0 < focal < MAX_FOCAL_PX):
        return None
    if not DISTANCE_RANGE[0] < found.get("distance", 1.0) < DISTANCE_RANGE[1]:
        return None
    size = found.get("width"), found.get("height")
    if any(side is not None and not (0 < side <= MAX_SIDE_PX and side == int(side))
           for side in size):
        return None
    centre = found.get("cx"), found.get("cy")
    if (centre[0] is None) != (centre[1] is None) or any(
            value is not None and abs(value) >= MAX_PRINCIPAL_POINT_PX for value in centre):
        return None
    if centre[0] is None and None not in size:
        centre = ((int(size[0]) - 1) / 2.0, (int(size[1]) - 1) / 2.0)  # as Intrinsics does
    return (pan, tilt, focal, *(math.nan if value is None else value for value in centre),
            *(math.nan if side is None else side for side in size))


def pinhole_params_row(numbers: tuple[float, ...], image: str | None = None
                       ) -> dict[str, Any] | None:
    """The ``params`` row of :func:`pinhole_numbers`' result (Sec. 4.5: theta Eq. 4.15,
    delta Eq. 4.14, gamma Eq. 4.18, a Eq. 4.16, the vanishing point and line Eq. 4.28-4.30,
    in pixels as ``x = cy - row, y = col - cx``); None when the horizon passes too close to
    the principal point (its view gives the error)."""
    pan, tilt, focal, cx, cy, width, height = numbers
    alpha, beta = math.radians(pan), math.radians(tilt)
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    frontal = abs(pan) <= FRONTAL_TOLERANCE_DEG and abs(tilt) <= FRONTAL_TOLERANCE_DEG
    foreshortening = ca * cb
    sin_theta = math.sqrt(sa * sa + ca * ca * sb * sb)
    if frontal:
        shift, delta_deg, gamma_deg, vp_x, vp_y = math.inf, 0.0, 0.0, math.inf, math.inf
    else:
        shift = focal * foreshortening / sin_theta
        if shift < MIN_HORIZON_OFFSET_PX:
            return None
        delta_deg = math.degrees(math.atan2(sa, ca * sb))
        gamma_deg = math.degrees(math.atan2(-sa * cb, sb))
        delta = math.radians(delta_deg)
        vp_x, vp_y = shift * math.cos(delta), shift * -math.sin(delta)
    row: dict[str, Any] = {
        "image": image, "pan_deg": pan, "tilt_deg": tilt, "focal_px": focal, "roll_deg": 0.0,
        "fx_px": focal, "fy_px": focal,
        "theta_deg": math.degrees(math.atan2(sin_theta, foreshortening)),
        "delta_deg": delta_deg, "a_px": shift, "gamma_deg": gamma_deg, "vp_x": vp_x,
        "vp_y": vp_y, "foreshortening": foreshortening,
    }
    line = None
    if not math.isnan(cx) and not frontal:
        # The image frame's line (-cos a sin b, sin a, f cos a cos b) in pixels, unit normal.
        a, b = sa, ca * sb
        c = cy * -b + -cx * a + focal * ca * cb
        norm = math.hypot(a, b)
        line = a / norm, b / norm, c / norm
    if math.isnan(width) or math.isnan(height):
        row["horizon_in_image"] = None
    else:
        row["horizon_in_image"] = line is not None and any(
            line[0] * col + line[1] * row_ + line[2] <= 0
            for col in (-0.5, width - 0.5) for row_ in (-0.5, height - 0.5))
    if not math.isnan(cx):
        row.update(vp_col=vp_y + cx, vp_row=cy - vp_x)
        if line is not None:
            row.update(vl_a=line[0], vl_b=line[1], vl_c=line[2])
    return row
