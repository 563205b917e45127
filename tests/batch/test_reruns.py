"""Reruns tell the truth (issue 21, items 2 and 3): a rerun keeps an existing output only if
the record of it is valid and says it was made with what this run asks for.

Every test runs the installed ``gsrwt`` in real subprocesses on real files: a first run, a
change (other options, a rewritten calibration file, a corrupted table, a deleted table, a
file put in the output's place), a second run; then the second run's rows are checked
against the files on disk.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
from pathlib import Path

import cv2
import imagesize
import pytest

from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.inputs.calibration import write_opencv_yaml
from tests.helpers.cli import run_gsrwt
from tests.helpers.faults import POSE, make_photos
from tests.helpers.images import smooth_texture
from tests.helpers.tables import by_image_name, read_table

BASE = ("--pan", "20", "--tilt", "10", "--focal", "500")


def table(path: Path) -> dict[str, dict[str, str]]:
    return by_image_name(read_table(path))


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def assert_rows_describe_their_files(rows: dict[str, dict[str, str]], root: Path) -> None:
    """Every row with an output size names a regular file of that size."""
    for row in rows.values():
        if row["out_width"]:
            output = root / row["output"]
            assert output.is_file() and not output.is_symlink(), row
            assert imagesize.get(str(output)) == (int(row["out_width"]),
                                                   int(row["out_height"])), row


@pytest.fixture
def photo(tmp_path: Path) -> Path:
    """``in/a.png``, 80x60, and ``in/b.jpg``, 80x60 (a lossy format, for --quality)."""
    folder = tmp_path / "in"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.png"), smooth_texture(60, 80, 1))
    cv2.imwrite(str(folder / "b.jpg"), smooth_texture(60, 80, 2))
    return folder


def write_camera(path: Path, fx: float, k1: float = 0.0) -> None:
    lens = Lens("plumb_bob", (("k1", k1),)) if k1 else None
    write_opencv_yaml(path, Intrinsics(fx, fx, 39.5, 29.5, 0.0, 80, 60, lens))


def write_sidecar(path: Path, k1: float) -> None:
    path.write_text(f"image,pan,tilt,focal,k1\na.png,20,10,500,{k1}\nb.jpg,20,10,500,{k1}\n")


#: (first run's arguments, a change made between the runs (or None), second run's
#: arguments, what the second run's error must name): every option that changes an output.
CHANGES = {
    "pan": (BASE, None, ("--pan", "10", "--tilt", "10", "--focal", "500"), "pan 20 -> 10"),
    "tilt": (BASE, None, ("--pan", "20", "--tilt", "-5", "--focal", "500"), "tilt 10 -> -5"),
    "roll": (BASE, None, (*BASE, "--roll", "3"), "roll none -> 3"),
    "focal": (BASE, None, ("--pan", "20", "--tilt", "10", "--focal", "700"),
              "focal 500 -> 700"),
    "fx, fy": (BASE, None, ("--pan", "20", "--tilt", "10", "--fx", "500", "--fy", "520"),
               "focal 500 -> none"),
    "principal point": (BASE, None, (*BASE, "--cx", "30"), "cx none -> 30"),
    "skew": (BASE, None, (*BASE, "--skew", "2"), "skew none -> 2"),
    "calibration file": (("--pan", "20", "--tilt", "10", "--camera", "cam.yaml"),
                         lambda root: write_camera(root / "cam.yaml", 650),
                         ("--pan", "20", "--tilt", "10", "--camera", "cam.yaml"),
                         "camera.fx 500 -> 650"),
    "calibration file's lens": (("--pan", "20", "--tilt", "10", "--camera", "cam.yaml"),
                                lambda root: write_camera(root / "cam.yaml", 500, -0.2),
                                ("--pan", "20", "--tilt", "10", "--camera", "cam.yaml"),
                                "camera.lens none -> plumb_bob(k1:-0.2)"),
    "sidecar lens": (("--sidecar", "views.csv"),
                     lambda root: write_sidecar(root / "views.csv", -0.25),
                     ("--sidecar", "views.csv"), "k1 -0.1 -> -0.25"),
    "frame": (BASE, None, (*BASE, "--bbox", "full"), "bbox frontal -> full"),
    "box": (BASE, None, (*BASE, "--bbox", "0,0,40,30"), "bbox frontal -> 0,0,40,30"),
    "max stretch": ((*BASE, "--bbox", "full"), None, (*BASE, "--bbox", "full",
                                                      "--max-stretch", "2"),
                    "max_stretch 4 -> 2"),
    "scale": (BASE, None, (*BASE, "--scale", "0.5"), "scale 1 -> 0.5"),
    "metric scale": ((*BASE, "--distance", "10"), None,
                     (*BASE, "--distance", "10", "--px-per-unit", "40"),
                     "scale 1 -> 40px/unit"),
    "max size": (BASE, None, (*BASE, "--max-size", "40x30"), "max_size none -> 40x30"),
    "interpolation": (BASE, None, (*BASE, "--interpolation", "cubic"),
                      "interpolation linear -> cubic"),
    "quality": ((*BASE, "--ext", "jpg"), None, (*BASE, "--ext", "jpg", "--quality", "50"),
                "quality 95 -> 50"),
    "antialias": (BASE, None, (*BASE, "--no-antialias"), "antialias on -> off"),
    "fill": (BASE, None, (*BASE, "--fill", "255"), "fill 0 -> 255"),
    "alpha": ((*BASE, "--ext", "png"), None, (*BASE, "--ext", "png", "--alpha"),
              "alpha off -> on"),
}


@pytest.mark.parametrize("first, change, second, named", CHANGES.values(), ids=list(CHANGES))
def test_a_rerun_with_other_options_never_skips_silently(tmp_path, photo, first, change,
                                                         second, named):
    """Each output-changing option, changed between two runs: the second run's row of each
    existing output is an error naming the change and --overwrite, and still describes the
    file on disk (the first run's row); nothing is rewritten."""
    write_camera(tmp_path / "cam.yaml", 500)
    write_sidecar(tmp_path / "views.csv", -0.1)
    done = run_gsrwt("rectify", "in", *first, "-o", "out", "-j", "1", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    before = table(tmp_path / "out" / "gsrwt.csv")
    outputs = {row["output"]: digest(tmp_path / row["output"]) for row in before.values()}
    if change is not None:
        change(tmp_path)
    again = run_gsrwt("rectify", "in", *second, "-o", "out", "-j", "1", cwd=tmp_path)
    assert again.returncode == 1, again.stderr
    after = table(tmp_path / "out" / "gsrwt.csv")
    for name, row in after.items():
        assert row["status"] == "error", row
        assert named in row["error"] and "use --overwrite to redo it" in row["error"], row
        assert row["error"].startswith("its output exists from a run with other options")
        assert {**row, "status": "ok", "error": ""} == {**before[name], "status": "ok",
                                                         "error": ""}
        assert f"Error: in/{name}: its output exists from a run with other options" in (
            again.stderr)
    assert {output: digest(tmp_path / output) for output in outputs} == outputs
    assert_rows_describe_their_files(after, tmp_path)


def test_the_issues_rerun_to_stdout_names_pan_and_focal(tmp_path, photo):
    (photo / "b.jpg").unlink()
    assert run_gsrwt("rectify", "in/a.png", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    first = table(tmp_path / "out" / "gsrwt.csv")["a.png"]
    again = run_gsrwt("rectify", "in/a.png", "--pan", "10", "--tilt", "10", "--focal", "700",
                      "-o", "out", "--table", "-", cwd=tmp_path)
    assert again.returncode == 1
    row = by_image_name(read_table(again.stdout))["a.png"]
    assert row["status"] == "error" and row["pan_deg"] == "20" and row["focal_px"] == "500"
    assert row["homography"] == first["homography"]
    assert ("its output exists from a run with other options (pan 20 -> 10, focal 500 -> "
            "700); use --overwrite to redo it") in again.stderr
    assert "0 ok, 0 skipped, 1 failed" in again.stderr
    # The same options again: skipped, the first row; --overwrite: redone, a true row.
    same = run_gsrwt("rectify", "in/a.png", *BASE, "-o", "out", "--table", "-", cwd=tmp_path)
    assert same.returncode == 0
    assert by_image_name(read_table(same.stdout))["a.png"] == {**first, "status": "skipped"}
    redo = run_gsrwt("rectify", "in/a.png", "--pan", "10", "--tilt", "10", "--focal", "700",
                     "-o", "out", "--overwrite", cwd=tmp_path)
    assert redo.returncode == 0, redo.stderr
    row = table(tmp_path / "out" / "gsrwt.csv")["a.png"]
    assert row["status"] == "ok" and row["pan_deg"] == "10" and row["focal_px"] == "700"


def test_an_error_row_keeps_the_record_for_the_next_run(tmp_path, photo):
    """Run A, run B (other options: error rows carrying A's record), run A again: skipped,
    with A's rows (the record survived the run that refused to redo them)."""
    args = ("rectify", "in", "-o", "out", "-j", "1")
    assert run_gsrwt(*args, *BASE, cwd=tmp_path).returncode == 0
    first = table(tmp_path / "out" / "gsrwt.csv")
    assert run_gsrwt(*args, *BASE, "--scale", "2", cwd=tmp_path).returncode == 1
    back = run_gsrwt(*args, *BASE, cwd=tmp_path)
    assert back.returncode == 0 and "0 ok, 2 skipped, 0 failed" in back.stderr
    assert table(tmp_path / "out" / "gsrwt.csv") == {
        name: {**row, "status": "skipped"} for name, row in first.items()}


def test_a_resumed_run_with_other_options_finishes_the_rest_and_refuses_the_done(
        tmp_path, photo):
    """The state an interrupted run leaves (some outputs with rows, the rest not done),
    resumed with other options: what was not done is done with the new ones, what was done
    is an error naming the difference."""
    (photo / "b.jpg").rename(tmp_path / "b.jpg")  # not reached by the first run
    assert run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    (tmp_path / "b.jpg").rename(photo / "b.jpg")
    resumed = run_gsrwt("rectify", "in", *BASE, "--scale", "0.5", "-o", "out", cwd=tmp_path)
    assert resumed.returncode == 1
    rows = table(tmp_path / "out" / "gsrwt.csv")
    assert rows["a.png"]["status"] == "error" and "scale 1 -> 0.5" in rows["a.png"]["error"]
    assert rows["a.png"]["out_width"] == "80"
    assert rows["b.jpg"]["status"] == "ok" and rows["b.jpg"]["out_width"] == "40"
    assert_rows_describe_their_files(rows, tmp_path)


def test_an_output_format_change_writes_the_new_file(tmp_path, photo):
    assert run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    again = run_gsrwt("rectify", "in", *BASE, "--ext", "webp", "-o", "out", cwd=tmp_path)
    assert again.returncode == 0 and "2 ok, 0 skipped, 0 failed" in again.stderr
    rows = table(tmp_path / "out" / "gsrwt.csv")
    assert {row["output"] for row in rows.values()} == {"out/a.webp", "out/b.webp"}
    assert_rows_describe_their_files(rows, tmp_path)


# --------------------------------------------------------------------------------------------
# Outputs with no valid record: checked against what this run makes of their image
# --------------------------------------------------------------------------------------------


def test_an_output_with_no_record_is_skipped_only_if_it_is_what_this_run_makes(
        tmp_path, photo):
    """The table gone (a killed run, ``--table -``): an output identical to what these
    options make is skipped with a true row; one made otherwise is an error; a user's own
    file is an error; none is rewritten."""
    assert run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    first = table(tmp_path / "out" / "gsrwt.csv")
    (tmp_path / "out" / "gsrwt.csv").unlink()
    same = run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path)
    assert same.returncode == 0 and "0 ok, 2 skipped, 0 failed" in same.stderr
    assert table(tmp_path / "out" / "gsrwt.csv") == {
        name: {**row, "status": "skipped"} for name, row in first.items()}

    (tmp_path / "out" / "gsrwt.csv").unlink()
    cv2.imwrite(str(tmp_path / "out" / "b.jpg"), smooth_texture(60, 80, 7))  # the user's
    hashes = {name: digest(tmp_path / "out" / name) for name in ("a.png", "b.jpg")}
    other = run_gsrwt("rectify", "in", "--pan", "10", "--tilt", "10", "--focal", "500",
                      "-o", "out", cwd=tmp_path)
    assert other.returncode == 1
    rows = table(tmp_path / "out" / "gsrwt.csv")
    for row in rows.values():
        assert row["status"] == "error" and row["out_width"] == "", row
        assert row["error"] == ("its output exists, not made with these options (no valid "
                                "row of the previous table records it); use --overwrite "
                                "to redo it"), row
    assert {name: digest(tmp_path / "out" / name) for name in hashes} == hashes
    # A user's file is never taken for ours, even with the options that made a.png.
    mine = run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path)
    assert mine.returncode == 1 and "0 ok, 1 skipped, 1 failed" in mine.stderr
    rows = table(tmp_path / "out" / "gsrwt.csv")
    assert rows["a.png"] == {**first["a.png"], "status": "skipped"}
    assert rows["b.jpg"]["status"] == "error"
    assert {name: digest(tmp_path / "out" / name) for name in hashes} == hashes


@pytest.mark.parametrize("kind", ["fifo", "directory", "symlink"])
def test_an_output_that_is_not_a_regular_file_is_an_error(tmp_path, photo, kind):
    assert run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    output = tmp_path / "out" / "a.png"
    (tmp_path / "kept.png").write_bytes(output.read_bytes())
    output.unlink()
    if kind == "fifo":
        os.mkfifo(output)
    elif kind == "directory":
        output.mkdir()
    else:
        output.symlink_to(tmp_path / "kept.png")  # the very bytes of the record: still not ours
    again = run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path)
    assert again.returncode == 1
    row = table(tmp_path / "out" / "gsrwt.csv")["a.png"]
    assert row["status"] == "error" and row["out_width"] == ""
    assert row["error"] == ("its output exists and is not a regular file; remove it or use "
                            "another -o")
    assert table(tmp_path / "out" / "gsrwt.csv")["b.jpg"]["status"] == "skipped"


