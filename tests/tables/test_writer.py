"""The one table writer (``tables/writer.py``): every format written and read back.

Rows with every kind of value a table holds (names that need quoting, numbers rounded to
the format's decimals, missing and non-finite values, flags, a name that is not UTF-8) are
written in each format and read back with ``tests/helpers/tables.py`` (the standard
library's csv and json, and the layout of the aligned formats), not the package's reader;
the package's reader for reruns must give back what writes the same table again.
"""

from __future__ import annotations

import io
import json
import math
import os

import pytest

from gsrwt_cli.tables.writer import (
    FORMATS,
    TableWriter,
    format_from_extension,
    read_table,
    write_table,
)
from tests.helpers import tables

COLUMNS = ("image", "pan_deg", "a_px", "out_width", "horizon_in_image", "error")
NOT_UTF8 = os.fsdecode(b"bad\xff.png")
ROWS = [
    {"image": "plain.png", "pan_deg": 15.0, "a_px": 427.46230466, "out_width": 320,
     "horizon_in_image": False, "error": None},
    {"image": 'a, "quoted"\tname|piped.jpg', "pan_deg": -0.0, "a_px": math.nan,
     "out_width": None, "horizon_in_image": True, "error": "line 3, field 'tilt': too big"},
    {"image": "two\nlines.png", "pan_deg": 1e-9, "a_px": math.inf, "out_width": 7,
     "horizon_in_image": None, "error": ""},
    {"image": NOT_UTF8, "pan_deg": 89.9999996, "a_px": -2.5, "out_width": 1,
     "horizon_in_image": False, "error": None},
]
#: What the machine formats (6 decimals) and the human ones (3) print of ``pan_deg`` and
#: ``a_px`` of each row.
PAN = {6: ["15", "0", "0", "90"], 3: ["15", "0", "0", "90"]}
A_PX = {6: ["427.462305", "", "", "-2.5"], 3: ["427.462", "", "", "-2.5"]}


def written(fmt: str, rows=ROWS) -> str:
    stream = io.StringIO()
    write_table(stream, COLUMNS, rows, fmt)
    return stream.getvalue()


@pytest.mark.parametrize("fmt", ["csv", "tsv", "markdown", "table"])
def test_text_formats_read_back_cell_for_cell(fmt):
    """Names come back as given (quoted in csv and tsv, ``|`` escaped in markdown), numbers
    to the format's decimals without trailing zeros, ``-0`` as 0, missing and non-finite
    values as empty cells, flags as true and false."""
    # A line break in a name would split the row of the laid-out formats: it is escaped.
    kept = list(range(len(ROWS)))
    rows = [ROWS[index] for index in kept]
    back = tables.read_table(written(fmt, rows), fmt)
    decimals = 3 if fmt in ("markdown", "table") else 6
    assert [list(row) for row in back] == [list(COLUMNS)] * len(rows)
    for got, index in zip(back, kept):
        row = ROWS[index]
        laid_out = fmt in ("markdown", "table")
        assert got["image"] == (row["image"].replace("\n", "\\n") if laid_out
                                else row["image"])
        assert (got["pan_deg"], got["a_px"]) == (PAN[decimals][index], A_PX[decimals][index])
        assert got["out_width"] == ("" if row["out_width"] is None else str(row["out_width"]))
        flag = row["horizon_in_image"]
        assert got["horizon_in_image"] == ("" if flag is None else str(flag).lower())
        assert got["error"] == (row["error"] or "")


@pytest.mark.parametrize("fmt", ["json", "jsonl"])
def test_json_formats_keep_types_and_write_null_for_what_is_not_a_number(fmt):
    text = written(fmt)
    back = tables.read_table(text, fmt)
    assert [list(row) for row in back] == [list(COLUMNS)] * len(ROWS)
    assert [row["pan_deg"] for row in back] == [15.0, 0.0, 0.0, 90.0]
    assert [row["a_px"] for row in back] == [427.462305, None, None, -2.5]
    assert [row["out_width"] for row in back] == [320, None, 7, 1]
    assert [row["horizon_in_image"] for row in back] == [False, True, None, False]
    assert [row["image"] for row in back] == [row["image"] for row in ROWS]
    assert "NaN" not in text and "Infinity" not in text  # valid JSON for any reader
    text.encode("utf-8")  # the name that is not UTF-8 escaped: valid UTF-8 for any reader
    if fmt == "jsonl":
        assert len(text.splitlines()) == len(ROWS)  # a row per line, the newline escaped


