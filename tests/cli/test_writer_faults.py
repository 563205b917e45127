"""Faults an attacker or a bad night would try on the commands that write and print.

Real files, real ``gsrwt`` processes, no mocks. Each test states what must hold:

- ``render --sidecar`` and ``lines/match --draw`` write only inside the output the user
  named: a sidecar name with ``..``, an absolute name, or a symbolic link inside the output
  that leads out is an error for that row or image (one line, exit 1), the others are still
  written, and nothing outside the output changes (every file's sha256, every link, no new
  entries, no ``.part`` files left anywhere).
- A reader that closes the pipe ends any command quietly with status 141 (128 + SIGPIPE).
- File names with a newline or with bytes that are not UTF-8 give correct results or one-line
  errors, never a crash or a traceback.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from tests.helpers.cli import run_gsrwt, start_gsrwt
from tests.helpers.images import smooth_texture
from tests.helpers.paths import ROOT
from tests.helpers.tables import read_table

#: Slow (out of the quick loop, ``pytest -m "not slow"``): the suite runs the command in
#: subprocesses.
pytestmark = pytest.mark.slow

VIEWS = ROOT / "sample_data" / "views"
KNOB = ROOT / "sample_data" / "templates" / "knob.png"
#: Longest stderr any of these runs may print (a few one-line errors).
STDERR_LIMIT = 4000
#: Longest single error line (messages.LINE_LIMIT plus "Error: ").
LINE_LIMIT = 2100
#: Status of a process whose reader closed the pipe: 128 + SIGPIPE.
CLOSED_PIPE_STATUS = 128 + signal.SIGPIPE


# --------------------------------------------------------------------------------------------
# Helpers: what the file tree holds, and what a clean stderr is
# --------------------------------------------------------------------------------------------


def sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def snapshot(root: Path) -> dict[str, str]:
    """Every entry below ``root``, links not followed: relative path -> what it is.

    A regular file is its sha256, a link its target, a directory ``dir``.
    """
    entries: dict[str, str] = {}
    for directory, subdirectories, files in os.walk(root):
        for name in subdirectories + files:
            full = os.path.join(directory, name)
            relative = os.path.relpath(full, root)
            if os.path.islink(full):
                entries[relative] = "link -> " + os.readlink(full)
            elif os.path.isdir(full):
                entries[relative] = "dir"
            else:
                entries[relative] = "sha256 " + sha256(full)
    return entries


def outside(entries: dict[str, str], output: str) -> dict[str, str]:
    """The entries that are not the output directory ``output`` (relative) or below it."""
    return {path: what for path, what in entries.items()
            if path != output and not path.startswith(output + os.sep)}


def assert_nothing_changed_outside(before: dict[str, str], after: dict[str, str],
                                   output: str) -> None:
    """Outside ``output``: the same entries with the same contents; nowhere a ``.part``."""
    assert outside(after, output) == outside(before, output)
    assert not [path for path in after if path.endswith(".part")], after


def assert_clean_stderr(stderr: str, error_lines: int | None = None) -> list[str]:
    """No traceback, bounded, every line an ``Error: `` line; returns the lines."""
    assert "Traceback" not in stderr
    assert len(stderr) <= STDERR_LIMIT, stderr[:500]
    lines = stderr.splitlines()
    for line in lines:
        assert line.startswith("Error: "), line
        assert len(line) <= LINE_LIMIT
    if error_lines is not None:
        assert len(lines) == error_lines, stderr
    return lines


# --------------------------------------------------------------------------------------------
# render --sidecar: names from the sidecar stay inside -o
# --------------------------------------------------------------------------------------------


@pytest.fixture
def render_workspace(tmp_path: Path) -> Path:
    """A texture, a user's photo (the decoy), a directory beside the output, and an output
    holding a directory link and a file link that both lead out of it."""
    cv2.imwrite(str(tmp_path / "wall.png"), smooth_texture(90, 120, seed=3))
    (tmp_path / "photos").mkdir()
    cv2.imwrite(str(tmp_path / "photos" / "IMG_0001.png"), smooth_texture(60, 80, seed=4))
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "absolute").mkdir()
    (tmp_path / "out").mkdir()
    os.symlink("../elsewhere", tmp_path / "out" / "sub")
    os.symlink("../photos/IMG_0001.png", tmp_path / "out" / "link.png")
    return tmp_path


ESCAPING_NAMES = {
    "parent": ("../x.png", "has a '..' part"),
    "parent-over-a-photo": ("../photos/IMG_0001.png", "has a '..' part"),
    "absolute": (None, "is an absolute path"),  # tmp_path/absolute/x.png
    "down-and-up": ("sub/../../x.png", "has a '..' part"),
    "backslashes": ("..\\photos\\IMG_0001.png", "has a '..' part"),
    "directory-link": ("sub/x.png", "outside the output"),
    "below-a-directory-link": ("sub/new/deeper/x.png", "outside the output"),
    "file-link": ("link.png", "is a symbolic link to"),
}


@pytest.mark.parametrize("case", sorted(ESCAPING_NAMES))
def test_render_refuses_a_sidecar_name_that_leaves_the_output(render_workspace, case):
    workspace = render_workspace
    name, problem = ESCAPING_NAMES[case]
    if name is None:
        name = str(workspace / "absolute" / "x.png")
    (workspace / "views.csv").write_text(
        "image,pan,tilt,focal,width,height\n"
        f"\"{name}\",10,20,300,80,60\n"
        "good.png,-10,15,300,80,60\n"
    )
    inputs = {path: sha256(workspace / path)
              for path in ("wall.png", "views.csv", "photos/IMG_0001.png")}
    before = snapshot(workspace)
    result = run_gsrwt("render", "wall.png", "--sidecar", "views.csv", "-o", "out",
                       "--overwrite", cwd=workspace)
    assert result.returncode == 1, result.stderr
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert line.startswith("Error: views.csv line 2, field 'image': ")
    assert problem in line
    after = snapshot(workspace)
    assert_nothing_changed_outside(before, after, "out")
    assert {path: sha256(workspace / path) for path in inputs} == inputs
    # The link stays a link to the photo; the good row is rendered and alone in the sidecar.
    assert os.readlink(workspace / "out" / "link.png") == "../photos/IMG_0001.png"
    assert os.listdir(workspace / "elsewhere") == []
    assert cv2.imread(str(workspace / "out" / "good.png")).shape == (60, 80, 3)
    assert [row["image"] for row in read_table(workspace / "out" / "views.csv")] \
        == ["good.png"]
    assert set(after) - set(before) == {"out/good.png", "out/views.csv"}


def test_render_never_overwrites_the_texture_or_the_sidecar(tmp_path):
    """Texture and sidecar inside -o: rows naming them, even with --overwrite, are refused."""
    out = tmp_path / "out"
    out.mkdir()
    cv2.imwrite(str(out / "wall.png"), smooth_texture(90, 120, seed=3))
    (out / "views.csv").write_text("image,pan,tilt,focal,width,height\n"
                                   "wall.png,10,20,300,80,60\n")
    before = snapshot(tmp_path)
    result = run_gsrwt("render", "out/wall.png", "--sidecar", "out/views.csv", "-o", "out",
                       "--overwrite", cwd=tmp_path)
    assert result.returncode == 2
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert "would overwrite an input" in line
    assert snapshot(tmp_path) == before
    # The sidecar's own name as a row: it is where the views' sidecar goes, refused too.
    (tmp_path / "views.yaml").write_text("views.csv: {pan: 10, tilt: 20, focal: 300}\n")
    before = snapshot(tmp_path)
    result = run_gsrwt("render", "out/wall.png", "--sidecar", "views.yaml", "-o", "out",
                       "--overwrite", cwd=tmp_path)
    assert result.returncode == 1
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert line.startswith("Error: views.yaml record ")  # the rest of where is sidecar.py's
    assert line.endswith("field 'image': 'views.csv' is the same file as the views' sidecar; "
                         "give another name")
    assert snapshot(tmp_path) == before


def test_render_names_a_rows_problem_on_one_bounded_line(render_workspace):
    """A hostile name (newlines, 5000 characters) is quoted escaped and cut short."""
    workspace = render_workspace
    long_name = "../" + "x" * 5000 + ".png"
    (workspace / "views.yaml").write_text(yaml.safe_dump({
        "../new\nline.png": {"pan": 10, "tilt": 20, "focal": 300},
        long_name: {"pan": 10, "tilt": 20, "focal": 300},
        "new\nline.png": {"pan": 10, "tilt": 20, "focal": 300},
    }))
    before = snapshot(workspace)
    result = run_gsrwt("render", "wall.png", "--sidecar", "views.yaml", "-o", "out",
                       "--width", "80", "--height", "60", cwd=workspace)
    assert result.returncode == 1
    first, second = assert_clean_stderr(result.stderr, error_lines=2)
    assert "'../new\\nline.png' has a '..' part" in first
    assert "(5007 characters)" in second and len(second) < 500
    assert_nothing_changed_outside(before, snapshot(workspace), "out")
    # The good name with a newline is a correct result: the file and its sidecar row.
    assert cv2.imread(str(workspace / "out" / "new\nline.png")).shape == (60, 80, 3)
    rows = read_table(workspace / "out" / "views.csv")
    assert [row["image"] for row in rows] == ["new\nline.png"]


# --------------------------------------------------------------------------------------------
# lines / match --draw: pictures stay inside DIR
# --------------------------------------------------------------------------------------------


def draw_command(command: str, *images: str, draw: str = "drawn") -> list[str]:
    extra = ["--template", str(KNOB), "--min-score", "0.99"] if command == "match" else []
    return [command, *images, *extra, "--draw", draw]


@pytest.fixture
def draw_workspace(tmp_path: Path) -> Path:
    """Three images in x/, a photo outside DIR, and DIR holding links that lead out:
    ``drawn/a.png`` to the photo, ``drawn/b.png`` to a directory beside DIR."""
    (tmp_path / "x").mkdir()
    for name, view in (("a", "corridor_p0_t30"), ("b", "corridor_p15_t30"),
                       ("c", "corridor_p30_t15")):
        shutil.copy(VIEWS / f"{view}.png", tmp_path / "x" / f"{name}.png")
    (tmp_path / "photos").mkdir()
    shutil.copy(VIEWS / "corridor_p45_t30.png", tmp_path / "photos" / "IMG_0001.png")
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "drawn").mkdir()
    os.symlink("../photos/IMG_0001.png", tmp_path / "drawn" / "a.png")
    os.symlink("../elsewhere", tmp_path / "drawn" / "b.png")
    return tmp_path


@pytest.mark.parametrize("command", ["lines", "match"])
def test_draw_refuses_links_that_lead_out_of_the_directory(draw_workspace, command):
    workspace = draw_workspace
    photo = sha256(workspace / "photos" / "IMG_0001.png")
    before = snapshot(workspace)
    result = run_gsrwt(*draw_command(command, "x/a.png", "x/b.png", "x/c.png"), cwd=workspace)
    assert result.returncode == 1, result.stderr
    first, second = assert_clean_stderr(result.stderr, error_lines=2)
    assert first.startswith("Error: x/a.png: --draw: its picture drawn/a.png is a symbolic link")
    assert second.startswith("Error: x/b.png: --draw: its picture drawn/b.png is a symbolic link")
    after = snapshot(workspace)
    assert_nothing_changed_outside(before, after, "drawn")
    assert sha256(workspace / "photos" / "IMG_0001.png") == photo
    assert os.listdir(workspace / "elsewhere") == []
    assert after["drawn/a.png"] == before["drawn/a.png"]  # the links are left as they were
    assert after["drawn/b.png"] == before["drawn/b.png"]
    assert set(after) - set(before) == {"drawn/c.png"}
    assert cv2.imread(str(workspace / "drawn" / "c.png")).shape == (240, 320, 3)
    if command == "lines":  # what was found is still reported for every image
        assert {row["image"] for row in read_table(result.stdout)} == {
            "x/a.png", "x/b.png", "x/c.png"}


@pytest.mark.parametrize("command", ["lines", "match"])
def test_draw_into_a_directory_the_user_named_through_a_link(draw_workspace, command):
    """DIR itself named through a link: the user chose that directory, wherever it is."""
    workspace = draw_workspace
    os.symlink("../elsewhere", workspace / "drawn" / "sub")
    before = snapshot(workspace)
    result = run_gsrwt(*draw_command(command, "x/c.png", draw="drawn/sub/deeper"),
                       cwd=workspace)
    # The user named drawn/sub/deeper: a directory they chose, wherever the link leads.
    assert result.returncode == 0, result.stderr
    assert_clean_stderr(result.stderr, error_lines=0)
    assert (workspace / "elsewhere" / "deeper" / "c.png").is_file()
    assert [path for path in snapshot(workspace) if path.endswith(".part")] == []
    assert outside(snapshot(workspace), "elsewhere") == outside(before, "elsewhere")


@pytest.mark.parametrize("command", ["lines", "match"])
def test_draw_refuses_the_second_image_with_the_same_name(tmp_path, command):
    """x/door.png and y/door.png both draw to DIR/door.png: the second is an error, the
    first's picture stays (byte for byte what drawing it alone gives)."""
    for directory, view in (("x", "corridor_p0_t30"), ("y", "corridor_p30_t30")):
        (tmp_path / directory).mkdir()
        shutil.copy(VIEWS / f"{view}.png", tmp_path / directory / "door.png")
    inputs = {path: sha256(tmp_path / path) for path in ("x/door.png", "y/door.png")}
    result = run_gsrwt(*draw_command(command, "x/door.png", "y/door.png"), cwd=tmp_path)
    assert result.returncode == 1
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert line.startswith("Error: y/door.png: --draw: its picture drawn/door.png would "
                           "replace the picture of x/door.png")
    alone = run_gsrwt(*draw_command(command, "x/door.png", draw="alone"), cwd=tmp_path)
    assert alone.returncode == 0
    assert sha256(tmp_path / "drawn" / "door.png") == sha256(tmp_path / "alone" / "door.png")
    assert sorted(os.listdir(tmp_path / "drawn")) == ["door.png"]
    assert {path: sha256(tmp_path / path) for path in inputs} == inputs