# --------------------------------------------------------------------------------------------
# A corrupt previous table: its rows are input, validated, and never carried over verbatim
# --------------------------------------------------------------------------------------------

HUGE = "x" * 100_000


#: (table format, column, the corrupt value): each must be caught.
CORRUPTIONS = {
    "size 99999x1": ("csv", {"out_width": "99999", "out_height": "1"}),
    "size as text": ("csv", {"out_width": "eighty"}),
    "size negative": ("json", {"out_width": -80}),
    "size a float": ("json", {"out_width": 80.5}),
    "pan a list": ("json", {"pan_deg": [1, 2]}),
    "pan a bool": ("json", {"pan_deg": True}),
    "pan not finite": ("csv", {"pan_deg": "nan"}),
    "pan huge text": ("csv", {"pan_deg": "9" * 100_000}),
    "homography an object": ("json", {"homography": {"a": 1}}),
    "homography of 8 numbers": ("csv", {"homography": "1 0 0 0 1 0 0 0"}),
    "homography not numbers": ("csv", {"homography": "1 0 0 0 1 0 0 0 x"}),
    "error of 100,000 characters": ("json", {"error": HUGE}),
    "error with a newline": ("csv", {"error": "a\nb"}),
    "status unknown": ("csv", {"status": "bogus"}),
    "status interrupted": ("csv", {"status": "interrupted"}),
    "focal source unknown": ("json", {"focal_source": "magic"}),
    "confidence above 1": ("csv", {"confidence": "2"}),
    "made_with missing": ("csv", {"made_with": None}),
    "made_with huge": ("json", {"made_with": "pan=" + "9" * 100_000}),
    "made_with not tokens": ("csv", {"made_with": "pan 20"}),
    "horizon_in_image a number": ("json", {"horizon_in_image": 3}),
    "image a number": ("json", {"image": 5}),
}


