"""The one table writer: rows of named values out as table, csv, tsv, json, jsonl or markdown.

Rows stream out as they come (csv, tsv, jsonl, and json as a valid array); the aligned human
``table`` and ``markdown`` are laid out when the table closes. Missing values (``None``, NaN,
infinities) are empty cells in text formats and ``null`` in JSON.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import IO, Any

from ..base.messages import QUOTE_LIMIT, escape_controls, quote, shorten
from ..base.numerals import parse_decimal, parse_whole

FORMATS = ("table", "csv", "tsv", "json", "jsonl", "markdown")
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
        else:
            self._buffer.append([_text_value(v, HUMAN_DECIMALS) for v in values])
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


# --------------------------------------------------------------------------------------------
# Shards: the tables of ``--shard K/N`` runs joined into one
# --------------------------------------------------------------------------------------------

#: N of ``--shard K/N`` at most (a bound, so that no N is too big to count to).
MAX_SHARDS = 1_000_000
#: ``gsrwt.3-of-8.csv``: the K and N of a shard's table name.
SHARD_NAME = re.compile(r"\.([0-9]+)-of-([0-9]+)\.[A-Za-z]+$")


def _shard_numbers(k_text: str, n_text: str) -> tuple[int, int] | None:
    """``(K, N)`` if both are whole numbers in ASCII digits (:func:`parse_whole`) and
    ``1 <= K <= N <=`` :data:`MAX_SHARDS`, else None."""
    try:
        k, n = parse_whole(k_text), parse_whole(n_text)
    except ValueError:
        return None
    return (k, n) if 1 <= k <= n <= MAX_SHARDS else None


def parse_shard(text: str) -> tuple[int, int]:
    """``K/N`` (the K-th of N slices) as ``(K, N)``: ASCII digits only (no sign, space or
    underscore), ``1 <= K <= N <=`` :data:`MAX_SHARDS`; ``ValueError`` otherwise."""
    parts = text.split("/")
    found = _shard_numbers(*parts) if len(parts) == 2 else None
    if found is None:
        raise ValueError(f"expected K/N in ASCII digits with 1 <= K <= N <= {MAX_SHARDS}, "
                         f"such as 2/8, got {quote(text)}")
    return found


def shard_slice(count: int, k: int, n: int) -> range:
    """The indices of the K-th of N contiguous slices of ``count`` items.

    Slices differ in size by one at most, cover ``range(count)`` in order and never overlap,
    so that shard 1's items, then shard 2's, ... are the items in input order.
    """
    return range((k - 1) * count // n, k * count // n)


def shard_table_name(name: str, k: int, n: int) -> str:
    """``gsrwt.csv`` -> ``gsrwt.2-of-8.csv``: the table of shard ``k`` of ``n``."""
    stem, dot, extension = name.rpartition(".")
    return f"{stem}.{k}-of-{n}.{extension}" if dot else f"{name}.{k}-of-{n}"


def shard_of_name(name: str) -> tuple[int, int] | None:
    """``(K, N)`` from a shard table's name (``gsrwt.2-of-8.csv``), or None for a name with no
    ``K-of-N``; :class:`MergeError` for one whose K and N are not shard numbers."""
    match = SHARD_NAME.search(name)
    if match is None:
        return None
    found = _shard_numbers(match.group(1), match.group(2))
    if found is None:
        raise MergeError(f"{name}: its name says shard {match.group(1)} of {match.group(2)}, "
                         f"not K of N with 1 <= K <= N <= {MAX_SHARDS}")
    return found


class MergeError(ValueError):
    """Shard tables that do not make one table; the message names the table and the fault."""


def order_shards(names: Sequence[str]) -> list[str]:
    """Shard tables in shard order (by the ``K-of-N`` in their names), all N of them.

    Tables whose names carry no ``K-of-N`` keep the order given (then none may carry one).
    Raises :class:`MergeError` for a missing, repeated or mismatched shard.
    """
    shards = [shard_of_name(name) for name in names]
    if all(shard is None for shard in shards):
        return list(names)
    if any(shard is None for shard in shards):
        name = names[shards.index(None)]
        raise MergeError(f"{name}: no K-of-N in its name, unlike the other tables")
    totals = {n for _, n in shards}  # type: ignore[misc]
    if len(totals) != 1:
        raise MergeError("the tables come from different shardings: "
                         + ", ".join(sorted(f"of {n}" for n in totals)))
    (total,) = totals
    by_k: dict[int, str] = {}
    for name, (k, _) in zip(names, shards):  # type: ignore[misc]
        if k in by_k:
            raise MergeError(f"{name}: shard {k}-of-{total} is also {by_k[k]}")
        by_k[k] = name
    missing = total - len(by_k)
    if missing:
        named = list(itertools.islice((k for k in range(1, total + 1) if k not in by_k), 10))
        listed = ", ".join(map(str, named)) + (f" and {missing - 10} more" if missing > 10 else "")
        raise MergeError(f"shard {listed} of {total} missing (got {len(by_k)} of {total} tables)")
    return [by_k[k] for k in range(1, total + 1)]


# --------------------------------------------------------------------------------------------
# Tables read back as input: each cell checked against what gsrwt writes in its column
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CellKind:
    """What the cells of a column hold. ``expected`` words it for messages; ``accepts`` checks
    a cell as read: from csv or tsv (``text``) a string, or None for an empty cell; from json
    or jsonl any JSON value, where a number must be a number, not a string of digits."""

    expected: str
    accepts: Callable[[Any, bool], bool]


def _decimal_text(cell: str) -> bool:
    try:
        parse_decimal(cell)
    except ValueError:
        return False
    return True


def _finite_number(value: Any) -> bool:
    return type(value) in (int, float) and math.isfinite(value)


def _nine_numbers(value: Any) -> bool:
    if not isinstance(value, str):
        return False
    numbers = value.split(" ")
    return len(numbers) == 9 and all(_decimal_text(number) for number in numbers)


def _positive_whole(value: Any, text: bool) -> bool:
    if value is None:
        return True
    if text:
        try:
            return parse_whole(value) > 0
        except ValueError:
            return False
    return type(value) is int and value > 0


TEXT = CellKind("text", lambda value, text: value is None or isinstance(value, str))
NUMBER = CellKind("a number", lambda value, text: value is None or (
    _decimal_text(value) if text else _finite_number(value)))
POSITIVE_WHOLE = CellKind("a whole number above 0", _positive_whole)
FLAG = CellKind("true or false", lambda value, text: value is None or (
    value in ("true", "false") if text else type(value) is bool))
MATRIX = CellKind("nine numbers", lambda value, text: value is None or _nine_numbers(value))
NAME = CellKind("the image's name", lambda value, text: isinstance(value, str) and value != "")


def choice(*values: str) -> CellKind:
    """A cell that is one of ``values`` (never empty)."""
    return CellKind(f"{', '.join(values[:-1])} or {values[-1]}",
                    lambda value, text: value in values)


@dataclass(frozen=True)
class TableSchema:
    """A table gsrwt writes: ``command`` (``gsrwt rectify``), its ``columns`` in order, and
    the :class:`CellKind` of each (:data:`TEXT` where ``kinds`` names none)."""

    command: str
    columns: tuple[str, ...]
    kinds: Mapping[str, CellKind]

    def columns_problem(self, names: Sequence[str]) -> str | None:
        """What is wrong with ``names`` as this table's columns, or None."""
        seen: set[str] = set()
        for name in names:
            if name in seen:
                return f"column {quote(name)} twice"
            seen.add(name)
        known = set(self.columns)
        missing = [name for name in self.columns if name not in seen]
        unknown = [name for name in names if name not in known]
        problems = [f"{what} {quote(found[0])}" + (f" (and {len(found) - 1} more)"
                                                      if len(found) > 1 else "")
                    for what, found in (("no column", missing), ("unknown column", unknown))
                    if found]
        if not problems and list(names) != list(self.columns):
            problems = [f"its columns are {self.command}'s in another order"]
        return ", ".join(problems) or None

    def check_row(self, where: str, row: Mapping[str, Any], text: bool) -> None:
        """Raise :class:`MergeError` naming ``where`` and the column of the first cell of
        ``row`` its column's kind does not accept."""
        for column in self.columns:
            kind, value = self.kinds.get(column, TEXT), row.get(column)
            if not kind.accepts(value, text):
                shown = quote(value or "") if text else shorten(
                    escape_controls(json.dumps(value, ensure_ascii=False)), QUOTE_LIMIT)
                raise MergeError(f"{where}, column {column}: expected {kind.expected}, "
                                 f"got {shown}")


