"""Sidecar files: per-image camera parameters from CSV or YAML, validated into ``View`` objects.

Formats (angles in degrees, lengths in pixels, ``distance`` in the user's wall unit):

- CSV (``.csv``, or ``.tsv`` tab-separated) with a header row: ``image,pan,tilt,focal`` and
  optionally ``cx,cy,width,height,distance``; instead of ``pan,tilt`` a row may give the
  transform's own ``delta,a,gamma`` (with ``focal``). Empty cells count as absent; other
  columns are ignored (sidecars often carry more than we need).
- YAML: a list of records with the same keys (an item ``{defaults: {...}}`` gives defaults),
  or a mapping from image name to record (a key ``defaults`` gives defaults).

Problems with the file itself raise :class:`SidecarError`; problems with one record surface
when its view is built (:mod:`.records`), as :class:`~gsrwt_cli.inputs.records.RecordError` naming
the file, the row and the field.

Refused (one-line messages, values quoted by :func:`~gsrwt_cli.base.messages.quote`): for the
file, a CSV column given twice, a cell the csv module refuses, an image given twice, and YAML
that :mod:`~gsrwt_cli.io.safe_yaml` refuses (deep nesting, alias bombs, duplicate keys, huge
integers);
for a record, a value that is not a real number or a plain ASCII decimal (``nan``, ``1e400``,
a 400-digit integer, ``1_000`` are errors) or that breaks the bounds of
:class:`~gsrwt_cli.geometry.camera.View`. CSV ``line N`` is where the row starts, quoted newlines
counted.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import IO, Any

from ..base.messages import escape_controls, one_line, quote
from ..geometry.camera import VIEW_FIELDS, View
from ..io.storage import Location, is_url, location
from .records import SIDECAR_FIELDS, merge_values, view_from_values

#: :data:`~gsrwt_cli.inputs.records.SIDECAR_FIELDS` as a set, for the test of every CSV row.
SIDECAR_FIELD_SET = frozenset(SIDECAR_FIELDS)


class SidecarError(ValueError):
    """The sidecar file as a whole cannot be used (missing, unreadable, malformed)."""


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


def _with_camera_path(sidecar: Path, values: dict[str, Any]) -> dict[str, Any]:
    """``camera`` relative to the sidecar's directory, as a path that works from anywhere."""
    camera = values.get("camera")
    if camera is None or str(camera).strip() == "":
        return values
    if is_url(str(camera).strip()):
        return {**values, "camera": str(camera).strip()}
    camera_path = Path(str(camera).strip())
    if not camera_path.is_absolute():
        return {**values, "camera": str(sidecar.parent / camera_path)}
    return {**values, "camera": str(camera_path)}


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
    """``text`` bounded and escaped like :func:`~gsrwt_cli.base.messages.quote`, without the
    quotes."""
    return quote(text)[1:-1]


def _normalize(image: str) -> str:
    text = str(image).strip().replace("\\", "/")
    while text.startswith("./"):
        text = text[2:]
    return text


def display_path(path: str | Path) -> str:
    """A path as messages show it: on one line (control characters escaped)."""
    return escape_controls(str(path))


def _check_is_file(path: Path | Location) -> None:
    try:
        exists, is_dir = path.exists(), path.is_dir()
    except OSError as error:  # a store that cannot be reached (storage.StoreError)
        raise SidecarError(f"{display_path(path)}: cannot read ({error.strerror})") from None
    if not exists:
        raise SidecarError(f"{display_path(path)}: no such file")
    if is_dir:
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


def _sidecar_suffix(path: Path) -> str:
    """The file type of a sidecar (``.csv``, ``.tsv``, ``.txt``, ``.yaml``, ``.yml``)."""
    suffix = path.suffix.lower()
    if suffix not in (".yaml", ".yml", ".csv", ".tsv", ".txt"):
        _check_is_file(path)  # a missing file is reported as such first
        raise SidecarError(
            f"{display_path(path)}: unknown sidecar type {quote(suffix)} "
            "(use .csv, .tsv or .yaml)"
        )
    return suffix


def load_sidecar(path: str | Path) -> Sidecar:
    """Read a CSV, TSV or YAML sidecar; raises :class:`SidecarError` naming the file."""
    path = location(path)  # a local path, or a URL (s3://...)
    suffix = _sidecar_suffix(path)
    text = read_sidecar_text(path)
    if suffix in (".yaml", ".yml"):
        return sidecar_from_yaml(path, parse_yaml(path, text))
    records = _csv_records(path, io.StringIO(text, newline=""),
                           delimiter="\t" if suffix == ".tsv" else ",")
    return Sidecar(path, list(_without_duplicates(records)))