def test_an_empty_table_is_a_header_or_an_empty_array():
    assert written("csv", []) == ",".join(COLUMNS) + "\n"
    assert written("tsv", []) == "\t".join(COLUMNS) + "\n"
    assert json.loads(written("json", [])) == []
    assert written("jsonl", []) == ""


def test_rows_columns_and_one_row_at_a_time_write_the_same_bytes():
    """``write_row`` one by one, ``write_rows`` at once and ``write_columns`` give the
    same table in every format (the bulk paths format whole columns at a time)."""
    columns = {name: [row.get(name) for row in ROWS] for name in COLUMNS}
    for fmt in FORMATS:
        one, many, by_columns = io.StringIO(), io.StringIO(), io.StringIO()
        writer = TableWriter(one, COLUMNS, fmt)
        for row in ROWS:
            writer.write_row(row)
        writer.close()
        write_table(many, COLUMNS, ROWS, fmt)
        writer = TableWriter(by_columns, COLUMNS, fmt)
        writer.write_columns(columns, len(ROWS))
        writer.close()
        assert one.getvalue() == many.getvalue() == by_columns.getvalue(), fmt


@pytest.mark.parametrize("fmt", ["csv", "tsv"])
def test_a_column_with_only_a_line_break_to_quote_is_quoted_in_bulk_too(fmt):
    """``write_columns`` writes plain columns by joining them and quotes through the csv
    module only where a cell needs it: a line break alone must be enough."""
    stream = io.StringIO()
    writer = TableWriter(stream, ("image", "out_width"), fmt)
    writer.write_columns({"image": ["a.png", "two\nlines.png"], "out_width": [1, 2]}, 2)
    writer.close()
    assert [row["image"] for row in tables.read_table(stream.getvalue(), fmt)] == [
        "a.png", "two\nlines.png"]


def test_keys_outside_the_columns_are_left_out_and_missing_ones_empty():
    back = tables.read_table(written("csv", [{"image": "x.png", "extra": 5}]))
    assert back == [{"image": "x.png", "pan_deg": "", "a_px": "", "out_width": "",
                     "horizon_in_image": "", "error": ""}]


@pytest.mark.parametrize("fmt", ["csv", "tsv", "json", "jsonl"])
def test_what_the_package_reads_back_writes_the_same_table_again(fmt):
    """The reader of reruns (``read_table``): its rows, written again, are the same bytes."""
    first = written(fmt)
    rows = read_table(io.StringIO(first, newline=""), fmt)
    assert len(rows) == len(ROWS)
    assert written(fmt, rows) == first


def test_the_reader_refuses_what_is_no_table_of_rows():
    for text, fmt in (("[1, 2]", "json"), ('{"a": 1}', "json"), ("| a |", "markdown")):
        with pytest.raises(ValueError):
            read_table(io.StringIO(text), fmt)
    with pytest.raises(ValueError, match="unknown table format"):
        TableWriter(io.StringIO(), COLUMNS, "xlsx")


def test_file_names_give_their_format():
    assert [format_from_extension(name) for name in
            ("t.csv", "T.TSV", "t.json", "t.jsonl", "t.md", "t.txt", "csv")] == [
        "csv", "tsv", "json", "jsonl", "markdown", None, None]


@pytest.mark.parametrize("fmt", ["table", "markdown"])
def test_the_aligned_formats_keep_one_line_per_row_whatever_a_name_holds(fmt):
    """A file name with a newline or a tab (legal on POSIX) is written with escapes in the
    human formats, so that every row stays one line of the layout."""
    stream = io.StringIO()
    writer = TableWriter(stream, ["image", "pan"], fmt)
    writer.write_row({"image": "a\nb\u2028c.jpg", "pan": 1.5})
    writer.close()
    lines = stream.getvalue().splitlines()
    assert len(lines) == (2 if fmt == "table" else 3)
    assert "a\\nb\\x2028c.jpg" in lines[-1]
