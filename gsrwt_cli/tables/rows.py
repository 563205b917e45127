"""The rows of the public tables: one dict per view with the documented column names."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..geometry.camera import (
    DISTANCE_RANGE,
    MAX_FOCAL_PX,
    MAX_PRINCIPAL_POINT_PX,
    MAX_SIDE_PX,
    MIN_HORIZON_OFFSET_PX,
    View,
)
from ..geometry.gsrwt import parameter_arrays
from ..inputs.records import (
    GSRWT_FIELDS,
    SIMPLE_PINHOLE_FIELDS,
    RecordError,
    simple_pinhole_numbers,
    view_from_values,
)
from .columns import (  # noqa: F401  (named here too)
    GAZE_COLUMNS,
    LINES_COLUMNS,
    MATCH_COLUMNS,
    PARAMS_COLUMNS,
    TRACK_COLUMNS,
)

if TYPE_CHECKING:
    from ..geometry.framing import Plan
    from ..vision.landmarks import Line, Match

#: Maps ``(N, 2)`` frontal-view pixels to the original image's, or gives None (no map).
ToSource = Callable[[np.ndarray], "np.ndarray | None"]



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


@dataclass(frozen=True)
class ParamsBlock:
    """Consecutive ``params`` rows as columns (``count`` values each; ``nan`` where
    :func:`params_row` leaves a column out: the tables write both as an empty cell)."""

    columns: dict[str, list[Any]]
    count: int


def plan_row(plan: Plan) -> dict[str, Any]:
    """The geometry columns of a ``gsrwt rectify`` row: the view's :func:`params_row`, the
    output's size (``out_width``, ``out_height``), its ``scale`` (output pixels per frontal
    pixel) and the ``homography`` (9 numbers row-major, output pixel <- input pixel, scaled
    so that ``w = 1`` at the principal point; 12 significant digits)."""
    homography = np.asarray(plan.pixel_map.output_from_input, dtype=np.float64)
    return {
        **params_row(plan.view, None),
        "out_width": plan.size[0],
        "out_height": plan.size[1],
        "scale": plan.frame.scale,
        "homography": " ".join(f"{value:.12g}" for value in homography.ravel()),
    }


def params_rows(
    records: Iterable[tuple[str | None, Mapping[str, Any], str]],
) -> Iterator[dict[str, Any] | RecordError | ParamsBlock]:
    """:func:`params_row` of each ``(image, values, where)``, in order, or the
    :class:`~gsrwt_cli.inputs.records.RecordError` of a record that is no valid view. A chunk of
    plain text records (a CSV's) that are all valid square-pixel pinholes comes as one
    :class:`ParamsBlock`.

    Square-pixel pinhole records (:func:`~gsrwt_cli.inputs.records.simple_pinhole_numbers`) are
    computed :data:`PARAMS_CHUNK` at a time by :func:`~gsrwt_cli.geometry.gsrwt.parameter_arrays`,
    exactly as their views would compute them; any other through its view.
    """
    records = iter(records)
    while chunk := list(islice(records, PARAMS_CHUNK)):
        block = _text_block(chunk)
        if block is not None:
            yield block
            continue
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


#: What the cells of a :class:`ParamsBlock`'s numbers may hold: a decimal's characters.
_NOT_DECIMAL = re.compile(r"[^0-9eE.+\-\n]")
#: The columns of a block, in the order of :func:`simple_pinhole_numbers`'s result.
_BLOCK_FIELDS = ("pan", "tilt", "focal", "cx", "cy", "width", "height")


def _text_block(chunk: list[tuple[str | None, Mapping[str, Any], str]]) -> ParamsBlock | None:
    """The chunk of records as one :class:`ParamsBlock` (:func:`params_block` of their
    values as columns), if every record gives the same fields; else None."""
    given = {name for _, values, _ in chunk for name in values}
    if not given <= SIMPLE_PINHOLE_FIELDS:
        return None
    columns: dict[str, list[Any]] = {name: [values.get(name) for _, values, _ in chunk]
                                     for name in given}
    columns["image"] = [image for image, _, _ in chunk]
    return params_block(columns)


def params_block(columns: Mapping[str, Sequence[Any]], defaults: Mapping[str, Any] | None = None
                 ) -> ParamsBlock | None:
    """Consecutive views given as columns of sidecar fields (``image``, and text cells as a
    CSV holds them: a :class:`~gsrwt_cli.inputs.sidecar.CsvChunk`'s
    :meth:`~gsrwt_cli.inputs.sidecar.CsvChunk.text_columns`), over ``defaults`` (numbers, as
    :func:`~gsrwt_cli.inputs.records.merge_values` merges them), as one :class:`ParamsBlock`,
    exactly the rows of their views (Eqs. 4.4-4.8 through
    :func:`~gsrwt_cli.geometry.gsrwt.parameter_arrays`). None unless every view gives only
    :data:`~gsrwt_cli.inputs.records.SIMPLE_PINHOLE_FIELDS` as plain decimal text (other columns
    than sidecar fields ignored, as is a column of empty cells) and is valid: the caller
    then takes them one by one, and each gives its own row or error."""
    given = {name for name, cells in columns.items() if name != "image" and any(cells)}
    constants: dict[str, float] = {}
    for name, value in (defaults or {}).items():
        if name in given or (name in GSRWT_FIELDS and {"pan", "tilt"} <= given):
            continue  # the column's own cells win; pan and tilt drop the GS-RWT's pose
        if name not in SIMPLE_PINHOLE_FIELDS or type(value) not in (int, float):
            return None
        constants[name] = float(value)
    known = given | set(constants)
    if not known <= SIMPLE_PINHOLE_FIELDS or not {"pan", "tilt", "focal"} <= known:
        return None
    if ("cx" in known) != ("cy" in known):
        return None
    count = len(columns["image"])
    numbers = {}
    for name in (*_BLOCK_FIELDS, "distance"):
        if name in constants:
            numbers[name] = np.full(count, constants[name])
        elif name not in given:
            numbers[name] = np.full(count, np.nan)
        else:
            texts = columns[name]
            try:
                if _NOT_DECIMAL.search("\n".join(texts)):  # None or a number: TypeError
                    return None
                numbers[name] = np.array(texts, dtype=np.float64)  # "" : ValueError
            except (TypeError, ValueError):
                return None
    pan, tilt, focal = numbers["pan"], numbers["tilt"], numbers["focal"]
    width, height, distance = numbers["width"], numbers["height"], numbers["distance"]
    cx, cy = numbers["cx"], numbers["cy"]
    with np.errstate(invalid="ignore"):
        valid = (all(np.isfinite(numbers[name]).all() for name in known)
                 and (np.abs(pan) < 90).all() and (np.abs(tilt) < 90).all()
                 and ((focal > 0) & (focal < MAX_FOCAL_PX)).all()
                 and ("distance" not in known or ((distance > DISTANCE_RANGE[0])
                                                  & (distance < DISTANCE_RANGE[1])).all())
                 and all(((side > 0) & (side <= MAX_SIDE_PX) & (side == np.floor(side))).all()
                         for name, side in (("width", width), ("height", height))
                         if name in known)
                 and ("cx" not in known or ((np.abs(cx) < MAX_PRINCIPAL_POINT_PX)
                                            & (np.abs(cy) < MAX_PRINCIPAL_POINT_PX)).all()))
    if not valid:
        return None
    if "cx" not in known and {"width", "height"} <= known:
        cx, cy = (width - 1) / 2.0, (height - 1) / 2.0  # as Intrinsics does
    block, usable = _simple_pinhole_columns(np.column_stack(
        [pan, tilt, focal, cx, cy, width, height]))
    if not usable.all():
        return None
    lists = {name: values.tolist() for name, values in block.items()}
    lists["image"] = list(columns["image"])
    lists["roll_deg"] = [0.0] * count
    return ParamsBlock(lists, count)


def _simple_pinhole_columns(table: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The :func:`params_row` columns of square-pixel pinholes given as rows ``(pan, tilt,
    focal, cx, cy, width, height)`` (``nan``: unknown), ``nan`` where a row has no such value
    (``horizon_in_image``: an object array of True, False and None), and which rows are
    views (a horizon too close to the principal point is not: its view gives the error)."""
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
    no_point = np.isnan(cx)
    for name in ("vp_col", "vp_row"):
        columns[name] = np.where(no_point, np.nan, columns[name])
    for name in ("vl_a", "vl_b", "vl_c"):
        columns[name] = np.where(no_point | frontal, np.nan, columns[name])
    horizon = np.where(crosses & ~frontal, True, False).astype(object)
    horizon[np.isnan(width) | np.isnan(height)] = None
    columns["horizon_in_image"] = horizon
    return columns, frontal | (shift >= MIN_HORIZON_OFFSET_PX)


def _simple_pinhole_rows(table: np.ndarray) -> list[dict[str, Any] | None]:
    """:func:`_simple_pinhole_columns` as :func:`params_row`'s rows (the columns it leaves
    out left out); None for a row that is no view."""
    columns, usable = _simple_pinhole_columns(table)
    lists = {name: values.tolist() for name, values in columns.items()}
    rows: list[dict[str, Any] | None] = []
    for index in range(len(table)):
        if not usable[index]:
            rows.append(None)
            continue
        row = {name: values[index] for name, values in lists.items()
               if not (type(values[index]) is float and math.isnan(values[index])
                       and name.startswith(("vp_col", "vp_row", "vl_")))}
        row["roll_deg"] = 0.0
        rows.append(row)
    return rows


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
