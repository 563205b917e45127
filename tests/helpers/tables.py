"""One reader of the tables gsrwt prints and writes, in every format it has.

Written here with the standard library alone (the csv and json modules, and the layout of
the aligned formats), not with the package's own reader, so that a test of a table does not
read it back with the code that wrote it.
"""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path
from typing import Any

#: The format a table file's extension names.
FORMAT_OF_EXTENSION = {".csv": "csv", ".tsv": "tsv", ".json": "json", ".jsonl": "jsonl",
                       ".md": "markdown"}
#: A markdown cell separator: a ``|`` the writer did not escape.
_MARKDOWN_SEPARATOR = re.compile(r"(?<!\\)\|")


def read_table(source: Path | str | bytes, fmt: str | None = None) -> list[dict[str, Any]]:
    """The rows of a table: ``source`` is a file (a ``Path``; its format from its extension
    unless ``fmt`` says) or the table's text (``str`` or ``bytes``, such as a command's
    stdout; ``fmt`` default csv, what gsrwt prints to a pipe).

    ``fmt``: csv, tsv, json, jsonl, markdown or table (the aligned one). Text formats give
    every cell as a string (an empty cell as ``""``), JSON its own types. Bytes that are not
    UTF-8 (file names that are not) come back as the surrogate escapes Python gives them.
    """
    if isinstance(source, Path):
        fmt = fmt or FORMAT_OF_EXTENSION.get(source.suffix.lower())
        assert fmt is not None, f"{source}: no table format for this extension"
        text = source.read_bytes().decode("utf-8", "surrogateescape")
    elif isinstance(source, bytes):
        text = source.decode("utf-8", "surrogateescape")
    else:
        text = source
    fmt = fmt or "csv"
    if fmt in ("csv", "tsv"):
        return list(csv.DictReader(io.StringIO(text, newline=""),
                                   dialect="excel-tab" if fmt == "tsv" else "excel"))
    if fmt == "json":
        return json.loads(text)
    if fmt == "jsonl":
        return [json.loads(line) for line in text.splitlines() if line.strip()]
    if fmt == "markdown":
        return _markdown_rows(text)
    if fmt == "table":
        return _aligned_rows(text)
    raise ValueError(f"no reader for the table format {fmt!r}")


def by_image_name(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """The rows keyed by their image's file name (the last part of the ``image`` column)."""
    return {Path(row["image"]).name: row for row in rows}


def _markdown_rows(text: str) -> list[dict[str, str]]:
    """``| a | b |`` lines: the header, the ``|---|`` line, then a line per row."""
    header, rule, *lines = text.splitlines()
    assert set(rule) <= set("|-"), rule

    def cells(line: str) -> list[str]:
        assert line.startswith("| ") and line.endswith(" |"), line
        parts = _MARKDOWN_SEPARATOR.split(line[2:-2])
        return [part.strip().replace("\\|", "|") for part in parts]

    columns = cells(header)
    return [dict(zip(columns, cells(line), strict=True)) for line in lines]


def _aligned_rows(text: str) -> list[dict[str, str]]:
    """The aligned table: column names left-aligned over their cells, columns two spaces
    apart (names hold no space), so each column is the span from its name to the next."""
    header, *lines = text.splitlines()
    columns = header.split()
    starts = [match.start() for match in re.finditer(r"\S+", header)]
    ends = [start - 2 for start in starts[1:]] + [None]
    return [{name: line[start:end].strip() for name, start, end in zip(columns, starts, ends)}
            for line in lines]
