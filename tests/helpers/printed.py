"""Two implementations of one number compared as users see it: a table cell printed to
:data:`~gsrwt_cli.tables.writer.MACHINE_DECIMALS` places.

Two correct implementations of a formula (numpy's columns and one view's matrices, the
``math`` module and numpy, a BLAS kernel with fused multiply-adds and one without) agree to
within a few units in the last place, and which last bit each gives depends on the CPU:
numpy, OpenBLAS and libm each pick their kernels by the processor they run on. So no test
here asserts float-for-float equality between two implementations. What users see is the
table, and a last-bit difference changes a printed digit only where the value lies within
that difference of a rounding boundary (``...xxxxxx5`` in the seventh decimal).

How far that is, in numbers: the ``params`` columns' largest disagreement measured between
two paths is 3e-13 (``vl_c``, a sum of terms of up to 1e4 that cancel), 7e-14 relative,
1e-7 of the printed unit 1e-6. A value then prints differently only if it lies within
3e-13 of a boundary: about 6 values in 10^7 printed. The comparisons below allow
:data:`TOLERANCE` (1e-11 relative: 50 000 times below half a printed unit, over 100 times
the worst measured difference) and allow a printed digit to differ only where the exact
value lies within it of the boundary between the two cells; those flips are counted, and a
caller asserts there are almost none (a real bug makes many).
"""

from __future__ import annotations

import math
from typing import Any

from gsrwt_cli.tables.writer import MACHINE_DECIMALS, _text_value

#: How far two correct implementations may put one value apart, relative to the value (and
#: absolute below 1).
TOLERANCE = 1e-11
#: One unit of the last printed decimal.
PRINTED_UNIT = 10.0 ** -MACHINE_DECIMALS


def allowed(value: float) -> float:
    """The largest difference two correct implementations may give for ``value``."""
    return TOLERANCE * max(1.0, abs(value))


def printed(value: Any) -> str:
    """``value`` as a machine-format table cell (CSV, TSV) prints it."""
    return _text_value(value, MACHINE_DECIMALS)


def is_boundary_flip(cell: str, value: float) -> bool:
    """Whether ``cell`` is the other side of a rounding boundary that ``value`` lies within
    :func:`allowed` of: the two printed numbers one unit apart, the boundary between them
    (their midpoint) that close to ``value``."""
    try:
        shown = float(cell)
    except ValueError:
        return False
    if not math.isfinite(value) or not math.isclose(abs(shown - round(value, MACHINE_DECIMALS)),
                                                    PRINTED_UNIT, rel_tol=1e-6):
        return False
    boundary = (shown + round(value, MACHINE_DECIMALS)) / 2
    return abs(value - boundary) <= allowed(value)


class PrintedComparison:
    """Compares values of one implementation with another's, cell by cell; counts flips."""

    def __init__(self) -> None:
        self.compared = 0
        self.flips = 0

    def values(self, got: Any, expected: Any, where: object) -> None:
        """``got`` and ``expected`` (row values) are the same type, print the same cell, and
        as floats lie within :func:`allowed` of each other; a differing cell only across a
        boundary ``expected`` lies that close to."""
        assert type(got) is type(expected), (where, got, expected)
        self.compared += 1
        if isinstance(expected, float) and math.isfinite(expected):
            assert math.isfinite(got) and abs(got - expected) <= allowed(expected), (
                where, got, expected)
        elif isinstance(expected, float):  # nan and infinities: the same kind, an empty cell
            assert math.isnan(got) if math.isnan(expected) else got == expected, (
                where, got, expected)
        else:
            assert got == expected, (where, got, expected)
        self.cell(printed(got), expected, where)

    def cell(self, cell: str | None, expected: Any, where: object) -> None:
        """A printed ``cell`` (text) is what ``expected`` prints, or a boundary flip of it."""
        want = printed(expected)
        if (cell or "") == want:
            return
        assert isinstance(expected, float) and is_boundary_flip(cell or "", expected), (
            where, cell, want, expected)
        self.flips += 1

    def json_value(self, got: Any, expected: Any, where: object) -> None:
        """A value read back from a JSON table is what ``expected`` writes, or a flip of it."""
        self.compared += 1
        if isinstance(expected, float) and math.isfinite(expected) and type(got) in (int, float):
            want = round(expected, MACHINE_DECIMALS)
            if got == want:
                return
            assert is_boundary_flip(repr(float(got)), expected), (where, got, want)
            self.flips += 1
            return
        if isinstance(expected, float):  # not finite: null
            assert got is None, (where, got, expected)
            return
        assert got == expected, (where, got, expected)

    def assert_few_flips(self) -> None:
        """Flips are legitimate but rare (see the module's note): at most one in 10^4."""
        assert self.compared > 0
        assert self.flips <= max(1, self.compared // 10_000), (self.flips, self.compared)


def assert_table_prints_rows(text: str, fmt: str, rows: list[dict[str, Any]],
                             columns: tuple[str, ...]) -> None:
    """A table written by one implementation (``text`` in ``fmt``: csv, tsv or json) shows
    ``rows`` of another cell for cell (a missing value as an empty cell or null), header and
    row count included, with few flips."""
    import csv
    import io
    import json

    compare = PrintedComparison()
    if fmt == "json":
        written = json.loads(text)
        assert len(written) == len(rows)
        for index, (got, expected) in enumerate(zip(written, rows)):
            assert list(got) == list(columns), index
            for name in columns:
                compare.json_value(got[name], expected.get(name), (index, name))
    else:
        reader = csv.reader(io.StringIO(text), dialect="excel-tab" if fmt == "tsv" else "excel")
        header, *cells = list(reader)
        assert header == list(columns) and len(cells) == len(rows)
        for index, (got, expected) in enumerate(zip(cells, rows)):
            assert len(got) == len(columns), index
            for name, cell in zip(columns, got):
                compare.cell(cell, expected.get(name), (index, name))
                compare.compared += 1
    compare.assert_few_flips()
