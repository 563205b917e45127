"""Sidecar files: per-image camera parameters from CSV or YAML, validated into ``View`` objects.

Formats (angles in degrees, lengths in pixels, ``distance`` in the user's wall unit):

- CSV (``.csv``, or ``.tsv`` tab-separated) with a header row: ``image,pan,tilt,focal`` and
  optionally ``cx,cy,width,height,distance``; instead of ``pan,tilt`` a row may give the
  transform's own ``delta,a,gamma`` (with ``focal``). Empty cells count as absent; other
  columns are ignored (sidecars often carry more than we need).
- YAML: a list of records with the same keys (an item ``{defaults: {...}}`` gives defaults),
  or a mapping from image name to record (a key ``defaults`` gives defaults).

Problems with the file itself raise :class:`SidecarError`; problems with one record surface
when its view is built, as :class:`RecordError` naming the file, the row and the field.

Refused (one-line messages, values quoted by :func:`~gsrwt_cli.messages.quote`): for the
file, a CSV column given twice, a cell the csv module refuses, an image given twice, and YAML
that :mod:`.safe_yaml` refuses (deep nesting, alias bombs, duplicate keys, huge integers);
for a record, a value that is not a real number or a plain ASCII decimal (``nan``, ``1e400``,
a 400-digit integer, ``1_000`` are errors) or that breaks the bounds of
:class:`~gsrwt_cli.camera.View`. CSV ``line N`` is where the row starts, quoted newlines
counted. (Over 400 lines: reading, validating and writing both formats belong together.)
"""

from __future__ import annotations

import csv
import io
import math
import numbers
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path, PurePosixPath
from typing import Any

import yaml

from .calibration import CalibrationError, load_camera
from .camera import (
    LENS_FIELDS,
    LENS_MODELS,
    VIEW_FIELDS,
    Intrinsics,
    Lens,
    Pose,
    View,
    ViewError,
)
from .geometry import pan_tilt_from_gsrwt
from .messages import escape_controls, one_line, quote
from .poses import PoseError, distance_from_tvec, pose_from_quaternion, pose_from_rvec
from .safe_yaml import YamlInputError, load_yaml

GSRWT_FIELDS = ("delta", "a", "gamma")
#: A pose as OpenCV's solvePnP gives it (camera_from_wall, OpenCV frames), or a quaternion of
#: the same rotation (scalar first): instead of pan, tilt and roll (docs/POSES.md).
RVEC_FIELDS = ("rvec_x", "rvec_y", "rvec_z")
TVEC_FIELDS = ("tvec_x", "tvec_y", "tvec_z")
QUATERNION_FIELDS = ("qw", "qx", "qy", "qz")
POSE_FIELDS = RVEC_FIELDS + TVEC_FIELDS + QUATERNION_FIELDS
#: A focal length in millimetres, with the sensor's size: ``fx = focal_mm * width /
#: sensor_width_mm`` (and ``fy`` from ``sensor_height_mm``, else square pixels).
SENSOR_FIELDS = ("focal_mm", "sensor_width_mm", "sensor_height_mm")
NUMERIC_FIELDS = VIEW_FIELDS + LENS_FIELDS + POSE_FIELDS + SENSOR_FIELDS + GSRWT_FIELDS
#: Fields whose values are words, not numbers: ``camera`` names a calibration file (OpenCV
#: or ROS, relative to the sidecar) whose intrinsics the record's own fields override.
TEXT_FIELDS = ("distortion_model", "camera")
#: Every field a sidecar record may give.
SIDECAR_FIELDS = NUMERIC_FIELDS + TEXT_FIELDS
#: How far a given gamma may stray from the one that delta and a imply (the thesis rounds to 1°).
GAMMA_TOLERANCE_DEG = 1.0


class SidecarError(ValueError):
    """The sidecar file as a whole cannot be used (missing, unreadable, malformed)."""


class RecordError(ValueError):
    """One record of parameters is invalid: ``where`` it came from, which ``field``, ``reason``."""

    def __init__(self, where: str, field_name: str | None, reason: str) -> None:
        self.where, self.field, self.reason = where, field_name, reason
        at = f"{where}, field '{field_name}'" if field_name else where
        super().__init__(f"{at}: {reason}")