@pytest.mark.parametrize("fmt, corruption", CORRUPTIONS.values(), ids=list(CORRUPTIONS))
def test_a_corrupt_previous_row_is_never_carried_over(tmp_path, photo, fmt, corruption):
    """A previous row that the table writer could not have written, or that does not fit
    its file, is not kept: its image is checked against what this run makes (skipped with
    a true row, as here, where it is) and nothing of the corrupt row reappears."""
    (photo / "b.jpg").unlink()
    name = f"out/gsrwt.{fmt}"
    args = ("rectify", "in", *BASE, "-o", "out", "--table", name)
    assert run_gsrwt(*args, cwd=tmp_path).returncode == 0
    path = tmp_path / name
    if fmt == "csv":
        rows = read_table(path)
        good = dict(rows[0])
        columns = [c for c in rows[0] if corruption.get(c, "") is not None]
        corrupt = {k: v for k, v in {**good, **corruption}.items() if k in columns}
        with open(path, "w", newline="") as stream:
            writer = csv.DictWriter(stream, columns)
            writer.writeheader()
            writer.writerow(corrupt)
    else:
        rows = read_table(path)
        good = dict(rows[0])
        path.write_text(json.dumps([{**good, **corruption}]))
    again = run_gsrwt(*args, cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert "0 ok, 1 skipped, 0 failed" in again.stderr
    text = path.read_text()
    assert len(text) < 3000 and "99999" not in text and "bogus" not in text
    (new,) = read_table(text, fmt)
    assert new == {**good, "status": "skipped"}  # recomputed: the first run's true row
    assert len(again.stderr) < 300


def test_a_corrupt_row_of_a_file_made_otherwise_is_an_error_with_bounded_words(tmp_path,
                                                                                photo):
    """A corrupt row cannot vouch for its file: with other options the image is an error,
    whose message quotes nothing of the row."""
    (photo / "b.jpg").unlink()
    assert run_gsrwt("rectify", "in", *BASE, "-o", "out", cwd=tmp_path).returncode == 0
    path = tmp_path / "out" / "gsrwt.csv"
    (row,) = read_table(path)
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, list(row))
        writer.writeheader()
        writer.writerow({**row, "made_with": row["made_with"].replace("pan=20",
                                                                      "pan=" + HUGE)})
    again = run_gsrwt("rectify", "in", "--pan", "10", "--tilt", "10", "--focal", "500",
                      "-o", "out", cwd=tmp_path)
    assert again.returncode == 1 and HUGE[:200] not in again.stderr + path.read_text()
    assert "no valid row of the previous table records it" in again.stderr


def test_a_dry_run_records_planned_rows_and_the_real_run_writes_them(tmp_path):
    """``--dry-run`` writes the table of a run that writes nothing: its rows say ``planned``
    (never ``ok`` for a file that is not on disk), and the real run after it writes every
    output (``ok``, none ``skipped``)."""
    folder = tmp_path / "in"
    make_photos(folder, 3, (160, 120))
    dry = run_gsrwt("rectify", str(folder), *POSE, "-o", "out", "--dry-run", cwd=tmp_path)
    assert dry.returncode == 0, dry.stderr
    assert "3 planned, 0 ok, 0 skipped, 0 failed" in dry.stderr
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert [row["status"] for row in rows] == ["planned"] * 3
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["gsrwt.csv"]
    real = run_gsrwt("rectify", str(folder), *POSE, "-o", "out", cwd=tmp_path)
    assert real.returncode == 0 and "3 ok, 0 skipped, 0 failed" in real.stderr, real.stderr
    assert [row["status"] for row in read_table(tmp_path / "out" / "gsrwt.csv")] == ["ok"] * 3
