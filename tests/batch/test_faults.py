"""Faults caused for real: killed workers and parents, signals, full and read-only disks,
decompression bombs, undecodable files between good ones, hostile names and values.

Every test runs the installed ``gsrwt`` in a real subprocess (or the real worker code on real
files) and asserts outcomes: exit codes, table rows, the pixels of outputs, the sha256 of
inputs, no stray or partial files, no traceback, bounded stderr.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import signal
import subprocess
import sys
import time
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gsrwt_cli import View
from gsrwt_cli.api.rectify import rectify_image
from gsrwt_cli.batch.rectify_jobs import ImageWorker, Job, Settings
from gsrwt_cli.io.outputs import TEMPORARY_PATTERN
from tests.helpers.cli import GSRWT, run_gsrwt, run_gsrwt_measuring_memory, start_gsrwt
from tests.helpers.faults import (
    POSE,
    assert_clean_stderr,
    assert_table_is_the_record,
    make_photos,
    sha256_tree,
    stray_files,
    wait_for_outputs,
    wait_until_gone,
)
from tests.helpers.images import smooth_texture
from tests.helpers.tables import by_image_name, read_table

#: Slow (out of the quick loop, ``pytest -m "not slow"``): the suite runs the command in
#: subprocesses, kills them and fills disks.
pytestmark = pytest.mark.slow


def rectified_pixels(path: Path, pan: float, tilt: float, focal: float) -> np.ndarray:
    """What gsrwt's Python API makes of an image file (the reference for batch outputs)."""
    image = cv2.imdecode(np.fromfile(path, np.uint8), cv2.IMREAD_UNCHANGED)
    output, _ = rectify_image(image, View(pan, tilt, focal))
    return output


