"""Tables read back: the shards of ``--shard K/N`` runs, and the cells of every table gsrwt
reads back checked against what it writes in each column (:data:`RECTIFY_TABLE`, the one
description of the rectify table's cells, which ``gsrwt tables merge`` and reruns share).
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
from ..inputs.guides import ASPECT_SOURCES
from .columns import (
    FOCAL_SOURCES,
    LENS_SOURCES,
    METADATA_VALUES,
    ORIENTATION_VALUES,
    PARAMS_COLUMNS,
    POSE_SOURCES,
    RECTIFY_COLUMNS,
    RECTIFY_STATUSES,
)
from .writer import TableWriter

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


def choice(*values: str, optional: bool = False) -> CellKind:
    """A cell that is one of ``values`` (empty too, if ``optional``)."""
    return CellKind(f"{', '.join(values[:-1])} or {values[-1]}",
                    lambda value, text: value in values or (optional and value is None))


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

    def cell_problem(self, row: Mapping[str, Any], text: bool) -> tuple[str, CellKind] | None:
        """The column and kind of the first cell of ``row`` its column's kind does not
        accept, or None."""
        for column in self.columns:
            kind = self.kinds.get(column, TEXT)
            if not kind.accepts(row.get(column), text):
                return column, kind
        return None

    def check_row(self, where: str, row: Mapping[str, Any], text: bool) -> None:
        """Raise :class:`MergeError` naming ``where`` and the column of the first cell of
        ``row`` its column's kind does not accept."""
        problem = self.cell_problem(row, text)
        if problem is not None:
            column, kind = problem
            value = row.get(column)
            shown = quote(value or "") if text else shorten(
                escape_controls(json.dumps(value, ensure_ascii=False)), QUOTE_LIMIT)
            raise MergeError(f"{where}, column {column}: expected {kind.expected}, "
                             f"got {shown}")


#: The table ``gsrwt rectify`` writes, each of its columns with what its cells hold.
RECTIFY_TABLE = TableSchema(
    "gsrwt rectify", RECTIFY_COLUMNS,
    {**{name: NUMBER for name in (*PARAMS_COLUMNS, "confidence", "aspect", "scale")},
     "image": NAME, "horizon_in_image": FLAG, "out_width": POSITIVE_WHOLE,
     "out_height": POSITIVE_WHOLE, "homography": MATRIX,
     "focal_source": choice(*FOCAL_SOURCES, optional=True),
     "pose_source": choice(*POSE_SOURCES, optional=True),
     "aspect_source": choice(*ASPECT_SOURCES, optional=True),
     "orientation": choice(*ORIENTATION_VALUES, optional=True),
     "metadata": choice(*METADATA_VALUES, optional=True),
     "lens_source": choice(*LENS_SOURCES, optional=True),
     "status": choice(*RECTIFY_STATUSES)},
)


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