def test_draw_never_overwrites_an_input(tmp_path):
    """DIR is the input directory (lines), or holds the template (match): refused per image."""
    (tmp_path / "x").mkdir()
    for view in ("corridor_p0_t30", "corridor_p15_t30"):
        shutil.copy(VIEWS / f"{view}.png", tmp_path / "x" / f"{view}.png")
    before = snapshot(tmp_path)
    result = run_gsrwt("lines", "x", "--draw", "x", cwd=tmp_path)
    assert result.returncode == 1
    lines = assert_clean_stderr(result.stderr, error_lines=2)
    assert all("would overwrite an input" in line for line in lines)
    assert snapshot(tmp_path) == before
    # The template's name is an image's: its picture would replace the template.
    (tmp_path / "t").mkdir()
    shutil.copy(KNOB, tmp_path / "t" / "corridor_p0_t30.png")
    before = snapshot(tmp_path)
    result = run_gsrwt("match", "x/corridor_p0_t30.png", "--template",
                       "t/corridor_p0_t30.png", "--draw", "t", cwd=tmp_path)
    assert result.returncode == 1
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert "would overwrite an input" in line
    assert snapshot(tmp_path) == before


# --------------------------------------------------------------------------------------------
# A file written at the end of the work (a table, a sidecar) that is a directory
# --------------------------------------------------------------------------------------------