def children_of(pid: int) -> list[int]:
    """Live processes whose parent is ``pid`` (from /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                found.append(int(entry.name))
    return found


# --------------------------------------------------------------------------------------------
# Undecodable files between good ones: never the previous image's pixels
# --------------------------------------------------------------------------------------------

BAD_FILES = {
    "text.png": b"this is a text file, not a PNG\n" * 4,
    "random.jpg": bytes(np.random.default_rng(7).integers(0, 256, 5000, dtype=np.uint8)),
    "fake.tif": b"II*\x00" + bytes(600),
    "header-only.jpg": b"\xff\xd8\xff\xe0\x00\x10JFIF\x00" + bytes(100) + b"\xff\xd9",
}


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_undecodable_file_after_a_good_one_is_an_error_not_its_pixels(tmp_path, jobs):
    folder = tmp_path / "in"
    folder.mkdir()
    good = smooth_texture(120, 160, 1)
    cv2.imwrite(str(folder / "a.png"), good)
    for name, data in BAD_FILES.items():
        (folder / name).write_bytes(data)
    cv2.imwrite(str(folder / "z.png"), smooth_texture(120, 160, 2))
    before = sha256_tree(folder)
    result = run_gsrwt("rectify", str(folder), "--pan", "0", "--tilt", "0", "--focal", "300",
                       "-o", str(tmp_path / "out"), "-j", jobs)
    assert result.returncode == 1, result.stderr
    assert_clean_stderr(result.stderr)
    rows = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    for name in BAD_FILES:
        assert rows[name]["status"] == "error" and rows[name]["error"], rows[name]
        assert not (tmp_path / "out" / name).exists()
        assert sum(f"{name}:" in line for line in result.stderr.splitlines()) == 1
    for name in ("a.png", "z.png"):
        assert rows[name]["status"] == "ok"
        np.testing.assert_array_equal(cv2.imread(str(tmp_path / "out" / name)),
                                      cv2.imread(str(folder / name)))
    assert sha256_tree(folder) == before
    assert stray_files(tmp_path) == []


KINDS = ["good-a", "good-b", "grey", "sixteen", *BAD_FILES]


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(sequence=st.lists(st.sampled_from(KINDS), min_size=1, max_size=8))
def test_one_worker_over_any_sequence_of_good_and_bad_files(tmp_path_factory, sequence):
    """The real worker (its memory reused from image to image) over any order of files:
    every good file gives exactly its own rectified pixels, every bad one an error."""
    folder = tmp_path_factory.mktemp("sequence")
    images = {
        "good-a": smooth_texture(90, 120, 11),
        "good-b": smooth_texture(90, 120, 12),  # same shape as good-a, other pixels
        "grey": smooth_texture(70, 100, 13, channels=1),
        "sixteen": smooth_texture(90, 120, 14).astype(np.uint16) * 257,
    }
    worker = ImageWorker(Settings(overwrite=True, root=folder / "out"))
    for index, kind in enumerate(sequence):
        source = folder / f"{index}-{kind}.png"
        if kind in images:
            cv2.imwrite(str(source), images[kind])
        else:
            source.write_bytes(BAD_FILES[kind])
        output = folder / "out" / source.name
        row = worker(Job(source, output, {"pan": 25, "tilt": -15, "focal": 150}, "test"))
        if kind in images:
            assert row["status"] == "ok", row
            np.testing.assert_array_equal(cv2.imread(str(output), cv2.IMREAD_UNCHANGED),
                                          rectified_pixels(source, 25, -15, 150))
        else:
            assert row["status"] == "error" and not output.exists(), row


# --------------------------------------------------------------------------------------------
# Names: not UTF-8, with newlines, from standard input
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_names_that_are_not_utf8_or_hold_newlines(tmp_path, jobs):
    folder = tmp_path / "in"
    folder.mkdir()
    image = smooth_texture(100, 140, 5)
    names = [b"bad\xff.png", b"new\nline.png", "caf\u00e9.png".encode()]
    for name in names:
        (Path(os.fsdecode(bytes(folder) + b"/" + name))).write_bytes(
            cv2.imencode(".png", image)[1].tobytes())
    (Path(os.fsdecode(bytes(folder) + b"/broken\n\xfe.jpg"))).write_bytes(b"not a jpeg")
    out = tmp_path / "out"
    result = run_gsrwt("rectify", str(folder), *POSE, "-o", str(out), "-j", jobs)
    assert result.returncode == 1
    assert_clean_stderr(result.stderr)
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error:")]
    assert len(errors) == 1 and "broken\\n" in errors[0], result.stderr
    expected = rectified_pixels(Path(os.fsdecode(bytes(folder) + b"/" + names[0])), 20, 10, 900)
    for name in names:
        written = Path(os.fsdecode(bytes(out) + b"/" + name))
        np.testing.assert_array_equal(cv2.imdecode(np.fromfile(written, np.uint8), -1), expected)
    raw = (out / "gsrwt.csv").read_bytes()
    assert b"bad\xff.png" in raw  # the table keeps the name's own bytes

    listed = b"\n".join(bytes(folder) + b"/" + name for name in names[:1]) + b"\n"
    piped = run_gsrwt("rectify", "-", *POSE, "-o", str(tmp_path / "piped"), stdin=listed,
                      text=False)
    assert piped.returncode == 0, piped.stderr
    assert Path(os.fsdecode(bytes(tmp_path) + b"/piped/bad\xff.png")).is_file()


# --------------------------------------------------------------------------------------------
# Dying workers, dying parents, signals
# --------------------------------------------------------------------------------------------


def test_a_killed_worker_costs_only_its_image(tmp_path):
    sources = make_photos(tmp_path / "in", 30)
    before = sha256_tree(tmp_path / "in")
    process = start_gsrwt("rectify", "in", *POSE, "-o", "out", "-j", "2", cwd=tmp_path,
                          own_session=True)
    wait_for_outputs(tmp_path / "out", 1, process)
    os.kill(busy_worker(process.pid), signal.SIGKILL)
    stdout, stderr = process.communicate(timeout=120)
    assert_clean_stderr(stderr)
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert_table_is_the_record(rows, tmp_path / "out", sources)
    assert stray_files(tmp_path) == []
    assert sha256_tree(tmp_path / "in") == before
    died = [row for row in rows if row["status"] == "error"]
    if not died:  # killed after writing its image whole, before reporting it: done after all
        assert process.returncode == 0 and all(row["status"] == "ok" for row in rows)
        return
    assert process.returncode == 1, stderr
    assert [row["error"] for row in died] == ["worker died: signal 9 (SIGKILL)"]
    assert sum(row["status"] == "ok" for row in rows) == len(sources) - 1
    rerun = run_gsrwt("rectify", "in", *POSE, "-o", "out", cwd=tmp_path)
    assert rerun.returncode == 0 and "1 ok, 29 skipped, 0 failed" in rerun.stderr


def busy_worker(parent: int) -> int:
    """A worker of ``parent`` that is running (computing an image), not waiting for one."""
    time.sleep(0.03)  # past the moment its first image was written and reported
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        for pid in children_of(parent):
            with contextlib.suppress(OSError):
                state = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1]
                if state.split()[0] == "R":
                    return pid
        time.sleep(0.002)
    raise AssertionError("no worker was busy")


#: A pose the photos show (a rectangle's corners): without --bbox, framed ``full`` (capped),
#: unlike ``POSE``'s given numbers, so the rows a stopped run makes itself must be too.
GUIDED = ("--corners", "400,300 1200,250 1150,950 450,900", "--focal", "900")


@pytest.mark.parametrize("pose", [POSE, GUIDED], ids=["given", "guided"])
@pytest.mark.parametrize("stop, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupt_writes_the_table_of_what_finished(tmp_path, stop, code, pose):
    # Enough images that the stop lands mid-batch however fast the batch (40 took 0.4 s).
    sources = make_photos(tmp_path / "in", 120)
    process = start_gsrwt("rectify", "in", *pose, "-o", "out", "-j", "2", cwd=tmp_path,
                          own_session=True)
    wait_for_outputs(tmp_path / "out", 3, process)
    os.killpg(process.pid, stop)  # the whole group, as a terminal's Ctrl-C does
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == code, stderr
    assert_clean_stderr(stderr)
    assert "interrupted:" in stderr
    assert wait_until_gone(process.pid), "workers outlived the command"
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    statuses = {row["status"] for row in rows}
    assert statuses <= {"ok", "interrupted"} and "interrupted" in statuses, statuses
    assert_table_is_the_record(rows, tmp_path / "out", sources)
    assert stray_files(tmp_path) == []
    frame = "bbox=full" if pose is GUIDED else "bbox=frontal"
    assert all(frame in row["made_with"].split() for row in rows if row["status"] == "ok")

    first = {row["image"]: row for row in rows if row["status"] == "ok"}
    rerun = run_gsrwt("rectify", "in", *pose, "-o", "out", cwd=tmp_path)
    assert rerun.returncode == 0, rerun.stderr
    again = {row["image"]: row for row in read_table(tmp_path / "out" / "gsrwt.csv")}
    for image, row in first.items():  # the record of the first run survives the rerun
        assert again[image] == {**row, "status": "skipped"}


def test_a_killed_parent_takes_its_workers_and_the_next_run_cleans_up(tmp_path):
    sources = make_photos(tmp_path / "in", 40)
    process = start_gsrwt("rectify", "in", *POSE, "-o", "out", "-j", "2", cwd=tmp_path,
                          own_session=True)
    wait_for_outputs(tmp_path / "out", 2, process)
    os.kill(process.pid, signal.SIGKILL)
    stdout, stderr = process.communicate(timeout=60)
    assert wait_until_gone(process.pid), "workers outlived their parent"
    assert stderr == ""  # the workers left quietly, no BrokenPipeError tracebacks
    leftovers = stray_files(tmp_path)
    assert all(TEMPORARY_PATTERN.match(p.name) for p in leftovers)  # only the table's
    for output in (tmp_path / "out").glob("img*.jpg"):  # whatever was written is whole
        assert cv2.imread(str(output)) is not None
    rerun = run_gsrwt("rectify", "in", *POSE, "-o", "out", cwd=tmp_path)
    assert rerun.returncode == 0, rerun.stderr
    assert stray_files(tmp_path) == []
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert {row["status"] for row in rows} <= {"ok", "skipped"}
    assert_table_is_the_record(rows, tmp_path / "out", sources)
    # Skipped rows were made from headers: the same geometry as a fresh run's.
    fresh = run_gsrwt("rectify", "in", *POSE, "-o", "fresh", "--table", "fresh.csv",
                      cwd=tmp_path)
    assert fresh.returncode == 0
    columns = ("out_width", "out_height", "homography", "theta_deg", "vp_col")
    by_name = by_image_name(read_table(tmp_path / "fresh.csv"))
    for row in rows:
        assert all(row[c] == by_name[Path(row["image"]).name][c] for c in columns), row


def test_stale_temporaries_of_dead_processes_are_removed_live_ones_kept(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = out / f".img.jpg.gsrwt-{dead.pid}-abc123.part"
    live = out / f".img.jpg.gsrwt-{os.getpid()}-def456.part"
    user_file = out / ".notes.part"
    for path in (stale, live, user_file):
        path.write_bytes(b"x")
    cv2.imwrite(str(tmp_path / "img.png"), smooth_texture(40, 50, 1))
    result = run_gsrwt("rectify", str(tmp_path / "img.png"), *POSE, "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert not stale.exists() and live.exists() and user_file.exists()


@pytest.mark.parametrize("command", ["render", "lines"])
def test_render_and_draw_remove_stale_temporaries_too(tmp_path, command):
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = out / f".view.png.gsrwt-{dead.pid}-abc123.part"
    stale.write_bytes(b"half")
    texture = tmp_path / "wall.png"
    cv2.imwrite(str(texture), smooth_texture(60, 80, 1))
    if command == "render":
        (tmp_path / "views.csv").write_text("image,pan,tilt,focal\nview.png,10,5,100\n")
        args = ["render", str(texture), "--sidecar", str(tmp_path / "views.csv"), "-o", str(out)]
    else:
        args = ["lines", str(texture), "--draw", str(out)]
    result = run_gsrwt(*args)
    assert result.returncode == 0, result.stderr
    assert not stale.exists() and stray_files(tmp_path) == []


# --------------------------------------------------------------------------------------------
# Disks: full, read-only; paths that are not directories
# --------------------------------------------------------------------------------------------


def mount_tmpfs(target: Path, options: str) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    target.mkdir(parents=True, exist_ok=True)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(target)],
                             capture_output=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.decode().strip()}")


@pytest.fixture
def small_disk(tmp_path):
    disk = tmp_path / "disk"
    mount_tmpfs(disk, "size=600k")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], check=False)


def test_a_full_disk_fails_images_whole_and_keeps_the_record(tmp_path, small_disk):
    sources = make_photos(tmp_path / "in", 6, size=(640, 480))
    result = run_gsrwt("rectify", str(tmp_path / "in"), *POSE, "-o", str(small_disk / "out"),
                       "--table", str(tmp_path / "table.csv"), "--ext", "png", "-j", "2")
    assert result.returncode == 1, result.stderr
    assert_clean_stderr(result.stderr)
    rows = read_table(tmp_path / "table.csv")
    assert any("No space left on device" in row["error"] for row in rows), rows
    assert_table_is_the_record(rows, small_disk / "out", sources)
    assert stray_files(small_disk) == []


def test_a_full_disk_under_the_table_is_one_line_exit_2(tmp_path, small_disk):
    (small_disk / "filler").write_bytes(b"\0" * (600 * 1024 - 8192))
    names = [f"{'n' * 150}{index:04d}.png" for index in range(60)]
    for name in names:
        cv2.imwrite(str(tmp_path / name), smooth_texture(8, 8, 1))
    result = run_gsrwt("rectify", *(str(tmp_path / n) for n in names), *POSE,
                       "-o", str(tmp_path / "out"), "--table", str(small_disk / "t.csv"))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "--table" in lines[0] and "No space left" in lines[0], lines
    assert not (small_disk / "t.csv").exists() and stray_files(small_disk) == []


def test_a_read_only_output_is_one_line_exit_2(tmp_path):
    readonly = tmp_path / "ro"
    mount_tmpfs(readonly, "size=1m,ro")
    try:
        cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(40, 50, 1))
        for target in ("-o", "--table"):
            args = ["-o", str(readonly / "out")] if target == "-o" else [
                "-o", str(tmp_path / "out"), "--table", str(readonly / "t.csv")]
            result = run_gsrwt("rectify", str(tmp_path / "a.png"), *POSE, *args)
            assert result.returncode == 2, result.stderr
            (line,) = result.stderr.strip().splitlines()
            assert line.startswith(f"Error: {target} ") and "Read-only file system" in line
    finally:
        subprocess.run(["umount", "-l", str(readonly)], check=False)


@pytest.mark.parametrize("option", ["-o", "--table"])
def test_an_output_under_a_file_is_one_line_exit_2(tmp_path, option):
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(40, 50, 1))
    (tmp_path / "FILE").write_text("keep me")
    args = ["-o", str(tmp_path / "FILE" / "sub")] if option == "-o" else [
        "-o", str(tmp_path / "out"), "--table", str(tmp_path / "FILE" / "t.csv")]
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), *POSE, *args)
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith(f"Error: {option} ") and "FILE is not a directory" in line, line
    assert (tmp_path / "FILE").read_text() == "keep me"


def without_permission_override(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run gsrwt as this user but without the capabilities that let root ignore permission
    bits (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH), so a directory of mode 000 is unreadable."""
    return subprocess.run(["setpriv", "--bounding-set=-dac_override,-dac_read_search",
                           str(GSRWT), *args], capture_output=True, text=True, cwd=cwd,
                          timeout=120)


