"""``--shard K/N`` and ``gsrwt tables merge``: N real shard runs add up to one whole run.

Every run is the installed ``gsrwt`` in a subprocess, on the sample views plus images that
fail (undecodable, truncated, without parameters), so that error rows are sharded too.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from gsrwt_cli.batch.rectify_jobs import RECTIFY_COLUMNS
from gsrwt_cli.tables.shards import (
    MAX_SHARDS,
    order_shards,
    parse_shard,
    shard_of_name,
    shard_slice,
    shard_table_name,
)
from tests.helpers.cli import run_gsrwt
from tests.helpers.faults import sha256_tree
from tests.helpers.paths import SAMPLE_VIEWS as SAMPLES
from tests.helpers.tables import read_table


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """The sample views, an undecodable file, a truncated JPEG and an image no row names."""
    folder = tmp_path_factory.mktemp("inputs")
    for path in SAMPLES.iterdir():
        shutil.copy(path, folder / path.name)
    (folder / "broken.jpg").write_bytes(b"not an image at all")
    door = (SAMPLES / "door_p20_t-8_f800.jpg").read_bytes()
    (folder / "door_p20_t-8_f800_cut.jpg").write_bytes(door[: len(door) // 2])
    shutil.copy(SAMPLES / "door_p40_t-12_f700.jpg", folder / "unlisted.jpg")
    return folder


def rectify(inputs: Path, cwd: Path, *extra: str):
    return run_gsrwt("rectify", str(inputs), "--sidecar", str(inputs / "views.csv"), "-o", "out",
                     "-q", "-j", "2", *extra, cwd=cwd)


@pytest.mark.parametrize(("count", "n"), [(0, 3), (1, 3), (12, 5), (13, 4), (1000, 7)])
def test_slices_cover_the_list_in_order_once(count, n):
    joined = [i for k in range(1, n + 1) for i in shard_slice(count, k, n)]
    assert joined == list(range(count))
    sizes = [len(shard_slice(count, k, n)) for k in range(1, n + 1)]
    assert max(sizes) - min(sizes) <= 1


@pytest.mark.slow
def test_the_union_of_shards_is_one_unsharded_run(inputs, tmp_path):
    whole, sharded = tmp_path / "whole", tmp_path / "sharded"
    whole.mkdir()
    sharded.mkdir()
    one = rectify(inputs, whole)
    assert one.returncode == 1, one.stderr  # the bad images failed, the others did not
    codes = [rectify(inputs, sharded, "--shard", f"{k}/3").returncode for k in (1, 2, 3)]
    tables = sorted((sharded / "out").glob("gsrwt.*-of-3.csv"))
    assert [t.name for t in tables] == [f"gsrwt.{k}-of-3.csv" for k in (1, 2, 3)]
    # each shard saw its own slice: 12 rows in slices of 4; failures exit 1 where they fell
    shard_statuses = []
    for table in tables:
        shard_statuses.append([row["status"] for row in read_table(table)])
    assert [len(s) for s in shard_statuses] == [4, 4, 4]
    assert codes == [1 if "error" in s else 0 for s in shard_statuses]
    merged = run_gsrwt("tables", "merge", *(str(t) for t in reversed(tables)),
                       "-o", "out/gsrwt.csv", cwd=sharded)
    assert merged.returncode == 0, merged.stderr
    table = (sharded / "out" / "gsrwt.csv").read_bytes()
    assert table == (whole / "out" / "gsrwt.csv").read_bytes()
    outputs = {k: v for k, v in sha256_tree(sharded / "out").items() if "-of-3" not in k}
    assert outputs == sha256_tree(whole / "out")
    statuses = [row["status"] for row in read_table(whole / "out" / "gsrwt.csv")]
    assert statuses.count("error") == 3 and statuses.count("ok") == 9


@pytest.mark.slow
def test_a_shard_rerun_resumes_and_keeps_its_own_table(inputs, tmp_path):
    first = rectify(inputs, tmp_path, "--shard", "2/3")
    again = rectify(inputs, tmp_path, "--shard", "2/3")
    assert first.returncode == again.returncode
    statuses = [row["status"] for row in read_table(tmp_path / "out" / "gsrwt.2-of-3.csv")]
    assert len(statuses) == 4 and "skipped" in statuses
    assert set(statuses) <= {"skipped", "error"}
    assert not (tmp_path / "out" / "gsrwt.csv").exists()


@pytest.fixture(scope="module")
def shard_tables(tmp_path_factory) -> Path:
    """The tables of a real two-shard run of the sample views (csv), and of its first shard
    written as json lines."""
    folder = tmp_path_factory.mktemp("shards")
    for k in (1, 2):
        result = rectify(SAMPLES, folder, "--shard", f"{k}/2")
        assert result.returncode == 0, result.stderr
    result = rectify(SAMPLES, folder, "--shard", "1/2", "--table", "out/gsrwt.1-of-2.jsonl")
    assert result.returncode == 0, result.stderr
    return folder / "out"


def merge(tmp_path: Path, *tables: Path, output: str = "merged.csv"):
    return run_gsrwt("tables", "merge", *(str(t) for t in tables), "-o", output, cwd=tmp_path)


@pytest.mark.parametrize("text", ["1_0/20", "\u0661/\u0662", "1/\u0662", "+1/2", "1/+2",
                                  " 1/2", "1/2 ", "1/10000000000000000000000",
                                  f"1/{MAX_SHARDS + 1}", "0/2", "3/2", "1.0/2", "1/2/3", "1"])
def test_shard_is_two_whole_numbers_in_ascii_digits_within_the_bound(text, tmp_path):
    result = run_gsrwt("rectify", str(SAMPLES / "corridor_p0_t30.png"), "--pan", "0", "--tilt",
                       "0", "--focal", "300", "-o", "out", "--shard", text, cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1].startswith(
        "Error: Invalid value for '--shard': expected K/N in ASCII digits with "
        f"1 <= K <= N <= {MAX_SHARDS}")
    assert not (tmp_path / "out").exists()


def test_the_largest_shard_count_is_taken(tmp_path):
    result = run_gsrwt("rectify", str(SAMPLES / "corridor_p0_t30.png"), "--pan", "0", "--tilt",
                       "0", "--focal", "300", "-o", "out", "--shard", f"1/{MAX_SHARDS}",
                       cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out" / f"gsrwt.1-of-{MAX_SHARDS}.csv").is_file()


@pytest.mark.parametrize("name", [f"t.1-of-{MAX_SHARDS + 1}.csv", "t.0-of-1.csv", "t.2-of-1.csv",
                                  "t.1-of-10000000000000000000000.csv"])
def test_merge_refuses_a_shard_name_out_of_bounds(name, tmp_path, shard_tables):
    shutil.copy(shard_tables / "gsrwt.1-of-2.csv", tmp_path / name)
    result = merge(tmp_path, tmp_path / name)
    assert result.returncode == 2
    assert result.stderr.strip() == (
        f"Error: {tmp_path / name}: its name says shard "
        f"{name.split('.')[1].replace('-of-', ' of ')}, not K of N with "
        f"1 <= K <= N <= {MAX_SHARDS}")
    assert not (tmp_path / "merged.csv").exists()


def test_merge_refuses_a_missing_or_repeated_shard(tmp_path, shard_tables):
    for k in (1, 3):
        shutil.copy(shard_tables / "gsrwt.1-of-2.csv", tmp_path / f"t.{k}-of-3.csv")
    missing = merge(tmp_path, tmp_path / "t.1-of-3.csv", tmp_path / "t.3-of-3.csv",
                    output="t.csv")
    assert missing.returncode == 2
    assert missing.stderr.strip() == "Error: shard 2 of 3 missing (got 2 of 3 tables)"
    assert not (tmp_path / "t.csv").exists()
    with pytest.raises(ValueError, match="also"):
        order_shards(["x/t.1-of-2.csv", "y/t.1-of-2.csv"])


def test_merge_names_few_of_many_missing_shards(tmp_path, shard_tables):
    shutil.copy(shard_tables / "gsrwt.1-of-2.csv", tmp_path / f"t.1-of-{MAX_SHARDS}.csv")
    result = merge(tmp_path, tmp_path / f"t.1-of-{MAX_SHARDS}.csv")
    assert result.returncode == 2
    assert result.stderr.strip() == (f"Error: shard 2, 3, 4, 5, 6, 7, 8, 9, 10, 11 and "
                                     f"{MAX_SHARDS - 11} more of {MAX_SHARDS} missing "
                                     f"(got 1 of {MAX_SHARDS} tables)")


def test_merge_joins_real_shards_of_csv_and_json_lines_in_shard_order(tmp_path, shard_tables):
    first, second = shard_tables / "gsrwt.1-of-2.jsonl", shard_tables / "gsrwt.2-of-2.csv"
    result = merge(tmp_path, second, first, output="all.jsonl")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "all.jsonl")
    images = [row["image"] for row in read_table(shard_tables / "gsrwt.1-of-2.csv")]
    images += [row["image"] for row in read_table(second)]
    assert [row["image"] for row in rows] == images
    assert len(images) == 9 and list(rows[0]) == list(RECTIFY_COLUMNS)


def csv_rows(path: Path) -> list[list[str]]:
    with open(path, newline="") as stream:
        return list(csv.reader(stream))


def write_csv(path: Path, rows: list[list[str]]) -> None:
    with open(path, "w", newline="") as stream:
        csv.writer(stream, lineterminator="\n").writerows(rows)


def test_merge_refuses_any_csv_that_is_not_a_rectify_table(tmp_path):
    (tmp_path / "t.csv").write_text("a,b\n1,2\n")
    result = merge(tmp_path, tmp_path / "t.csv")
    assert result.returncode == 2
    assert result.stderr.strip() == (f"Error: {tmp_path / 't.csv'}: not a table of gsrwt rectify: "
                                     f"no column 'image' (and {len(RECTIFY_COLUMNS) - 1} more), "
                                     "unknown column 'a' (and 1 more)")
    assert not (tmp_path / "merged.csv").exists()


@pytest.mark.parametrize(("change", "problem"), [
    (lambda rows: [row[:-1] for row in rows], "no column 'error'"),
    (lambda rows: [[*row, "x"] for row in rows], "unknown column 'x'"),
    (lambda rows: [row[1:2] + row[:1] + row[2:] for row in rows],
     "its columns are gsrwt rectify's in another order"),
    (lambda rows: [[*rows[0], "image"]] + [[*row, ""] for row in rows[1:]],
     "column 'image' twice"),
    (lambda rows: [[]], f"no column 'image' (and {len(RECTIFY_COLUMNS) - 1} more)"),
])
def test_merge_refuses_a_shard_with_other_columns(tmp_path, shard_tables, change, problem):
    shutil.copy(shard_tables / "gsrwt.1-of-2.csv", tmp_path / "t.1-of-2.csv")
    write_csv(tmp_path / "t.2-of-2.csv", change(csv_rows(shard_tables / "gsrwt.2-of-2.csv")))
    result = merge(tmp_path, tmp_path / "t.1-of-2.csv", tmp_path / "t.2-of-2.csv", output="-")
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.strip() == (f"Error: {tmp_path / 't.2-of-2.csv'}: not a table of gsrwt "
                                     f"rectify: {problem}")


@pytest.mark.parametrize(("column", "value", "expected"), [
    ("pan_deg", "1_0", "a number"),
    ("pan_deg", "\u0663", "a number"),
    ("pan_deg", "nan", "a number"),
    ("tilt_deg", "1e400", "a number"),
    ("out_width", "12.5", "a whole number above 0"),
    ("out_height", "-3", "a whole number above 0"),
    ("out_width", "+320", "a whole number above 0"),
    ("horizon_in_image", "yes", "true or false"),
    ("homography", "1 0 0 0 1 0 0 0", "nine numbers"),
    ("homography", "1 0 0 0 1 0 0 0 nan", "nine numbers"),
    ("status", "done", "ok, skipped, error, interrupted or planned"),
    ("status", "", "ok, skipped, error, interrupted or planned"),
    ("image", "", "the image's name"),
])
def test_merge_refuses_a_csv_cell_of_the_wrong_type(tmp_path, shard_tables, column, value,
                                                    expected):
    rows = csv_rows(shard_tables / "gsrwt.2-of-2.csv")
    rows[2][rows[0].index(column)] = value
    write_csv(tmp_path / "t.2-of-2.csv", rows)
    shutil.copy(shard_tables / "gsrwt.1-of-2.csv", tmp_path / "t.1-of-2.csv")
    result = merge(tmp_path, tmp_path / "t.1-of-2.csv", tmp_path / "t.2-of-2.csv")
    assert result.returncode == 2
    assert result.stderr.strip() == (f"Error: {tmp_path / 't.2-of-2.csv'} line 3, column "
                                     f"{column}: expected {expected}, got '{value}'")
    assert not (tmp_path / "merged.csv").exists()


def test_merge_refuses_a_csv_row_with_too_many_or_too_few_cells(tmp_path, shard_tables):
    rows = csv_rows(shard_tables / "gsrwt.1-of-2.csv")
    for name, row in (("long", [*rows[1], "extra"]), ("short", rows[1][:5])):
        write_csv(tmp_path / f"{name}.csv", [rows[0], row])
        result = merge(tmp_path, tmp_path / f"{name}.csv")
        assert result.returncode == 2
        assert result.stderr.strip() == (
            f"Error: {tmp_path / name}.csv line 2: {len(row)} cells, not the "
            f"{len(rows[0])} of the columns")


@pytest.mark.parametrize(("change", "problem"), [
    (lambda row: {**row, "pan_deg": "10"}, ", column pan_deg: expected a number, got \"10\""),
    (lambda row: {**row, "pan_deg": True}, ", column pan_deg: expected a number, got true"),
    (lambda row: {**row, "out_width": 320.5}, ", column out_width: expected a whole number "
                                              "above 0, got 320.5"),
    (lambda row: {**row, "horizon_in_image": 1}, ", column horizon_in_image: expected true or "
                                                 "false, got 1"),
    (lambda row: {**row, "homography": [1, 0, 0]}, ", column homography: expected nine numbers, "
                                                   "got [1, 0, 0]"),
    (lambda row: {**row, "error": 5}, ", column error: expected text, got 5"),
    (lambda row: {k: v for k, v in row.items() if k != "scale"}, ": no column 'scale'"),
    (lambda row: [row], ": not a row of named values"),
])
def test_merge_refuses_a_json_row_of_the_wrong_type(tmp_path, shard_tables, change, problem):
    lines = (shard_tables / "gsrwt.1-of-2.jsonl").read_text().splitlines()
    lines[1] = json.dumps(change(json.loads(lines[1])))
    (tmp_path / "t.jsonl").write_text("\n".join(lines) + "\n")
    result = merge(tmp_path, tmp_path / "t.jsonl")
    assert result.returncode == 2
    assert result.stderr.strip().startswith(f"Error: {tmp_path / 't.jsonl'} row 2{problem}")
    assert not (tmp_path / "merged.csv").exists()


def test_merge_refuses_a_json_nan(tmp_path, shard_tables):
    lines = (shard_tables / "gsrwt.1-of-2.jsonl").read_text().splitlines()
    (tmp_path / "t.jsonl").write_text(lines[0].replace('"scale": 1.0', '"scale": NaN') + "\n")
    result = merge(tmp_path, tmp_path / "t.jsonl")
    assert result.returncode == 2
    assert result.stderr.strip() == (f"Error: {tmp_path / 't.jsonl'} row 1, column scale: "
                                     "expected a number, got NaN")


def test_a_shards_table_is_named_by_its_k_and_n():
    name = shard_table_name("out/gsrwt.csv", 3, 8)
    assert name == "out/gsrwt.3-of-8.csv" and shard_of_name(name) == (3, 8)
    assert shard_of_name("out/gsrwt.csv") is None
    assert parse_shard("2/8") == (2, 8)
    for text in ("0/8", "9/8", "2 /8", "2/8/1", "-1/8"):
        with pytest.raises(ValueError):
            parse_shard(text)
