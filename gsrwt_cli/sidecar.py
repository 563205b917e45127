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
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any

import yaml

from .camera import View, ViewError
from .geometry import gsrwt_parameters, pan_tilt_from_gsrwt

VIEW_FIELDS = ("pan", "tilt", "focal", "cx", "cy", "width", "height", "distance")
GSRWT_FIELDS = ("delta", "a", "gamma")
NUMERIC_FIELDS = VIEW_FIELDS + GSRWT_FIELDS
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


def _number(where: str, name: str, raw: Any) -> float:
    if isinstance(raw, bool):
        raise RecordError(where, name, f"not a number: {raw!r}")
    try:
        value = float(raw)
    except (TypeError, ValueError):
        raise RecordError(where, name, f"not a number: {raw!r}") from None
    if not math.isfinite(value):
        raise RecordError(where, name, f"must be finite, got {raw!r}")
    return value


def view_from_values(values: Mapping[str, Any], where: str) -> View:
    """Build a :class:`View` from raw values (numbers or numeric strings), naming what is wrong.

    When ``delta`` and ``a`` are given instead of pan and tilt, the pose comes from the GS-RWT
    parameters (:func:`~gsrwt_cli.geometry.pan_tilt_from_gsrwt`); a given ``gamma`` must
    agree with them within :data:`GAMMA_TOLERANCE_DEG`.
    """
    numbers = {
        name: _number(where, name, values[name])
        for name in NUMERIC_FIELDS
        if values.get(name) is not None and values.get(name) != ""
    }
    given = set(numbers)
    if given & {"pan", "tilt"} and given & {"delta", "a"}:
        raise RecordError(where, None, "give pan and tilt, or delta and a, not both")
    if given & {"delta", "a"}:
        for name in ("delta", "a", "focal"):
            if name not in numbers:
                reason = f"missing field '{name}' (needed with delta, a, gamma)"
                raise RecordError(where, None, reason)
        try:
            pan, tilt = pan_tilt_from_gsrwt(numbers["delta"], numbers["a"], numbers["focal"])
        except ValueError as error:
            raise RecordError(where, str(error).split(" ", 1)[0], str(error)) from None
        numbers["pan"], numbers["tilt"] = pan, tilt
        if "gamma" in numbers:
            implied = gsrwt_parameters(pan, tilt, numbers["focal"]).gamma_deg
            if abs(numbers["gamma"] - implied) > GAMMA_TOLERANCE_DEG:
                raise RecordError(
                    where,
                    "gamma",
                    f"{numbers['gamma']:g} disagrees with delta and a, which imply "
                    f"gamma = {implied:.2f}",
                )
    for name in ("pan", "tilt", "focal"):
        if name not in numbers:
            raise RecordError(where, None, f"missing field '{name}'")
    try:
        return View(**{name: numbers[name] for name in VIEW_FIELDS if name in numbers})
    except ViewError as error:
        raise RecordError(where, error.field, str(error)) from None


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
            rows = ", ".join(record.image for record in candidates)
            raise SidecarError(
                f"{self.path}: {PurePosixPath(key).name} matches several rows by file name "
                f"({rows}); give the image's relative path"
            )
        return candidates[0] if candidates else None


def _normalize(image: str) -> str:
    text = str(image).strip().replace("\\", "/")
    while text.startswith("./"):
        text = text[2:]
    return text


def load_sidecar(path: str | Path) -> Sidecar:
    """Read a CSV, TSV or YAML sidecar; raises :class:`SidecarError` naming the file."""
    path = Path(path)
    if not path.exists():
        raise SidecarError(f"{path}: no such file")
    if path.is_dir():
        raise SidecarError(f"{path}: is a directory, not a sidecar file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        raise SidecarError(f"{path}: not UTF-8 text ({error.reason})") from None
    except OSError as error:
        raise SidecarError(f"{path}: cannot read ({error.strerror})") from None
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        records = _yaml_records(path, text)
    elif suffix in (".csv", ".tsv", ".txt"):
        records = _csv_records(path, text, delimiter="\t" if suffix == ".tsv" else ",")
    else:
        raise SidecarError(f"{path}: unknown sidecar type '{suffix}' (use .csv, .tsv or .yaml)")
    seen: dict[str, str] = {}
    for record in records:
        key = _normalize(record.image)
        if key in seen:
            raise SidecarError(f"{record.where}: image '{record.image}' is already in {seen[key]}")
        seen[key] = record.where
    return Sidecar(path, records)


def _csv_records(path: Path, text: str, delimiter: str) -> list[Record]:
    reader = csv.reader(text.splitlines(), delimiter=delimiter)
    header = next(reader, None)
    if header is None or not any(cell.strip() for cell in header):
        raise SidecarError(f"{path}: empty file, expected a header row starting with 'image'")
    columns = [cell.strip().lower() for cell in header]
    if "image" not in columns:
        raise SidecarError(
            f"{path} line 1: missing column 'image' (header is {','.join(columns)})"
        )
    records = []
    for line_number, cells in enumerate(reader, start=2):
        if not any(cell.strip() for cell in cells):
            continue
        where = f"{path} line {line_number}"
        if len(cells) > len(columns):
            raise SidecarError(f"{where}: {len(cells)} cells but the header has {len(columns)}")
        row = {c: v.strip() for c, v in zip(columns, cells) if v.strip() != ""}
        image = row.pop("image", "")
        if not image:
            raise SidecarError(f"{where}, field 'image': empty")
        values = {k: v for k, v in row.items() if k in NUMERIC_FIELDS}
        records.append(Record(image=image, values=values, where=where))
    return records


def _yaml_records(path: Path, text: str) -> list[Record]:
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        at = f" line {mark.line + 1}" if mark is not None else ""
        problem = getattr(error, "problem", None) or "invalid YAML"
        raise SidecarError(f"{path}{at}: {problem}") from None
    if data is None:
        raise SidecarError(f"{path}: empty file")
    defaults: dict[str, Any] = {}
    items: list[tuple[str, Any, Any]] = []  # (where, image name or None, record)
    if isinstance(data, list):
        for index, item in enumerate(data, start=1):
            if isinstance(item, dict) and set(item) == {"defaults"}:
                where = f"{path} record {index} (defaults)"
                defaults = _yaml_mapping(path, where, item["defaults"])
                continue
            items.append((f"{path} record {index}", None, item))
    elif isinstance(data, dict):
        for key, item in data.items():
            if key == "defaults":
                defaults = _yaml_mapping(path, f"{path} defaults", item)
                continue
            items.append((f"{path} record '{key}'", str(key), item))
    else:
        raise SidecarError(f"{path}: expected a list of records or a mapping of image to record")
    for name in defaults:
        if name not in NUMERIC_FIELDS:
            raise SidecarError(f"{path} defaults: unknown field '{name}'")
    records = []
    for where, key, item in items:
        mapping = _yaml_mapping(path, where, item)
        image = key if key is not None else mapping.get("image")
        if image is None or str(image).strip() == "":
            raise SidecarError(f"{where}, field 'image': missing")
        values = {k: v for k, v in mapping.items() if k in NUMERIC_FIELDS and v is not None}
        records.append(Record(image=str(image), values=values, where=where, defaults=defaults))
    return records


def _yaml_mapping(path: Path, where: str, item: Any) -> dict[str, Any]:
    if not isinstance(item, dict):
        raise SidecarError(f"{where}: expected a mapping of field to value, got {item!r}")
    return {str(k).strip().lower(): v for k, v in item.items()}


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