def test_unreadable_directories_are_reported(tmp_path):
    if shutil.which("setpriv") is None:
        pytest.skip("needs setpriv (util-linux) to drop permission overrides")
    tree = tmp_path / "in"
    (tree / "open").mkdir(parents=True)
    (tree / "closed").mkdir()
    for folder in (tree / "open", tree / "closed"):
        cv2.imwrite(str(folder / "a.png"), smooth_texture(40, 50, 1))
    os.chmod(tree / "closed", 0)
    try:
        probe = subprocess.run(["setpriv", "--bounding-set=-dac_override,-dac_read_search",
                                "ls", str(tree / "closed")], capture_output=True)
        if probe.returncode == 0:
            pytest.skip("this user reads a directory of mode 000 anyway")
        recursive = without_permission_override("rectify", "-r", "in", *POSE, "-o", "out",
                                                cwd=tmp_path)
        assert recursive.returncode == 1, recursive.stderr
        assert_clean_stderr(recursive.stderr)
        assert "in/closed: cannot read directory (Permission denied)" in recursive.stderr
        assert (tmp_path / "out" / "open" / "a.png").is_file()
        top = without_permission_override("rectify", "in/closed", *POSE, "-o", "out2",
                                          cwd=tmp_path)
        assert top.returncode == 2
        (line,) = top.stderr.strip().splitlines()
        assert "in/closed: cannot read directory (Permission denied)" in line
        assert not (tmp_path / "out2").exists()
    finally:
        os.chmod(tree / "closed", 0o755)