@dataclass(frozen=True)
class Record:
    """The raw parameters of one image, before validation.

    ``where`` says where they came from, e.g. ``views.csv line 4`` or ``views.yaml record 2``.
    """

    image: str
    values: Mapping[str, Any]
    where: str
    defaults: Mapping[str, Any] = field(default_factory=dict)

    def merged(self, fallback: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The record's values over its file's defaults over ``fallback``."""
        return merge_values(self.values, self.defaults, fallback or {})

    def view(self, fallback: Mapping[str, Any] | None = None) -> View:
        """Validate into a :class:`View`; ``fallback`` fills what record and defaults leave out."""
        return view_from_values(self.merged(fallback), self.where)


def merge_values(own: Mapping[str, Any], *fallbacks: Mapping[str, Any]) -> dict[str, Any]:
    """``own`` values over the ``fallbacks`` (earlier ones win over later ones).

    A record that gives the pose as the GS-RWT's ``delta``/``a`` takes no pan or tilt from
    the fallbacks, and one that gives pan/tilt takes no ``delta``, ``a`` or ``gamma``.
    """
    merged: dict[str, Any] = {}
    for fallback in reversed(fallbacks):
        merged.update(fallback)
    own_keys = {k for k, v in own.items() if v is not None and v != ""}
    if own_keys & {"delta", "a"} and not own_keys & {"pan", "tilt"}:
        merged.pop("pan", None)
        merged.pop("tilt", None)
    elif own_keys & {"pan", "tilt"}:
        for name in GSRWT_FIELDS:
            merged.pop(name, None)
    merged.update(own)
    return merged


_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NOT_FINITE = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)


def _number(where: str, name: str, raw: Any) -> float:
    """A raw value as a finite float: a real number (numpy's too) or a decimal string.

    Strings must be plain ASCII decimals (``-12``, ``3.5``, ``1e-3``); ``nan``, ``inf`` and
    values beyond floating point (``1e400``, an integer of 400 digits) are errors.
    """
    if isinstance(raw, str):
        text = raw.strip()
        if _NOT_FINITE.fullmatch(text):
            raise RecordError(where, name, f"must be finite, got {quote(raw)}")
        if not _DECIMAL.fullmatch(text):
            raise RecordError(where, name, f"not a number: {quote(raw)}")
        value = float(text)
    elif isinstance(raw, bool) or not isinstance(raw, numbers.Real):
        raise RecordError(where, name, f"not a number: {quote(raw)}")
    else:
        try:
            value = float(raw)
        except OverflowError:  # an integer or a fraction beyond floating point
            raise RecordError(where, name, f"out of range, got {quote(raw)}") from None
        if not math.isfinite(value):
            raise RecordError(where, name, f"must be finite, got {quote(raw)}")
    if not math.isfinite(value):  # a decimal string beyond floating point
        raise RecordError(where, name, f"out of range, got {quote(raw)}")
    return value


def view_from_values(values: Mapping[str, Any], where: str) -> View:
    """Build a :class:`View` from raw values (numbers or numeric strings), naming what is wrong.

    When ``delta`` and ``a`` are given instead of pan and tilt, the pose comes from the GS-RWT
    parameters (:func:`~gsrwt_cli.geometry.pan_tilt_from_gsrwt`); a given ``gamma`` must
    agree with them within :data:`GAMMA_TOLERANCE_DEG`. Raises only :class:`RecordError`.
    """
    numbers_given = {
        name: _number(where, name, values[name])
        for name in NUMERIC_FIELDS
        if values.get(name) is not None and values.get(name) != ""
    }
    given = set(numbers_given)
    if given & {"pan", "tilt"} and given & {"delta", "a"}:
        raise RecordError(where, None, "give pan and tilt, or delta and a, not both")
    if given & {"delta", "a"}:
        for name in ("delta", "a", "focal"):
            if name not in numbers_given:
                reason = f"missing field '{name}' (needed with delta, a, gamma)"
                raise RecordError(where, None, reason)
        try:
            pan, tilt = pan_tilt_from_gsrwt(
                numbers_given["delta"], numbers_given["a"], numbers_given["focal"]
            )
        except ValueError as error:
            raise RecordError(where, str(error).split(" ", 1)[0], str(error)) from None
        numbers_given["pan"], numbers_given["tilt"] = pan, tilt
    _pose_from_rotation_fields(where, numbers_given)
    for name in ("pan", "tilt"):
        if name not in numbers_given:
            raise RecordError(where, None, f"missing field '{name}'")
    _focal_from_millimetres(where, numbers_given)
    given = set(numbers_given)
    camera = values.get("camera")
    if "focal" not in numbers_given and not {"fx", "fy"} <= given and not camera:
        raise RecordError(where, None, "missing field 'focal'")
    try:
        lens = _lens_from_values(values, numbers_given)
        if camera:
            try:
                base = load_camera_file(str(camera))
            except CalibrationError as error:
                raise RecordError(where, "camera", str(error)) from None
            view = _view_with_camera(base, numbers_given, lens, values)
        else:
            view = View(**{name: numbers_given[name] for name in VIEW_FIELDS
                           if name in numbers_given}, lens=lens)
    except ViewError as error:
        raise RecordError(where, error.field, str(error)) from None
    if "gamma" in numbers_given:
        implied = view.parameters.gamma_deg
        if abs(numbers_given["gamma"] - implied) > GAMMA_TOLERANCE_DEG:
            raise RecordError(
                where,
                "gamma",
                f"{numbers_given['gamma']:g} disagrees with delta and a, which imply "
                f"gamma = {implied:.2f}",
            )
    return view


def _focal_from_millimetres(where: str, numbers: dict[str, float]) -> None:
    """Fill fx and fy from ``focal_mm`` and the sensor's size in millimetres, in place."""
    if "focal_mm" not in numbers:
        return
    if given := {"focal", "fx", "fy"} & set(numbers):
        raise RecordError(where, "focal_mm", f"give focal_mm or {sorted(given)[0]}, not both")
    for name in ("sensor_width_mm", "width"):
        if name not in numbers:
            reason = (f"missing field '{name}' (needed with focal_mm"
                      + (", or an image whose size can be read)" if name == "width" else ")"))
            raise RecordError(where, name, reason)
    for name in ("focal_mm", "sensor_width_mm", "sensor_height_mm"):
        if name in numbers and not numbers[name] > 0:
            raise RecordError(where, name, f"{name} must be positive, got {numbers[name]:g}")
    numbers["fx"] = numbers["focal_mm"] * numbers["width"] / numbers["sensor_width_mm"]
    if "sensor_height_mm" in numbers:
        if "height" not in numbers:
            raise RecordError(where, "height", "missing field 'height' (needed with "
                              "sensor_height_mm)")
        numbers["fy"] = numbers["focal_mm"] * numbers["height"] / numbers["sensor_height_mm"]
    else:
        numbers["fy"] = numbers["fx"]


def _pose_from_rotation_fields(where: str, numbers: dict[str, float]) -> None:
    """Fill pan, tilt and roll from an rvec or a quaternion, and distance from a tvec
    (its distance along the wall's normal, not ``tvec_z``), in place."""
    given = set(numbers)
    sources = [name for name, fields in (("pan/tilt", ("pan", "tilt", "roll")),
                                          ("rvec", RVEC_FIELDS), ("quaternion", QUATERNION_FIELDS))
               if given & set(fields)]
    if len(sources) > 1:
        raise RecordError(where, None, f"give one pose, not {' and '.join(sources)}")
    for fields in (RVEC_FIELDS, TVEC_FIELDS, QUATERNION_FIELDS):
        missing = [name for name in fields if name not in given]
        if given & set(fields) and missing:
            raise RecordError(where, missing[0], f"missing field '{missing[0]}' (needed with "
                              f"{', '.join(fields)})")
    if given & set(TVEC_FIELDS) and not given & set(RVEC_FIELDS):
        raise RecordError(where, "tvec_x", "a tvec needs its rvec (rvec_x, rvec_y, rvec_z)")
    try:
        if given & set(RVEC_FIELDS):
            rvec = [numbers[name] for name in RVEC_FIELDS]
            angles = pose_from_rvec(rvec)
            if given & set(TVEC_FIELDS) and "distance" not in given:
                numbers["distance"] = distance_from_tvec(
                    rvec, [numbers[name] for name in TVEC_FIELDS])
        elif given & set(QUATERNION_FIELDS):
            angles = pose_from_quaternion(*(numbers[name] for name in QUATERNION_FIELDS))
        else:
            return
    except PoseError as error:
        field = "rvec_x" if given & set(RVEC_FIELDS) else "qw"
        raise RecordError(where, field, str(error)) from None
    numbers["pan"], numbers["tilt"], numbers["roll"] = angles.pan, angles.tilt, angles.roll


@lru_cache(maxsize=64)
def load_camera_file(path: str) -> Intrinsics:
    """A calibration file's intrinsics (:func:`~gsrwt_cli.calibration.load_camera`), read once
    per process; raises :class:`~gsrwt_cli.calibration.CalibrationError`."""
    return load_camera(path)


def _view_with_camera(base: Intrinsics, numbers: Mapping[str, float], lens: Lens | None,
                      values: Mapping[str, Any]) -> View:
    """A view whose intrinsics come from a calibration file, with the record's own fields
    (fx, fy or focal, cx, cy, skew, a lens) over the file's."""
    fx, fy = base.fx, base.fy
    if "focal" in numbers:
        fx = fy = numbers["focal"]
    fx, fy = numbers.get("fx", fx), numbers.get("fy", fy)
    cx, cy = numbers.get("cx", base.cx), numbers.get("cy", base.cy)
    overrides_lens = lens is not None or values.get("distortion_model")
    intrinsics = Intrinsics(
        fx, fy, cx, cy, numbers.get("skew", base.skew),
        numbers.get("width", base.width), numbers.get("height", base.height),
        lens if overrides_lens else base.lens,
    )
    pose = Pose(numbers["pan"], numbers["tilt"], numbers.get("roll", 0.0))
    return View(intrinsics=intrinsics, pose=pose, distance=numbers.get("distance"))


def _with_camera_path(sidecar: Path, values: dict[str, Any]) -> dict[str, Any]:
    """``camera`` relative to the sidecar's directory, as a path that works from anywhere."""
    camera = values.get("camera")
    if camera is None or str(camera).strip() == "":
        return values
    camera_path = Path(str(camera).strip())
    if not camera_path.is_absolute():
        camera_path = sidecar.parent / camera_path
    return {**values, "camera": str(camera_path)}


def _lens_from_values(values: Mapping[str, Any], numbers: Mapping[str, float]) -> Lens | None:
    """The lens a record gives: ``distortion_model`` (default ``plumb_bob``, or
    ``rational_polynomial`` when a coefficient only it has is given) and coefficients."""
    coefficients = tuple((name, numbers[name]) for name in LENS_FIELDS if name in numbers)
    model = values.get("distortion_model")
    if model is None or str(model).strip() == "":
        if not coefficients:
            return None
        plumb_bob = set(LENS_MODELS["plumb_bob"])
        model = ("plumb_bob" if {name for name, _ in coefficients} <= plumb_bob
                 else "rational_polynomial")
    return Lens(str(model).strip().lower(), coefficients)


@dataclass
class Sidecar:
    """All records of one sidecar file, looked up by relative path or by file name."""

    path: Path
    records: list[Record]

    def __post_init__(self) -> None:
        self._by_path = {_normalize(r.image): r for r in self.records}
        by_name: dict[str, list[Record]] = {}
        for record in self.records:
            by_name.setdefault(PurePosixPath(_normalize(record.image)).name, []).append(record)
        self._by_name = by_name

    def find(self, relative_path: str) -> Record | None:
        """The record for an image: an exact relative-path match, else a unique file-name match.

        Raises :class:`SidecarError` when only the file name matches, and several rows.
        """
        key = _normalize(relative_path)
        if key in self._by_path:
            return self._by_path[key]
        candidates = self._by_name.get(PurePosixPath(key).name, [])
        if len(candidates) > 1:
            rows = ", ".join(_unquoted(record.image) for record in candidates[:3])
            more = f" and {len(candidates) - 3} more" if len(candidates) > 3 else ""
            raise SidecarError(
                f"{display_path(self.path)}: {_unquoted(PurePosixPath(key).name)} matches "
                f"several rows by file name ({rows}{more}); give the image's relative path"
            )
        return candidates[0] if candidates else None


def _unquoted(text: str) -> str:
    """``text`` bounded and escaped like :func:`~gsrwt_cli.messages.quote`, without the quotes."""
    return quote(text)[1:-1]


def _normalize(image: str) -> str:
    text = str(image).strip().replace("\\", "/")
    while text.startswith("./"):
        text = text[2:]
    return text


def display_path(path: str | Path) -> str:
    """A path as messages show it: on one line (control characters escaped)."""
    return escape_controls(str(path))


def _check_is_file(path: Path) -> None:
    if not path.exists():
        raise SidecarError(f"{display_path(path)}: no such file")
    if path.is_dir():
        raise SidecarError(f"{display_path(path)}: is a directory, not a sidecar file")


def read_sidecar_text(path: Path) -> str:
    """The text of a sidecar file (UTF-8, an optional BOM removed); SidecarError if unreadable."""
    name = display_path(path)
    _check_is_file(path)
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        raise SidecarError(f"{name}: not UTF-8 text ({error.reason})") from None
    except OSError as error:
        raise SidecarError(f"{name}: cannot read ({error.strerror})") from None


def load_sidecar(path: str | Path) -> Sidecar:
    """Read a CSV, TSV or YAML sidecar; raises :class:`SidecarError` naming the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".yaml", ".yml", ".csv", ".tsv", ".txt"):
        _check_is_file(path)  # a missing file is reported as such first
        raise SidecarError(
            f"{display_path(path)}: unknown sidecar type {quote(suffix)} "
            "(use .csv, .tsv or .yaml)"
        )
    text = read_sidecar_text(path)
    if suffix in (".yaml", ".yml"):
        return sidecar_from_yaml(path, parse_yaml(path, text))
    return _checked_sidecar(
        path, _csv_records(path, text, delimiter="\t" if suffix == ".tsv" else ",")
    )


def _checked_sidecar(path: Path, records: list[Record]) -> Sidecar:
    """The sidecar of ``records``; an image given twice is an error naming both places."""
    seen: dict[str, str] = {}
    for record in records:
        key = _normalize(record.image)
        if key in seen:
            raise SidecarError(
                f"{record.where}: image {quote(record.image)} is already in {seen[key]}"
            )
        seen[key] = record.where
    return Sidecar(path, records)


def _csv_records(path: Path, text: str, delimiter: str) -> list[Record]:
    """Records of a CSV/TSV text; ``line N`` is where the row starts, quoted newlines counted."""
    name = display_path(path)
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    try:
        header = next(reader, None)
        if header is None or not any(cell.strip() for cell in header):
            raise SidecarError(f"{name}: empty file, expected a header row starting with 'image'")
        columns = [cell.strip().lower() for cell in header]
        if "image" not in columns:
            raise SidecarError(
                f"{name} line 1: missing column 'image' (header is {quote(','.join(columns))})"
            )
        first_seen: dict[str, int] = {}
        for number, column in enumerate(columns, start=1):
            if column and column in first_seen:
                raise SidecarError(
                    f"{name} line 1: column {quote(column)} given twice "
                    f"(columns {first_seen[column]} and {number})"
                )
            first_seen.setdefault(column, number)
        records = []
        row_start = reader.line_num + 1
        for cells in reader:
            line_number, row_start = row_start, reader.line_num + 1
            if not any(cell.strip() for cell in cells):
                continue
            where = f"{name} line {line_number}"
            if len(cells) > len(columns):
                raise SidecarError(
                    f"{where}: {len(cells)} cells but the header has {len(columns)}"
                )
            row = {c: v.strip() for c, v in zip(columns, cells) if v.strip() != ""}
            image = row.pop("image", "")
            if not image:
                raise SidecarError(f"{where}, field 'image': empty")
            values = {k: v for k, v in row.items() if k in SIDECAR_FIELDS}
            records.append(Record(image=image, values=_with_camera_path(path, values),
                                  where=where))
    except csv.Error as error:
        raise SidecarError(
            f"{name} line {reader.line_num}: {one_line(str(error), 200)}"
        ) from None
    return records


def parse_yaml(path: Path, text: str) -> Any:
    """The YAML document of a sidecar, read by the bounded loader (:mod:`.safe_yaml`).

    Raises :class:`SidecarError` naming the file and, when known, the line.
    """
    try:
        return load_yaml(text)
    except YamlInputError as error:
        at = f" line {error.line}" if error.line is not None else ""
        raise SidecarError(f"{display_path(path)}{at}: {error.problem}") from None


def load_yaml_file(path: Path) -> Any:
    """Read and parse a YAML file (a sidecar, or the parameters beside one image)."""
    return parse_yaml(path, read_sidecar_text(path))


def sidecar_from_yaml(path: Path, data: Any) -> Sidecar:
    """The sidecar of a parsed YAML document: a list of records or a mapping image -> record."""
    return _checked_sidecar(path, _yaml_records(path, data))


def _yaml_records(path: Path, data: Any) -> list[Record]:
    name = display_path(path)
    if data is None:
        raise SidecarError(f"{name}: empty file")
    defaults: dict[str, Any] = {}
    defaults_where: str | None = None
    items: list[tuple[str, Any, Any]] = []  # (where, image name or None, record)
    if isinstance(data, list):
        for index, item in enumerate(data, start=1):
            if isinstance(item, dict) and set(item) == {"defaults"}:
                where = f"{name} record {index} (defaults)"
                if defaults_where is not None:
                    raise SidecarError(f"{where}: defaults given twice (first in {defaults_where})")
                defaults, defaults_where = fields_of(where, item["defaults"]), where
                continue
            items.append((f"{name} record {index}", None, item))
    elif isinstance(data, dict):
        for key, item in data.items():
            if key == "defaults":
                defaults = fields_of(f"{name} defaults", item)
                continue
            items.append((f"{name} record {quote(str(key))}", str(key), item))
    else:
        raise SidecarError(f"{name}: expected a list of records or a mapping of image to record")
    for field_name in defaults:
        if field_name not in SIDECAR_FIELDS:
            raise SidecarError(f"{name} defaults: unknown field {quote(field_name)}")
    records = []
    for where, key, item in items:
        mapping = fields_of(where, item)
        image = key if key is not None else mapping.get("image")
        if image is None or str(image).strip() == "":
            raise SidecarError(f"{where}, field 'image': missing")
        if isinstance(image, bool) or not isinstance(image, (str, int, float)):
            raise SidecarError(f"{where}, field 'image': expected a file name, got {quote(image)}")
        values = {k: v for k, v in mapping.items() if k in SIDECAR_FIELDS and v is not None}
        records.append(Record(image=str(image), values=_with_camera_path(path, values),
                              where=where, defaults=_with_camera_path(path, defaults)))
    return records


def fields_of(where: str, item: Any) -> dict[str, Any]:
    """A YAML record as ``{field: value}`` with field names stripped and lower-cased.

    Not a mapping, or two keys that name the same field (``Pan`` and ``pan``), is an error.
    """
    if not isinstance(item, dict):
        raise SidecarError(f"{where}: expected a mapping of field to value, got {quote(item)}")
    fields: dict[str, Any] = {}
    for key, value in item.items():
        field_name = str(key).strip().lower()
        if field_name in fields:
            raise SidecarError(f"{where}: field {quote(field_name)} given twice")
        fields[field_name] = value
    return fields


def format_sidecar(path: str | Path, rows: list[Mapping[str, Any]]) -> str:
    """Sidecar text for ``rows`` (dicts with ``image`` and view fields), CSV or YAML by extension.

    Only the columns some row has are written, in the order of :data:`VIEW_FIELDS`; what
    :func:`load_sidecar` reads back gives the same views.
    """
    columns = [name for name in VIEW_FIELDS if any(row.get(name) is not None for row in rows)]
    suffix = Path(path).suffix.lower()
    if suffix in (".yaml", ".yml"):
        mapping = {
            str(row["image"]): {c: row[c] for c in columns if row.get(c) is not None}
            for row in rows
        }
        return yaml.safe_dump(mapping, sort_keys=False, allow_unicode=True)
    if suffix not in (".csv", ".tsv"):
        raise SidecarError(f"{path}: a sidecar must end in .csv, .tsv or .yaml")
    lines = []
    writer = csv.writer(_LineSink(lines), delimiter="\t" if suffix == ".tsv" else ",",
                        lineterminator="\n")
    writer.writerow(["image", *columns])
    for row in rows:
        writer.writerow([row["image"], *("" if row.get(c) is None else row[c] for c in columns)])
    return "".join(lines)


class _LineSink:
    """A write() target collecting text for csv.writer."""

    def __init__(self, lines: list[str]) -> None:
        self.lines = lines

    def write(self, text: str) -> None:
        self.lines.append(text)
