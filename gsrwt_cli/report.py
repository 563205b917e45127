"""The rows of the public tables: one dict per view with the documented column names."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from itertools import islice
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .camera import MIN_HORIZON_OFFSET_PX, View
from .geometry import parameter_arrays
from .records import RecordError, simple_pinhole_numbers, view_from_values

if TYPE_CHECKING:
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


#: Views whose ``params`` rows are computed together: a first row out in milliseconds, and
#: memory that does not grow with the number of rows.
PARAMS_CHUNK = 2048


def params_rows(
    records: Iterable[tuple[str | None, Mapping[str, Any], str]],
) -> Iterator[dict[str, Any] | RecordError]:
    """:func:`params_row` of each ``(image, values, where)``, in order, or the
    :class:`~gsrwt_cli.records.RecordError` of a record that is no valid view.

    Square-pixel pinhole records (:func:`~gsrwt_cli.records.simple_pinhole_numbers`) are
    computed :data:`PARAMS_CHUNK` at a time by :func:`~gsrwt_cli.geometry.parameter_arrays`,
    exactly as their views would compute them; any other through its view.
    """
    records = iter(records)
    while chunk := list(islice(records, PARAMS_CHUNK)):
        numbers = [simple_pinhole_numbers(values, where) for _, values, where in chunk]
        simple = [index for index, found in enumerate(numbers) if found is not None]
        rows: dict[int, dict[str, Any]] = {}
        if simple:
            table = np.array([numbers[index] for index in simple], dtype=np.float64)
            for index, row in zip(simple, _simple_pinhole_rows(table)):
                if row is not None:
                    rows[index] = row
        for index, (image, values, where) in enumerate(chunk):
            if index in rows:
                yield {"image": image, **rows[index]}
                continue
            try:
                yield params_row(view_from_values(values, where), image)
            except RecordError as error:
                yield error


def _simple_pinhole_rows(table: np.ndarray) -> list[dict[str, Any] | None]:
    """The :func:`params_row` columns of square-pixel pinholes given as rows ``(pan, tilt,
    focal, cx, cy, width, height)`` (``nan``: unknown); None for a view whose horizon is too
    close to its principal point (its view gives the error)."""
    pan, tilt, focal, cx, cy, width, height = table.T
    found = parameter_arrays(pan, tilt, focal)
    frontal, shift = found["frontal"], found["shift"]
    # The vanishing point and line in pixels: x = cy - row, y = col - cx (square pixels).
    vp_col, vp_row = found["vp_y"] + cx, cy - found["vp_x"]
    line_a, line_b = found["line_b"], -found["line_a"]
    line_c = cy * found["line_a"] + -cx * found["line_b"] + found["line_c"]
    with np.errstate(invalid="ignore", divide="ignore"):
        norm = np.fromiter(map(math.hypot, line_a.tolist(), line_b.tolist()), np.float64,
                           count=len(table))
        line_a, line_b, line_c = line_a / norm, line_b / norm, line_c / norm
        crosses = np.zeros(len(table), dtype=bool)
        for col in (-0.5, width - 0.5):
            for row in (-0.5, height - 0.5):
                crosses |= line_a * col + line_b * row + line_c <= 0
    columns = {
        "pan_deg": pan, "tilt_deg": tilt, "focal_px": focal, "fx_px": focal, "fy_px": focal,
        "theta_deg": found["theta_deg"], "delta_deg": found["delta_deg"], "a_px": shift,
        "gamma_deg": found["gamma_deg"], "vp_x": found["vp_x"], "vp_y": found["vp_y"],
        "foreshortening": found["foreshortening"], "vp_col": vp_col, "vp_row": vp_row,
        "vl_a": line_a, "vl_b": line_b, "vl_c": line_c,
    }
    lists = {name: values.tolist() for name, values in columns.items()}
    rows: list[dict[str, Any] | None] = []
    for index in range(len(table)):
        if not frontal[index] and not shift[index] >= MIN_HORIZON_OFFSET_PX:
            rows.append(None)
            continue
        row = {name: values[index] for name, values in lists.items()}
        row["roll_deg"] = 0.0
        known_point = not math.isnan(cx[index])
        known_size = not (math.isnan(width[index]) or math.isnan(height[index]))
        if not known_point:
            for name in ("vp_col", "vp_row", "vl_a", "vl_b", "vl_c"):
                del row[name]
        elif frontal[index]:
            for name in ("vl_a", "vl_b", "vl_c"):
                del row[name]
        row["horizon_in_image"] = (None if not known_size
                                   else bool(crosses[index]) and not frontal[index])
        rows.append(row)
    return rows


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