# --------------------------------------------------------------------------------------------
# Decompression bombs and overflowing values
# --------------------------------------------------------------------------------------------


def png_bomb(width: int, height: int) -> bytes:
    """A valid grey PNG of ``width x height`` zeros: a few hundred KB on disk."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return len(data).to_bytes(4, "big") + body + zlib.crc32(body).to_bytes(4, "big")

    header = width.to_bytes(4, "big") + height.to_bytes(4, "big") + bytes([8, 0, 0, 0, 0])
    compressor = zlib.compressobj(9)
    row = bytes(width + 1)
    data = b"".join(compressor.compress(row) for _ in range(height)) + compressor.flush()
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", data) + chunk(
        b"IEND", b"")


@pytest.mark.parametrize("dry_run", [False, True])
def test_a_decompression_bomb_is_refused_from_its_header(tmp_path, dry_run):
    bomb = tmp_path / "bomb.png"
    bomb.write_bytes(png_bomb(30000, 30000))
    assert bomb.stat().st_size < 2_000_000
    command = ["rectify", str(bomb), *POSE, "-o", str(tmp_path / "out")]
    if dry_run:
        command.append("--dry-run")
    result, peak_kib = run_gsrwt_measuring_memory(*command)
    assert result.returncode == 1
    assert "30000x30000 = 900.0 megapixels, above the input limit of 300" in result.stderr
    assert_clean_stderr(result.stderr)
    # The largest process of the run stayed small: the image alone would take 900 MB.
    assert peak_kib < 300 * 1024, f"peak RSS {peak_kib / 1024:.0f} MiB"
    limited, peak_kib = run_gsrwt_measuring_memory(*command, "--max-input-pixels", "1000M",
                                                   "--max-pixels", "1k")
    assert "above --max-pixels" in limited.stderr  # past the header, refused by its output
    assert peak_kib < 300 * 1024, f"peak RSS {peak_kib / 1024:.0f} MiB"


@pytest.mark.parametrize("extra, message", [
    (("--px-per-unit", "100"), "more than any image can be"),
    (("--scale", "1e308"), "more than any image can be"),
    (("--bbox", "-1e308,0,1e308,10"), "more than any image can be"),
])
def test_overflowing_values_are_rows_not_crashes(tmp_path, extra, message):
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(40, 50, 1))
    cv2.imwrite(str(tmp_path / "b.png"), smooth_texture(40, 50, 2))
    # distance 1e307 is refused where it enters (below 1e12, test_sidecar_faults.py); 1e11 is
    # accepted and still makes --px-per-unit 100 ask for 1.7e12-pixel outputs.
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal,distance\na.png,10,5,300,1e11\nb.png,10,5,300,1e11\n")
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), str(tmp_path / "b.png"),
                       "--sidecar", str(tmp_path / "views.csv"), "-o", str(tmp_path / "out"),
                       *extra)
    assert_clean_stderr(result.stderr)
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert len(rows) == 2
    assert all(row["status"] == "error" and message in row["error"] for row in rows), rows
    assert result.returncode == 1


@pytest.mark.parametrize("pose", [("89.9999999", "89.9999999", "300"), ("10", "5", "1e300")])
def test_extreme_poses_are_never_ok_with_non_finite_numbers(tmp_path, pose):
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(40, 50, 1))
    pan, tilt, focal = pose
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), "--pan", pan, "--tilt", tilt,
                       "--focal", focal, "-o", str(tmp_path / "out"))
    assert_clean_stderr(result.stderr)
    if result.returncode == 2:  # refused where the value entered
        assert len(result.stderr.strip().splitlines()) == 1
        return
    (row,) = read_table(tmp_path / "out" / "gsrwt.csv")
    if row["status"] == "ok":
        values = np.array(row["homography"].split(), dtype=float)
        assert np.all(np.isfinite(values))
        image = cv2.imread(str(tmp_path / "out" / "a.png"))
        assert image is not None and image.std() > 0  # not an all-fill image
    else:
        assert row["status"] == "error" and result.returncode == 1


def test_formats_that_cannot_hold_the_output_say_which_can(tmp_path):
    cv2.imwrite(str(tmp_path / "deep.tif"), np.zeros((20, 30), np.int32))  # no format holds it
    cv2.imwrite(str(tmp_path / "grey.png"), smooth_texture(20, 30, 1, channels=1))
    result = run_gsrwt("rectify", str(tmp_path / "deep.tif"), *POSE, "-o",
                       str(tmp_path / "out"))
    assert "no output format gsrwt writes can hold them" in result.stderr
    assert "--ext tif" not in result.stderr
    wide = run_gsrwt("rectify", str(tmp_path / "grey.png"), *POSE, "--scale", "3000",
                     "--max-pixels", "10G", "--ext", "jpg", "-o", str(tmp_path / "o2"),
                     "--dry-run")
    assert ".jpg cannot store images over 65535 pixels wide or high" in wide.stderr
    assert "use --ext png or --ext tif" in wide.stderr
    # OpenCV reads a GIF, and gsrwt writes none: the input's format, kept by default, cannot be
    # the output's, and the line says which --ext can (it said "use one of .jpg, ...", which
    # named no option)
    assert cv2.imwrite(str(tmp_path / "anim.gif"), smooth_texture(20, 30, 1))
    gif = run_gsrwt("rectify", str(tmp_path / "anim.gif"), *POSE, "-o", str(tmp_path / "o3"))
    assert gif.returncode == 1
    assert gif.stderr.splitlines()[0].endswith(
        "anim.gif: cannot write '.gif' files; use --ext jpg or --ext png or --ext tif or "
        "--ext bmp or --ext webp")
    assert sorted(path.name for path in (tmp_path / "o3").iterdir()) == ["gsrwt.csv"]


# --------------------------------------------------------------------------------------------
# Writes outside the output: symbolic links inside it
# --------------------------------------------------------------------------------------------


def test_recursive_outputs_never_follow_a_symlink_out_of_the_output(tmp_path):
    tree = tmp_path / "in"
    (tree / "sub").mkdir(parents=True)
    (tree / "top.png").write_bytes(cv2.imencode(".png", smooth_texture(40, 50, 1))[1])
    (tree / "sub" / "x.png").write_bytes(cv2.imencode(".png", smooth_texture(40, 50, 2))[1])
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "x.png").write_text("a user's file")
    out = tmp_path / "out"
    out.mkdir()
    (out / "sub").symlink_to("../elsewhere")
    before = sha256_tree(elsewhere)
    for overwrite in ([], ["--overwrite"]):
        result = run_gsrwt("rectify", "-r", str(tree), *POSE, "-o", str(out), *overwrite)
        assert result.returncode == 1
        assert_clean_stderr(result.stderr)
        rows = by_image_name(read_table(out / "gsrwt.csv"))
        assert rows["top.png"]["status"] in ("ok", "skipped")
        assert rows["x.png"]["status"] == "error"
        assert "outside the output" in rows["x.png"]["error"]
        assert sha256_tree(elsewhere) == before


def test_files_that_change_order_between_runs_keep_their_own_rows(tmp_path):
    """Rows follow the images, not their positions: new files sorting first, and a changed
    sidecar, never shift one image's record onto another."""
    folder = tmp_path / "in"
    folder.mkdir()
    poses = {"m.png": (10, 5), "n.png": (-20, 15)}
    for index, name in enumerate(poses):
        cv2.imwrite(str(folder / name), smooth_texture(60, 80, index))

    def sidecar(entries):
        lines = ["image,pan,tilt,focal"] + [f"{n},{p},{t},200" for n, (p, t) in entries.items()]
        (tmp_path / "views.csv").write_text("\n".join(lines) + "\n")

    sidecar(poses)
    args = ["rectify", str(folder), "--sidecar", str(tmp_path / "views.csv"), "-o",
            str(tmp_path / "out")]
    assert run_gsrwt(*args).returncode == 0
    first = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    cv2.imwrite(str(folder / "a.png"), smooth_texture(60, 80, 9))  # sorts before the others
    sidecar({"a.png": (30, -5), **poses})
    assert run_gsrwt(*args).returncode == 0
    second = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    assert list(second) == ["a.png", "m.png", "n.png"]
    assert second["a.png"]["status"] == "ok" and second["a.png"]["pan_deg"] == "30"
    for name in poses:
        assert second[name] == {**first[name], "status": "skipped"}


def test_table_of_a_rerun_is_byte_identical_but_for_status(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for index in range(3):
        cv2.imwrite(str(folder / f"{index}.png"), smooth_texture(50, 70, index))
    args = ["rectify", str(folder), *POSE, "-o", str(tmp_path / "out")]
    assert run_gsrwt(*args).returncode == 0
    first = (tmp_path / "out" / "gsrwt.csv").read_text()
    assert run_gsrwt(*args).returncode == 0
    second = (tmp_path / "out" / "gsrwt.csv").read_text()
    assert second == first.replace(",ok,", ",skipped,")
    assert io.StringIO(second).read().count(",skipped,") == 3
