"""The one table writer: rows of named values out as table, csv, tsv, json, jsonl or markdown.

Rows stream out as they come (csv, tsv, jsonl, and json as a valid array); the aligned human
``table`` and ``markdown`` are laid out when the table closes. Missing values (``None``, NaN,
infinities) are empty cells in text formats and ``null`` in JSON.
"""

from __future__ import annotations

import csv
import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import IO, Any

from ..base.messages import escape_controls

FORMATS = ("table", "csv", "tsv", "json", "jsonl", "markdown")
#: What ``str.splitlines`` breaks a line at: escaped in the aligned formats' cells.
_LINE_BREAK = re.compile("[\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029]")
#: Decimal places of floats in the machine formats and in the human ones.
MACHINE_DECIMALS = 6
HUMAN_DECIMALS = 3
_SURROGATE = re.compile("[\ud800-\udfff]")


def format_from_extension(path: str) -> str | None:
    """The table format a file name asks for (.csv, .tsv, .json, .jsonl, .md), else None."""
    suffix = path.rsplit(".", 1)[-1].lower() if "." in path else ""
    return {"csv": "csv", "tsv": "tsv", "json": "json", "jsonl": "jsonl", "md": "markdown"}.get(
        suffix
    )


def _json_value(value: Any) -> Any:
    if isinstance(value, float):
        return round(value, MACHINE_DECIMALS) if math.isfinite(value) else None
    return value


#: What a float formatted and stripped becomes in a cell when it is not finite, or -0.
_NOT_FINITE_OR_MINUS_ZERO = {"nan": "", "inf": "", "-inf": "", "-0": "0"}


#: A cell the csv module quotes, per format: the delimiter, a quote or a line break in it.
_TO_QUOTE = {"csv": re.compile('[,"\r\n]'), "tsv": re.compile('[\t"\r\n]')}


def _text_cells(values: list[Any], decimals: int) -> list[str]:
    """:func:`_text_value` of each value (finite floats, most cells, the short way)."""
    if decimals <= 0:
        return [_text_value(value, decimals) for value in values]
    spec = f".{decimals}f"
    kinds = set(map(type, values))
    if kinds == {str}:  # a column of names
        return list(values)
    if kinds <= {bool, type(None)}:  # a column of flags
        return ["" if value is None else "true" if value else "false" for value in values]
    if kinds == {float}:  # a column of numbers: in bulk
        cells = [format(value, spec).rstrip("0").rstrip(".") for value in values]
        fixed = _NOT_FINITE_OR_MINUS_ZERO.get
        return [fixed(cell, cell) for cell in cells]
    finite, cells = math.isfinite, []
    for value in values:
        if type(value) is float and finite(value):
            text = format(value, spec).rstrip("0").rstrip(".")
            cells.append("0" if text == "-0" else text)
        else:
            cells.append(_text_value(value, decimals))
    return cells


def _text_value(value: Any, decimals: int) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if not math.isfinite(value):
            return ""
        text = f"{value:.{decimals}f}"
        if "." in text:
            text = text.rstrip("0").rstrip(".")
        return "0" if text == "-0" else text
    return str(value)


