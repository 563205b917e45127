"""The rows of the public tables: one dict per view with the documented column names."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .camera import View
from .landmarks import Line, Match

#: Maps ``(N, 2)`` frontal-view pixels to the original image's, or gives None (no map).
ToSource = Callable[[np.ndarray], "np.ndarray | None"]

#: Columns of ``gsrwt params`` (a public contract, documented in the README).
PARAMS_COLUMNS = (
    "image",
    "pan_deg",
    "tilt_deg",
    "focal_px",
    "roll_deg",
    "fx_px",
    "fy_px",
    "theta_deg",
    "delta_deg",
    "a_px",
    "gamma_deg",
    "vp_x",
    "vp_y",
    "vp_col",
    "vp_row",
    "vl_a",
    "vl_b",
    "vl_c",
    "foreshortening",
    "horizon_in_image",
)


def params_row(view: View, image: str | None = None) -> dict[str, Any]:
    """The ``gsrwt params`` row of a view (Sec. 4.5; Table 5.1 and 5.2 quantities).

    Values that do not exist are ``None``: the vanishing point and line of a frontal view (at
    infinity), pixel coordinates when the principal point is unknown, ``horizon_in_image``
    when the image size is unknown.
    """
    parameters = view.parameters
    vp_x, vp_y = (float(v) for v in parameters.vanishing_point)
    if view.roll:  # the image frame of the rolled camera: the point turns with the roll
        rolled = view.pose.unrolled_from_rolled()[:2, :2].T @ np.array([vp_x, vp_y])
        vp_x, vp_y = (float(v) for v in rolled)
    row: dict[str, Any] = {
        "image": image,
        "pan_deg": view.pan,
        "tilt_deg": view.tilt,
        "focal_px": view.focal,
        "roll_deg": view.roll,
        "fx_px": view.intrinsics.fx,
        "fy_px": view.intrinsics.fy,
        "theta_deg": parameters.theta_deg,
        "delta_deg": parameters.delta_deg,
        "a_px": parameters.shift,
        "gamma_deg": parameters.gamma_deg,
        "vp_x": vp_x,
        "vp_y": vp_y,
        "foreshortening": parameters.foreshortening,
        "horizon_in_image": view.horizon_in_image(),
    }
    if view.has_principal_point:
        vp_col, vp_row = (float(v) for v in view.vanishing_point_pixels())
        row.update(vp_col=vp_col, vp_row=vp_row)
        line = view.vanishing_line_pixels()
        if line is not None:
            row.update(vl_a=float(line[0]), vl_b=float(line[1]), vl_c=float(line[2]))
    return row


#: Columns of ``gsrwt gaze`` and ``gsrwt track``.
GAZE_COLUMNS = ("pan_deg", "tilt_deg", "wall_x", "wall_y")
TRACK_COLUMNS = ("position", "pan_deg", "tilt_deg", "theta_deg", "foreshortening")

#: Columns of ``gsrwt lines`` and ``gsrwt match``.
LINES_COLUMNS = ("image", "rho", "theta_deg", "votes", "x1", "y1", "x2", "y2",
                 "x1_src", "y1_src", "x2_src", "y2_src", "length", "contrast")
MATCH_COLUMNS = ("image", "template", "x", "y", "scale", "votes", "score", "x_src", "y_src")


def line_row(image: Path, line: Line, to_source: ToSource) -> dict[str, Any]:
    """The ``gsrwt lines`` row of a line found on the frontal view of ``image``; the ``*_src``
    end points when ``to_source`` maps frontal pixels back to the image's."""
    row: dict[str, Any] = {"image": str(image), "rho": line.rho, "theta_deg": line.theta_deg,
                           "votes": line.votes, "x1": line.x1, "y1": line.y1, "x2": line.x2,
                           "y2": line.y2, "length": line.length, "contrast": line.contrast}
    source = to_source(np.array([[line.x1, line.y1], [line.x2, line.y2]]))
    if source is not None:
        row.update(x1_src=source[0, 0], y1_src=source[0, 1], x2_src=source[1, 0],
                   y2_src=source[1, 1])
    return row


def match_row(image: Path, template: str, match: Match, to_source: ToSource) -> dict[str, Any]:
    """The ``gsrwt match`` row of a ``template`` found on the frontal view of ``image``."""
    row: dict[str, Any] = {"image": str(image), "template": template, "x": match.x,
                           "y": match.y, "scale": match.scale, "votes": match.votes,
                           "score": match.score}
    source = to_source(np.array([[match.x, match.y]]))
    if source is not None:
        row.update(x_src=source[0, 0], y_src=source[0, 1])
    return row