DOOR = str(VIEWS / "door_p8_t-2_f1500.jpg")
DOOR_POSE = ("--pan", "8", "--tilt", "-2", "--focal", "1500")
#: Each command that writes a file when its work is done, with that file a directory
#: already: (the directory, the command, the directory that must hold no work after it).
DIRECTORY_TARGETS = {
    "rectify-default-table": ("out/gsrwt.csv", ["rectify", DOOR, *DOOR_POSE, "-o", "out"],
                              "out"),
    "rectify-table": ("t.json", ["rectify", DOOR, *DOOR_POSE, "-o", "out", "--table",
                                 "t.json"], "out"),
    "rectify-shard-table": ("out/gsrwt.1-of-2.csv", [
        "rectify", str(VIEWS), "--sidecar", str(VIEWS / "views.csv"), "-o", "out", "--shard",
        "1/2"], "out"),
    "estimate": ("e.csv", ["estimate", DOOR, "--focal", "1500", "-o", "e.csv", "--draw",
                           "out"], "out"),
    "render-sidecar": ("out/views.csv", ["render", str(ROOT / "sample_data" / "corridor_wall.png"),
                                         "--sidecar", str(VIEWS / "views.csv"), "-o", "out",
                                         "--overwrite"], "out"),
    "render-one-view-sidecar": ("out/v.yaml", [
        "render", str(ROOT / "sample_data" / "corridor_wall.png"), *DOOR_POSE, "--width",
        "64", "--height", "48", "-o", "out/v.png", "--overwrite"], "out"),
    "tables-merge": ("m.csv", ["tables", "merge", "a.csv", "-o", "m.csv"], "out"),
}