class TableWriter:
    """Write rows with a fixed list of columns to a text stream in one of :data:`FORMATS`.

    Each row is flushed as it is written (a slow batch shows its progress), unless
    ``flush_rows`` is False (a fast producer: the stream's buffer then goes out as it fills).
    """

    def __init__(self, stream: IO[str], columns: Sequence[str], fmt: str,
                 flush_rows: bool = True) -> None:
        if fmt not in FORMATS:
            raise ValueError(f"unknown table format {fmt!r}; choose one of {', '.join(FORMATS)}")
        self.stream = stream
        self.columns = list(columns)
        self.fmt = fmt
        self.flush_rows = flush_rows
        self._rows_written = 0
        self._buffer: list[list[str]] = []
        self._csv = None
        if fmt in ("csv", "tsv"):
            self._csv = csv.writer(
                stream, dialect="excel-tab" if fmt == "tsv" else "excel", lineterminator="\n"
            )
            self._csv.writerow(self.columns)

    def write_row(self, row: Mapping[str, Any]) -> None:
        """Write one row; keys not in the columns are ignored, missing ones are empty."""
        values = [row.get(column) for column in self.columns]
        if self._csv is not None:
            self._csv.writerow(_text_value(v, MACHINE_DECIMALS) for v in values)
        elif self.fmt in ("json", "jsonl"):
            record = {c: _json_value(v) for c, v in zip(self.columns, values)}
            text = json.dumps(record, ensure_ascii=False)
            if _SURROGATE.search(text):  # a file name that is not UTF-8: escape it, so that
                text = json.dumps(record)  # the JSON stays valid and json.loads gives it back
            if self.fmt == "jsonl":
                self.stream.write(text + "\n")
            else:
                self.stream.write(("[\n  " if self._rows_written == 0 else ",\n  ") + text)
        else:  # one line per row: what would break a line (a newline in a name) escaped
            self._buffer.append([_LINE_BREAK.sub(lambda m: escape_controls(m.group(0)),
                                                 _text_value(v, HUMAN_DECIMALS))
                                 for v in values])
        self._rows_written += 1
        if self.flush_rows:
            self.stream.flush()

    def write_rows(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Write many rows: in csv and tsv formatted a column at a time (as :meth:`write_row`
        would, faster), flushed once."""
        if self._csv is None:
            for row in rows:
                self.write_row(row)
            return
        rows = list(rows)
        cells = [_text_cells([row.get(column) for row in rows], MACHINE_DECIMALS)
                 for column in self.columns]
        self._csv.writerows(zip(*cells))
        self._rows_written += len(rows)
        if self.flush_rows:
            self.stream.flush()

    def write_columns(self, columns: Mapping[str, Sequence[Any]], count: int) -> None:
        """Write ``count`` rows given as columns (a missing column is empty), as
        :meth:`write_rows` would write them."""
        if self._csv is None:
            self.write_rows({name: values[index] for name, values in columns.items()}
                            for index in range(count))
            return
        empty = [None] * count
        cells = [_text_cells(list(columns.get(column, empty)), MACHINE_DECIMALS)
                 for column in self.columns]
        delimiter = "\t" if self.fmt == "tsv" else ","
        if any(_TO_QUOTE[self.fmt].search("".join(column)) for column in cells):
            self._csv.writerows(zip(*cells))  # some cell to quote, as the csv module does
        else:
            self.stream.write("".join(f"{delimiter.join(row)}\n" for row in zip(*cells)))
        self._rows_written += count
        if self.flush_rows:
            self.stream.flush()

    def close(self) -> None:
        """Finish the table (close the JSON array, lay out the aligned formats)."""
        if self.fmt == "json":
            self.stream.write("[]\n" if self._rows_written == 0 else "\n]\n")
        elif self.fmt == "table":
            widths = [
                max([len(c)] + [len(r[i]) for r in self._buffer])
                for i, c in enumerate(self.columns)
            ]
            lines = [self.columns, *self._buffer]
            for cells in lines:
                line = "  ".join(_align(cell, w) for cell, w in zip(cells, widths))
                self.stream.write(line.rstrip() + "\n")
        elif self.fmt == "markdown":
            escaped = [[cell.replace("|", "\\|") for cell in r] for r in self._buffer]
            self.stream.write("| " + " | ".join(self.columns) + " |\n")
            self.stream.write("|" + "|".join("---" for _ in self.columns) + "|\n")
            for cells in escaped:
                self.stream.write("| " + " | ".join(cells) + " |\n")
        self.stream.flush()


def _align(cell: str, width: int) -> str:
    """Right-align numbers, left-align text."""
    try:
        float(cell)
    except ValueError:
        return cell.ljust(width)
    return cell.rjust(width)


def write_table(
    stream: IO[str], columns: Sequence[str], rows: Iterable[Mapping[str, Any]], fmt: str
) -> None:
    """Write all ``rows`` at once."""
    writer = TableWriter(stream, columns, fmt)
    writer.write_rows(rows)
    writer.close()


def read_table(stream: IO[str], fmt: str) -> list[dict[str, Any]]:
    """The rows of a table this module wrote in a machine format (csv, tsv, json, jsonl).

    Text formats give every value as a string (empty cells as ``None``), which
    :class:`TableWriter` writes back unchanged. Raises ``ValueError`` for anything else.
    """
    if fmt in ("csv", "tsv"):
        reader = csv.DictReader(stream, dialect="excel-tab" if fmt == "tsv" else "excel")
        return [{k: (v if v != "" else None) for k, v in row.items()} for row in reader]
    if fmt == "json":
        rows = json.load(stream)
    elif fmt == "jsonl":
        rows = [json.loads(line) for line in stream if line.strip()]
    else:
        raise ValueError(f"cannot read back a {fmt} table")
    if not isinstance(rows, list) or not all(isinstance(row, dict) for row in rows):
        raise ValueError("not a table of rows")
    return rows


class YamlRecordWriter:
    """A table as a YAML list of records, one per row with its non-empty cells, written as
    the rows come (``gsrwt estimate -o poses.yaml``: a YAML sidecar that ``gsrwt rectify
    --sidecar`` reads). Floats are rounded as in the machine formats."""

    def __init__(self, stream: IO[str], columns: Sequence[str]) -> None:
        self.stream = stream
        self.columns = list(columns)
        self._rows_written = 0

    def write_row(self, row: Mapping[str, Any]) -> None:
        import yaml

        record = {column: _json_value(row[column]) for column in self.columns
                  if row.get(column) is not None and row.get(column) != ""}
        record = {name: value for name, value in record.items() if value is not None}
        self.stream.write(yaml.safe_dump([record], sort_keys=False, allow_unicode=True))
        self.stream.flush()
        self._rows_written += 1

    def close(self) -> None:
        """An empty list when no row was written."""
        if self._rows_written == 0:
            self.stream.write("[]\n")
