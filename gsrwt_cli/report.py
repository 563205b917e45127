"""The rows of the public tables: one dict per view with the documented column names."""

from __future__ import annotations

from typing import Any

from .camera import View

#: Columns of ``gsrwt params`` (a public contract, documented in the README).
PARAMS_COLUMNS = (
    "image",
    "pan_deg",
    "tilt_deg",
    "focal_px",
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
    row: dict[str, Any] = {
        "image": image,
        "pan_deg": view.pan,
        "tilt_deg": view.tilt,
        "focal_px": view.focal,
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
