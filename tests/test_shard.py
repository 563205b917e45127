"""``--shard K/N`` and ``gsrwt tables merge``: N real shard runs add up to one whole run.

Every run is the installed ``gsrwt`` in a subprocess, on the sample views plus images that
fail (undecodable, truncated, without parameters), so that error rows are sharded too.
"""

from __future__ import annotations

import csv
import hashlib
import shutil
from pathlib import Path

import pytest
from conftest import run_gsrwt

from gsrwt_cli.tables import order_shards, shard_slice

SAMPLES = Path(__file__).resolve().parent.parent / "sample_data" / "views"


def sha256_tree(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


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
        with open(table, newline="") as stream:
            shard_statuses.append([row["status"] for row in csv.DictReader(stream)])
    assert [len(s) for s in shard_statuses] == [4, 4, 4]
    assert codes == [1 if "error" in s else 0 for s in shard_statuses]
    merged = run_gsrwt("tables", "merge", *(str(t) for t in reversed(tables)),
                       "-o", "out/gsrwt.csv", cwd=sharded)
    assert merged.returncode == 0, merged.stderr
    table = (sharded / "out" / "gsrwt.csv").read_bytes()
    assert table == (whole / "out" / "gsrwt.csv").read_bytes()
    outputs = {k: v for k, v in sha256_tree(sharded / "out").items() if "-of-3" not in k}
    assert outputs == sha256_tree(whole / "out")
    with open(whole / "out" / "gsrwt.csv", newline="") as stream:
        statuses = [row["status"] for row in csv.DictReader(stream)]
    assert statuses.count("error") == 3 and statuses.count("ok") == 9


@pytest.mark.slow
def test_a_shard_rerun_resumes_and_keeps_its_own_table(inputs, tmp_path):
    first = rectify(inputs, tmp_path, "--shard", "2/3")
    again = rectify(inputs, tmp_path, "--shard", "2/3")
    assert first.returncode == again.returncode
    with open(tmp_path / "out" / "gsrwt.2-of-3.csv", newline="") as stream:
        statuses = [row["status"] for row in csv.DictReader(stream)]
    assert len(statuses) == 4 and "skipped" in statuses
    assert set(statuses) <= {"skipped", "error"}
    assert not (tmp_path / "out" / "gsrwt.csv").exists()


def test_merge_refuses_a_missing_or_repeated_shard(tmp_path):
    header = "image,status\n"
    for k in (1, 3):
        (tmp_path / f"t.{k}-of-3.csv").write_text(header + f"a{k}.jpg,ok\n")
    missing = run_gsrwt("tables", "merge", str(tmp_path / "t.1-of-3.csv"),
                        str(tmp_path / "t.3-of-3.csv"), "-o", str(tmp_path / "t.csv"))
    assert missing.returncode == 2
    assert missing.stderr.strip() == "Error: shard 2 of 3 missing (got 2 of 3 tables)"
    assert not (tmp_path / "t.csv").exists()
    with pytest.raises(ValueError, match="also"):
        order_shards(["x/t.1-of-2.csv", "y/t.1-of-2.csv"])


def test_merge_refuses_tables_with_other_columns(tmp_path):
    (tmp_path / "t.1-of-2.csv").write_text("image,status\na.jpg,ok\n")
    (tmp_path / "t.2-of-2.csv").write_text("image,error\nb.jpg,\n")
    result = run_gsrwt("tables", "merge", str(tmp_path / "t.1-of-2.csv"),
                       str(tmp_path / "t.2-of-2.csv"), "-o", "-")
    assert result.returncode == 2
    assert "t.2-of-2.csv: its columns differ" in result.stderr


def test_merge_joins_json_lines_in_shard_order(tmp_path):
    (tmp_path / "t.2-of-2.jsonl").write_text('{"image": "b.jpg", "scale": 0.5}\n')
    (tmp_path / "t.1-of-2.jsonl").write_text('{"image": "a.jpg", "scale": 1.25}\n')
    result = run_gsrwt("tables", "merge", str(tmp_path / "t.2-of-2.jsonl"),
                       str(tmp_path / "t.1-of-2.jsonl"), "-o", str(tmp_path / "all.jsonl"))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "all.jsonl").read_text() == (
        '{"image": "a.jpg", "scale": 1.25}\n{"image": "b.jpg", "scale": 0.5}\n')