def read_shard_table(name: str, stream: IO[str], fmt: str,
                     schema: TableSchema) -> list[dict[str, Any]]:
    """The rows of one table to merge (csv, tsv, json or jsonl), each cell checked against
    ``schema``; :class:`MergeError` names the table, the line or row, and what is wrong.

    Cells of text tables stay the strings they are (empty ones None), so that the merged
    table repeats them as they were written.
    """
    try:
        if fmt in ("csv", "tsv"):
            return _read_text_table(name, stream, fmt, schema)
        if fmt == "json":
            rows = json.load(stream)
        else:
            rows = [json.loads(line) for line in stream if line.strip()]
    except MergeError:
        raise
    except (ValueError, csv.Error, RecursionError) as error:
        raise MergeError(f"{name}: not a table gsrwt wrote ({error})") from None
    if not isinstance(rows, list):
        raise MergeError(f"{name}: not a table gsrwt wrote (not a JSON array of rows)")
    for number, row in enumerate(rows, 1):
        where = f"{name} row {number}"
        if not isinstance(row, dict):
            raise MergeError(f"{where}: not a row of named values")
        problem = schema.columns_problem(list(row))
        if problem is not None:
            raise MergeError(f"{where}: {problem}")
        schema.check_row(where, row, text=False)
    return rows


def _read_text_table(name: str, stream: IO[str], fmt: str,
                     schema: TableSchema) -> list[dict[str, Any]]:
    reader = csv.reader(stream, dialect="excel-tab" if fmt == "tsv" else "excel")
    header = next(reader, [])
    problem = schema.columns_problem(header)
    if problem is not None:
        raise MergeError(f"{name}: not a table of {schema.command}: {problem}")
    rows = []
    while True:
        line = reader.line_num + 1  # where the row starts (a quoted cell may span lines)
        cells = next(reader, None)
        if cells is None:
            return rows
        where = f"{name} line {line}"
        if len(cells) != len(header):
            raise MergeError(f"{where}: {len(cells)} cells, not the {len(header)} of the "
                             "columns")
        row = {column: cell if cell != "" else None for column, cell in zip(header, cells)}
        schema.check_row(where, row, text=True)
        rows.append(row)


def write_merged(parts: Iterable[list[dict[str, Any]]], columns: Sequence[str],
                 output: IO[str], fmt: str) -> int:
    """Write the rows of ``parts`` (tables read by :func:`read_shard_table`, in order) as one
    table with ``columns``; returns the number of rows written."""
    writer = TableWriter(output, columns, fmt)
    count = 0
    for rows in parts:
        writer.write_rows(rows)
        count += len(rows)
    writer.close()
    return count