#: The name of a sidecar read from standard input (``--sidecar -``) in messages.
STDIN_SIDECAR = "standard input"


def sidecar_from_text(text: str, name: str = STDIN_SIDECAR) -> Sidecar:
    """A sidecar given as text (``--sidecar -``: a pipe from ``gsrwt estimate``), CSV, TSV
    or YAML told apart by its content: YAML when its first line is a list item, a flow
    collection or ``key: value``; else CSV, or TSV when that line has a tab. Relative file
    names in it (``camera``) are relative to the working directory."""
    path = Path(name)
    first = next((line.strip() for line in text.lstrip("\ufeff").splitlines()
                  if line.strip() and not line.lstrip().startswith("#")), "")
    if first.startswith(("-", "{", "[")) or re.match(r"^[^,\t]*:(\s|$)", first):
        return sidecar_from_yaml(path, parse_yaml(path, text))
    records = _csv_records(path, io.StringIO(text.lstrip("\ufeff"), newline=""),
                           delimiter="\t" if "\t" in first else ",")
    return Sidecar(path, list(_without_duplicates(records)))


def iter_sidecar_records(path: str | Path) -> Iterator[Record]:
    """The records of a sidecar as :func:`load_sidecar` reads them, one at a time: a CSV or
    TSV file is read as the records are taken (a YAML file at once), in memory that does not
    grow with the file. Raises :class:`SidecarError`, possibly after some records, when the
    file turns out bad. An image given twice is two records here (nothing is looked up by
    image; :func:`load_sidecar`, for lookups, refuses it)."""
    for chunk in iter_sidecar_chunks(path):
        yield from chunk.records()


#: Data rows of a CSV sidecar read at a time by :func:`iter_sidecar_chunks`, after a first
#: chunk of :data:`FIRST_CHUNK_ROWS` (whose rows a reader of the output sees first).
CHUNK_ROWS = 2048
FIRST_CHUNK_ROWS = 256


def iter_sidecar_chunks(path: str | Path, size: int = CHUNK_ROWS) -> Iterator[SidecarChunk]:
    """:func:`iter_sidecar_records` as chunks of ``size`` consecutive rows (the first of at
    most :data:`FIRST_CHUNK_ROWS`): a CSV or
    TSV file's as it is read (:class:`CsvChunk`, whose cells a caller may also take as
    columns), a YAML file's all at once. Raises :class:`SidecarError` as that does, after the
    chunk of the rows before the fault."""
    path = location(path)  # a local path, or a URL (s3://...)
    suffix = _sidecar_suffix(path)
    if suffix in (".yaml", ".yml"):
        yield RecordChunk(load_sidecar(path).records)
        return
    _check_is_file(path)
    name = display_path(path)
    try:
        with _open_text(path) as stream:
            yield from _csv_chunks(path, stream, "\t" if suffix == ".tsv" else ",", size)
    except UnicodeDecodeError as error:
        raise SidecarError(f"{name}: not UTF-8 text ({error.reason})") from None
    except OSError as error:
        raise SidecarError(f"{name}: cannot read ({error.strerror})") from None


def _open_text(path: Path | Location) -> IO[str]:
    """A sidecar's text stream (UTF-8, an optional BOM removed): a local file, or an object
    read as it is taken."""
    if isinstance(path, Location):
        return io.TextIOWrapper(path.open_read(), encoding="utf-8-sig", newline="")
    return path.open(encoding="utf-8-sig", newline="")


@dataclass(frozen=True)
class RecordChunk:
    """Records already made (a YAML sidecar's)."""

    items: list[Record]

    def records(self) -> Iterator[Record]:
        """The records, in the file's order."""
        return iter(self.items)

    def text_columns(self) -> None:
        """YAML values are typed, not text: no columns (see :meth:`CsvChunk.text_columns`)."""
        return None


