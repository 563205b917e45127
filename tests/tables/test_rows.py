"""The rows of the public tables (``tables/rows.py``): params rows of many views computed
together, against each view's own row (a second implementation, compared as the table prints
it); the rectify, gaze, track, lines and match rows from the values they describe."""

from __future__ import annotations

import io

import pytest

from gsrwt_cli.tables.rows import PARAMS_COLUMNS
from tests.helpers.printed import PrintedComparison, assert_table_prints_rows


def _random_record(rng, index: int) -> tuple[str, dict[str, str], str]:
    """A sidecar record of a random kind: plain, with size or principal point, frontal,
    invalid, near the horizon limit, rolled (the long way)."""
    values = {"pan": f"{rng.uniform(-89.99, 89.99):.3f}",
              "tilt": f"{rng.uniform(-89.99, 89.99):.3f}", "focal": f"{rng.uniform(1, 3000):.2f}"}
    kind = rng.randrange(10)
    extra = [
        {"width": str(rng.randint(1, 5000)), "height": str(rng.randint(1, 5000))},
        {"cx": f"{rng.uniform(-100, 1000):.1f}", "cy": f"{rng.uniform(-100, 1000):.1f}"},
        {"cx": "10", "cy": "20", "width": "30", "height": "40"},
        {"pan": "0", "tilt": "0", "width": "640", "height": "480"},
        {"pan": "0", "tilt": "-0"},
        {"tilt": "95"},
        {"width": "64.5", "height": "3"},
        {"pan": "89.99999999", "tilt": "89.9999999", "focal": "1"},
        {"width": "640", "cx": "nan", "cy": "1"},
        {"roll": "5", "width": "640", "height": "480"},
    ][kind]
    return f"i{index}.png", {**values, **extra}, f"views.csv line {index + 2}"


def test_views_computed_together_print_what_their_views_print():
    """``params --sidecar`` computes square-pixel pinholes many at once: every row prints
    what the record's own view prints (a second implementation: values within
    :data:`printed.TOLERANCE`, cells identical but where a value lies that close to a
    rounding boundary), and every error is the view's own."""
    import random

    from gsrwt_cli.inputs.records import RecordError, view_from_values
    from gsrwt_cli.tables.rows import params_row, params_rows

    rng = random.Random(7)
    records = [_random_record(rng, index) for index in range(20_000)]
    fast = 0
    compare = PrintedComparison()
    for (image, values, where), row in zip(records, params_rows(records)):
        try:
            expected = params_row(view_from_values(values, where), image)
        except RecordError as error:
            assert isinstance(row, RecordError) and str(row) == str(error)
            continue
        assert isinstance(row, dict) and row.keys() == expected.keys(), (values, row)
        for name, value in expected.items():
            compare.values(row[name], value, (name, values))
        fast += "roll" not in values
    assert fast > 8_000  # valid rows without roll: computed together
    compare.assert_few_flips()


@pytest.mark.parametrize("kind", ["size", "principal point", "neither", "frontal rows"])
def test_a_plain_csv_chunk_computed_as_columns_writes_what_its_views_would(kind):
    """A chunk of plain CSV rows (decimal text, valid square-pixel pinholes) is computed and
    written as columns: the same csv and json, byte for byte, as each row's own view gives."""
    import random

    from gsrwt_cli.inputs.records import view_from_values
    from gsrwt_cli.tables.rows import PARAMS_CHUNK, ParamsBlock, params_row, params_rows
    from gsrwt_cli.tables.writer import TableWriter

    rng = random.Random(kind)
    records = []
    for index in range(PARAMS_CHUNK + 100):  # a whole chunk, then part of one
        values = {"pan": f"{rng.uniform(-85, 85):.4f}", "tilt": f"{rng.uniform(-85, 85):.4f}",
                  "focal": f"{rng.uniform(50, 4000):.3f}"}
        if kind == "frontal rows" and index % 3 == 0:
            values.update(pan="0", tilt="-0.0")
        if kind in ("size", "frontal rows"):
            values.update(width=str(rng.randint(1, 6000)), height=str(rng.randint(1, 6000)))
        elif kind == "principal point":
            values.update(cx=f"{rng.uniform(-50, 900):.2f}", cy=f"{rng.uniform(-50, 900):.2f}")
        records.append((f"img{index}.jpg", values, f"views.csv line {index + 2}"))
    produced = list(params_rows(records))
    assert all(isinstance(item, ParamsBlock) for item in produced) and len(produced) == 2
    rows = [params_row(view_from_values(values, where), image)
            for image, values, where in records]
    for fmt in ("csv", "json"):
        fast = io.StringIO()
        writer = TableWriter(fast, PARAMS_COLUMNS, fmt)
        for block in produced:
            writer.write_columns(block.columns, block.count)
        writer.close()
        assert_table_prints_rows(fast.getvalue(), fmt, rows, PARAMS_COLUMNS)


def test_a_chunk_with_one_odd_cell_is_computed_row_by_row():
    """One cell that is not plain decimal text (here ``1_000``, which Python's float reads)
    sends its chunk the long way: that row is the error its view gives."""
    from gsrwt_cli.inputs.records import RecordError
    from gsrwt_cli.tables.rows import ParamsBlock, params_rows

    records = [(f"i{index}", {"pan": "10", "tilt": "5", "focal": "300"}, f"v line {index}")
               for index in range(50)]
    records[7] = ("i7", {"pan": "10", "tilt": "5", "focal": "1_000"}, "v line 7")
    produced = list(params_rows(records))
    assert not any(isinstance(item, ParamsBlock) for item in produced)
    assert isinstance(produced[7], RecordError) and "not a number" in str(produced[7])
    assert sum(isinstance(item, dict) for item in produced) == 49