@pytest.mark.parametrize("case", sorted(DIRECTORY_TARGETS))
def test_a_table_that_is_a_directory_is_refused_before_any_work(tmp_path, case):
    """A table, shard table or sidecar to be written at the end whose name is a directory:
    one line naming it, exit 2, and no work done (no image written, nothing drawn)."""
    directory, args, work = DIRECTORY_TARGETS[case]
    (tmp_path / "a.csv").write_text("image,status\nx.jpg,ok\n")
    (tmp_path / directory).mkdir(parents=True)
    result = run_gsrwt(*args, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert f"{directory}: is a directory" in line, line
    left = sorted(str(path.relative_to(tmp_path)) for path in (tmp_path / work).rglob("*"))
    assert left == ([directory] if directory.startswith(f"{work}/") else []), left


# --------------------------------------------------------------------------------------------
# A reader that closes the pipe
# --------------------------------------------------------------------------------------------


def read_one_line_and_close(args: list[str], cwd: Path, timeout: float = 120
                            ) -> tuple[bytes, int, bytes]:
    """Run ``gsrwt ARGS | head -1`` as a real pipeline: the first line, status and stderr."""
    process = start_gsrwt(*args, cwd=cwd, text=False)
    first = process.stdout.readline()
    process.stdout.close()
    stderr = process.stderr.read()
    return first, process.wait(timeout=timeout), stderr


def close_before_any_output(args: list[str], cwd: Path, timeout: float = 120
                            ) -> tuple[int, bytes]:
    """Run ``gsrwt ARGS | true``: the reader is gone before the first byte is written."""
    process = start_gsrwt(*args, cwd=cwd, text=False)
    process.stdout.close()
    stderr = process.stderr.read()
    return process.wait(timeout=timeout), stderr


def test_params_of_a_big_sidecar_ends_quietly_when_the_reader_leaves(tmp_path):
    rows = "".join(f"img{n:05d}.png,{n % 80 - 40},{n % 60 - 30},{300 + n % 500},640,480\n"
                   for n in range(20_000))
    (tmp_path / "big.csv").write_text("image,pan,tilt,focal,width,height\n" + rows)
    first, status, stderr = read_one_line_and_close(["params", "--sidecar", "big.csv"],
                                                    tmp_path)
    assert first.startswith(b"image,pan_deg,tilt_deg,")
    assert status == CLOSED_PIPE_STATUS
    assert stderr == b""


def test_lines_on_many_images_ends_quietly_when_the_reader_leaves(tmp_path):
    # jsonl rows of 40 images: far more than a pipe (64 KiB) and stdout's buffer hold, so
    # the command is still writing when the reader leaves.
    for n in range(40):
        shutil.copy(VIEWS / "corridor_p30_t15.png", tmp_path / f"view{n:02d}.png")
    first, status, stderr = read_one_line_and_close(
        ["lines", ".", "--format", "jsonl", "--min-votes", "20"], tmp_path)
    assert first.startswith(b'{"image": ')
    assert status == CLOSED_PIPE_STATUS
    assert stderr == b""


@pytest.mark.parametrize("args", [
    ["params", "--pan", "15", "--tilt", "30", "--focal", "280"],
    ["lines", str(VIEWS / "corridor_p30_t15.png")],
    ["gaze", "--pan", "15", "--tilt", "30", "--focal", "280"],
    ["track", "--distance", "25", "--object", "33", "--positions", "0,12,18"],
    ["--help"],
    ["render", "--help"],
], ids=lambda args: " ".join(args[:2]).replace("/", "_")[:30])
def test_any_command_ends_quietly_when_stdout_is_closed_before_it_writes(tmp_path, args):
    """The whole output fits in stdout's buffer: the pipe breaks at the final flush."""
    status, stderr = close_before_any_output(args, tmp_path)
    assert status == CLOSED_PIPE_STATUS
    assert stderr == b""


def test_rectify_table_on_stdout_ends_quietly_and_leaves_no_temporaries(tmp_path):
    status, stderr = close_before_any_output(
        ["rectify", str(VIEWS), "--sidecar", str(VIEWS / "views.csv"), "--table", "-",
         "-o", "out", "-j", "2", "-q"], tmp_path)
    assert status == CLOSED_PIPE_STATUS
    assert stderr == b""
    assert [path for path in snapshot(tmp_path) if path.endswith(".part")] == []


# --------------------------------------------------------------------------------------------
# File names with a newline, and with bytes that are not UTF-8
# --------------------------------------------------------------------------------------------

NEWLINE_NAME = "new\nline.png"


@pytest.mark.parametrize("command", ["lines", "match"])
def test_a_name_with_a_newline_is_a_correct_result(tmp_path, command):
    shutil.copy(VIEWS / "corridor_p0_t30.png", tmp_path / NEWLINE_NAME)
    extra = ["--template", str(KNOB), "--min-score", "0.1"] if command == "match" else []
    result = run_gsrwt(command, NEWLINE_NAME, *extra, "--draw", "drawn", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert_clean_stderr(result.stderr, error_lines=0)
    rows = read_table(result.stdout)
    assert rows and {row["image"] for row in rows} == {NEWLINE_NAME}
    assert cv2.imread(str(tmp_path / "drawn" / NEWLINE_NAME)).shape == (240, 320, 3)


@pytest.mark.parametrize("command", ["lines", "match", "render"])
def test_a_missing_name_with_a_newline_is_one_line(tmp_path, command):
    shutil.copy(KNOB, tmp_path / "knob.png")
    args = {"lines": ["lines", "gone\nname.png"],
            "match": ["match", "gone\nname.png", "--template", "knob.png"],
            "render": ["render", "gone\nname.png", "--pan", "1", "--tilt", "1", "--focal",
                       "300", "-o", "out.png"]}[command]
    result = run_gsrwt(*args, cwd=tmp_path)
    assert result.returncode == 2
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert line.startswith("Error: gone\\nname.png: ")


@pytest.mark.parametrize("command", ["lines", "match"])
def test_an_unreadable_file_with_a_newline_is_one_line(tmp_path, command):
    (tmp_path / "text\nfile.png").write_text("not an image\n")
    shutil.copy(VIEWS / "corridor_p0_t30.png", tmp_path / "good.png")
    extra = ["--template", str(KNOB)] if command == "match" else []
    result = run_gsrwt(command, "text\nfile.png", "good.png", *extra, cwd=tmp_path)
    assert result.returncode == 1
    (line,) = assert_clean_stderr(result.stderr, error_lines=1)
    assert line.startswith("Error: text\\nfile.png: ")


NOT_UTF8 = os.fsdecode(b"bad\xff.png")


@pytest.mark.parametrize("command", ["lines", "match"])
def test_a_name_that_is_not_utf8_is_a_correct_result(tmp_path, command):
    """The table names the file by its very bytes; the picture gets its very name."""
    shutil.copy(VIEWS / "corridor_p0_t30.png", tmp_path / NOT_UTF8)
    extra = ["--template", str(KNOB), "--min-score", "0.1"] if command == "match" else []
    result = run_gsrwt(command, NOT_UTF8, *extra, "--draw", "drawn", cwd=tmp_path, text=False)
    assert result.returncode == 0, result.stderr
    assert_clean_stderr(result.stderr.decode("utf-8", "backslashreplace"), error_lines=0)
    rows = result.stdout.splitlines()[1:]
    assert rows and all(row.startswith(b"bad\xff.png,") for row in rows)
    assert (tmp_path / "drawn" / NOT_UTF8).is_file()


@pytest.mark.parametrize("command", ["lines", "match"])
def test_an_unreadable_file_that_is_not_utf8_is_one_line(tmp_path, command):
    (tmp_path / NOT_UTF8).write_bytes(b"not an image\n")
    extra = ["--template", str(KNOB)] if command == "match" else []
    result = run_gsrwt(command, NOT_UTF8, *extra, cwd=tmp_path, text=False)
    assert result.returncode == 1
    stderr = result.stderr.decode("utf-8", "backslashreplace")
    (line,) = assert_clean_stderr(stderr, error_lines=1)
    assert line.startswith("Error: bad")


def test_render_to_and_from_names_that_are_not_utf8(tmp_path):
    """A texture and an output named with a byte that is not UTF-8: rendered, and the sidecar
    written beside it names the output so that rectify finds its parameters."""
    cv2.imwrite(str(tmp_path / "wall.png"), smooth_texture(90, 120, seed=3))
    os.rename(tmp_path / "wall.png", tmp_path / NOT_UTF8)
    output = os.fsdecode(b"view\xfe.png")
    result = run_gsrwt("render", NOT_UTF8, "--pan", "10", "--tilt", "20", "--focal", "300",
                       "--width", "80", "--height", "60", "-o", output, cwd=tmp_path, text=False)
    assert result.returncode == 0, result.stderr
    assert result.stderr == b""
    image = cv2.imdecode(np.fromfile(tmp_path / output, np.uint8), cv2.IMREAD_UNCHANGED)
    assert image.shape == (60, 80, 3)
    record = yaml.safe_load((tmp_path / os.fsdecode(b"view\xfe.yaml")).read_text())
    assert list(record) == [output] and record[output]["focal"] == 300.0


def test_internal_error_message_is_one_bounded_line():
    """The group's last-resort message: one line, the exception's text cut short."""
    from gsrwt_cli.cli import internal_error_message

    message = internal_error_message(RuntimeError("first\nsecond " + "x" * 10_000))
    assert "\n" not in message and len(message) < 500
    assert message.startswith("internal error: RuntimeError: first\\nsecond xxx")
    assert message.endswith("(rerun with --debug for details)")