@dataclass(frozen=True)
class CsvChunk:
    """Consecutive data rows of a CSV or TSV sidecar as the csv module read them: each row's
    cells and the line it starts on."""

    path: Path
    columns: list[str]
    rows: list[list[str]]
    lines: list[int]

    def records(self) -> Iterator[Record]:
        """The rows as records (blank rows skipped, cells stripped, empty cells absent, other
        columns than :data:`~gsrwt_cli.inputs.records.SIDECAR_FIELDS` ignored); a row with more
        cells
        than the header, or no image, raises :class:`SidecarError` naming its line."""
        path, columns = self.path, self.columns
        name = display_path(path)
        for cells, line_number in zip(self.rows, self.lines):
            if not any(cell.strip() for cell in cells):
                continue
            where = f"{name} line {line_number}"
            if len(cells) > len(columns):
                raise SidecarError(
                    f"{where}: {len(cells)} cells but the header has {len(columns)}"
                )
            row = {c: v for c, v in zip(columns, map(str.strip, cells)) if v}
            image = row.pop("image", "")
            if not image:
                raise SidecarError(f"{where}, field 'image': empty")
            values = row if row.keys() <= SIDECAR_FIELD_SET else {
                k: v for k, v in row.items() if k in SIDECAR_FIELD_SET}
            if "camera" in values:
                values = _with_camera_path(path, values)
            yield Record(image=image, values=values, where=where)

    def text_columns(self) -> dict[str, list[str]] | None:
        """The cells of ``image`` (stripped) and of each other column of
        :data:`~gsrwt_cli.inputs.records.SIDECAR_FIELDS`, as they are, when every row has exactly
        the header's cells and an image: the same values :meth:`records` gives, for a
        caller that takes them a column at a time (a cell that is empty or padded with
        spaces is kept as it is, for that caller to refuse). None for any other chunk, whose
        :meth:`records` tell."""
        width = len(self.columns)
        if not self.rows or any(len(cells) != width for cells in self.rows):
            return None
        cells_of = list(zip(*self.rows))
        columns = {column: list(cells) for column, cells in zip(self.columns, cells_of)
                   if column in SIDECAR_FIELD_SET}
        images = [cell.strip() for cell in cells_of[self.columns.index("image")]]
        if not all(images):
            return None
        columns["image"] = images
        return columns


#: One or the other kind of chunk.
SidecarChunk = RecordChunk | CsvChunk


def _checked_sidecar(path: Path, records: list[Record]) -> Sidecar:
    """The sidecar of ``records``; an image given twice is an error naming both places."""
    return Sidecar(path, list(_without_duplicates(records)))


def _without_duplicates(records: Iterable[Record]) -> Iterator[Record]:
    """``records``, checked as they pass: an image given twice is an error naming both places."""
    seen: dict[str, str] = {}
    for record in records:
        key = _normalize(record.image)
        if key in seen:
            raise SidecarError(
                f"{record.where}: image {quote(record.image)} is already in {seen[key]}"
            )
        seen[key] = record.where
        yield record


def _csv_records(path: Path, lines: Iterable[str], delimiter: str) -> Iterator[Record]:
    """Records of CSV/TSV text lines; ``line N`` is where the row starts, quoted newlines
    counted."""
    for chunk in _csv_chunks(path, lines, delimiter, CHUNK_ROWS):
        yield from chunk.records()


def _csv_chunks(path: Path, lines: Iterable[str], delimiter: str, size: int
                ) -> Iterator[CsvChunk]:
    """:class:`CsvChunk` of ``size`` rows at a time of CSV/TSV text lines, after the header's
    checks; a cell the csv module refuses raises :class:`SidecarError` naming its line, after
    the chunk of the rows before it."""
    name = display_path(path)
    reader = csv.reader(lines, delimiter=delimiter)
    rows: list[list[str]] = []
    starts: list[int] = []
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
        row_start = reader.line_num + 1
        limit = min(size, FIRST_CHUNK_ROWS)  # the first rows out soon
        for cells in reader:
            rows.append(cells)
            starts.append(row_start)
            row_start = reader.line_num + 1
            if len(rows) == limit:
                yield CsvChunk(path, columns, rows, starts)
                rows, starts, limit = [], [], size
    except csv.Error as error:
        if rows:
            yield CsvChunk(path, columns, rows, starts)
        raise SidecarError(
            f"{name} line {reader.line_num}: {one_line(str(error), 200)}"
        ) from None
    if rows:
        yield CsvChunk(path, columns, rows, starts)


def parse_yaml(path: Path, text: str) -> Any:
    """The YAML document of a sidecar, read by the bounded loader (:mod:`~gsrwt_cli.io.safe_yaml`).

    Raises :class:`SidecarError` naming the file and, when known, the line.
    """
    from ..io.safe_yaml import YamlInputError, load_yaml  # PyYAML: only for YAML files

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
        import yaml

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
