"""Golden tables: every command's table, in every format, as committed in ``tests/data/golden``.

The golden files hold what the commands printed on the sample data when they were made; a
change in columns, order, quoting, alignment or number formatting shows up here as a diff.
They are compared cell by cell as users see them (:mod:`printed`): a number may differ only
by one unit of its last printed decimal (a value within rounding of a boundary, where two
CPUs' last bits may fall on either side), and such flips must be rare. Everything else is
compared to the letter (whitespace runs of the aligned formats as one space, since a flipped
``0.5`` / ``0.499999`` changes a column's width).

Remake them after an intended change with ``python -m tests.test_golden_tables`` (from the
project's root) and review the diff.
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

import pytest

from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA, ROOT

GOLDEN = DATA / "golden"
FORMATS = ("table", "csv", "tsv", "json", "jsonl", "markdown")
#: Decimals printed by the machine formats and by the human ones (table, markdown).
DECIMALS = {"table": 3, "markdown": 3}

#: Table commands whose numbers are closed-form (the writer is one for all commands), run
#: from a copy of ``sample_data`` (relative names in the tables). ``estimate``, ``lines`` and
#: ``match`` are left out: their searches decide on thresholds (an inlier, an orientation
#: bin) where another CPU's last bit may decide otherwise, so their golden tables would not
#: hold on every machine; their own tests check their values with tolerances.
COMMANDS = {
    "params": ["params", "--sidecar", "views/views.csv"],
    "gaze": ["gaze", "--pan", "10", "--tilt", "5", "--focal", "500", "--width", "640",
             "--height", "480", "--to-pixel", "100,80"],
    "track": ["track", "--distance", "25", "--object", "33", "--positions", "0,4,8,12"],
}
#: ``gsrwt rectify``'s table, by the table file's extension.
RECTIFY = ["rectify", "views", "--sidecar", "views/views.csv", "-o", "out", "-j", "1", "-q"]
RECTIFY_FORMATS = ("csv", "tsv", "json", "jsonl")

_NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def _sample_copy(where: Path) -> Path:
    shutil.copytree(ROOT / "sample_data" / "views", where / "views")
    return where


def produce(name: str, fmt: str, where: Path) -> str:
    """The table ``name`` (a command, or ``rectify``) in ``fmt``, made in ``where``."""
    if name == "rectify":
        shutil.rmtree(where / "out", ignore_errors=True)
        result = run_gsrwt(*RECTIFY, "--table", f"table.{fmt}", cwd=where)
        assert result.returncode == 0, result.stderr
        return (where / f"table.{fmt}").read_text()
    result = run_gsrwt(*COMMANDS[name], "--format", fmt, cwd=where)
    assert result.returncode in (0, 1), result.stderr
    return result.stdout


def _tokens(text: str, fmt: str) -> tuple[list[str], list[str]]:
    """The text between numbers, and the numbers (whitespace runs as one space in the
    aligned formats)."""
    if fmt in DECIMALS:
        text = re.sub(r"[ \t]+", " ", text)
    return _NUMBER.split(text), _NUMBER.findall(text)


def assert_prints_like(got: str, golden: str, fmt: str, where: str) -> None:
    """``got`` is ``golden`` to the letter, but for numbers one printed unit apart (rare)."""
    if got == golden:
        return
    got_text, got_numbers = _tokens(got, fmt)
    golden_text, golden_numbers = _tokens(golden, fmt)
    assert got_text == golden_text and len(got_numbers) == len(golden_numbers), (
        f"{where}: the table's text changed")
    unit = 10.0 ** -DECIMALS.get(fmt, 6)
    flips = 0
    for number, expected in zip(got_numbers, golden_numbers):
        if number == expected:
            continue
        assert abs(float(number) - float(expected)) <= unit * (1 + 1e-9), (
            f"{where}: {number} where the golden table has {expected}")
        flips += 1
    assert flips <= max(1, len(golden_numbers) // 10_000), (where, flips)


CASES = [(name, fmt) for name in COMMANDS for fmt in FORMATS]
CASES += [("rectify", fmt) for fmt in RECTIFY_FORMATS]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "fmt"), CASES)
def test_each_table_prints_as_its_golden_file(tmp_path, name, fmt):
    got = produce(name, fmt, _sample_copy(tmp_path))
    golden = (GOLDEN / f"{name}.{fmt}").read_text()
    assert_prints_like(got, golden, fmt, f"{name}.{fmt}")


def test_the_comparison_tells_a_flip_from_a_change():
    """A number one printed unit off passes (once); two units, a changed word, a column
    moved or several flips fail."""
    golden = "image,a_px\nx.png,427.462305\n"
    assert_prints_like("image,a_px\nx.png,427.462306\n", golden, "csv", "flip")
    for changed in ("image,a_px\nx.png,427.462307\n", "image,a\nx.png,427.462305\n",
                    "a_px,image\n427.462305,x.png\n"):
        with pytest.raises(AssertionError):
            assert_prints_like(changed, golden, "csv", "changed")
    with pytest.raises(AssertionError):
        assert_prints_like("1.000001,2.000001", "1.000000,2.000000", "csv", "two flips")


if __name__ == "__main__":  # remake the golden files
    import tempfile

    GOLDEN.mkdir(parents=True, exist_ok=True)
    for name, fmt in CASES:
        with tempfile.TemporaryDirectory() as folder:
            text = produce(name, fmt, _sample_copy(Path(folder)))
        (GOLDEN / f"{name}.{fmt}").write_text(text)
        print(f"{name}.{fmt}: {len(text)} characters", file=sys.stderr)
