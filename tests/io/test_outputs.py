"""Files that appear whole, only inside the output named (``io/outputs.py``): real files,
real symbolic links, a real dead process's id."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import PurePosixPath

import pytest

from gsrwt_cli.io.outputs import (
    TEMPORARY_PATTERN,
    OutsideOutputError,
    check_inside,
    current_umask,
    open_atomic,
    relative_output,
    remove_stale_temporaries,
    temporary_target,
    write_atomic,
)


def dead_pid() -> int:
    """The id of a process that has ended (and been waited for)."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


@pytest.mark.parametrize(("name", "kept"), [
    ("a.png", "a.png"), ("sub/dir/a.png", "sub/dir/a.png"), ("./a/./b.png", "a/b.png"),
    ("sub\\win.png", "sub/win.png"), ("spaces and ü.png", "spaces and ü.png"),
])
def test_a_relative_name_from_user_data_is_kept_as_a_clean_relative_path(name, kept):
    assert relative_output(name) == PurePosixPath(kept)


@pytest.mark.parametrize(("name", "why"), [
    ("/etc/passwd", "absolute"), ("C:/x.png", "absolute"), ("c:x.png", "absolute"),
    ("../x.png", "'..'"), ("a/../../x.png", "'..'"), ("a\\..\\x.png", "'..'"),
    ("", "usable"), ("   ", "usable"), (".", "usable"), ("a\x00b.png", "usable"),
])
def test_a_name_that_could_point_anywhere_is_refused(name, why):
    with pytest.raises(OutsideOutputError, match=why):
        relative_output(name)


def test_a_target_is_inside_only_if_its_real_directory_is(tmp_path):
    """Links are resolved: a directory link inside the output that leads out is outside, one
    that stays in is inside; a sibling whose name starts like the output's is outside; the
    target itself may be a link (it is replaced, not followed)."""
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "sub").mkdir()
    (out / "away").symlink_to(elsewhere)
    (out / "stay").symlink_to(out / "sub")
    (out / "link.png").symlink_to(elsewhere / "x.png")
    check_inside(out, out / "a.png")
    check_inside(out, out / "new" / "deeper" / "a.png")  # not made yet: taken as given
    check_inside(out, out / "stay" / "a.png")
    check_inside(out, out / "link.png")
    for target in (out / "away" / "a.png", tmp_path / "out-b" / "a.png", tmp_path / "a.png",
                   out / ".." / "a.png"):
        with pytest.raises(OutsideOutputError, match="outside the output"):
            check_inside(out, target)


def test_a_file_appears_whole_under_a_recognisable_temporary_name(tmp_path):
    target = tmp_path / "sub" / "table.csv"
    with open_atomic(target, "w", root=tmp_path) as stream:
        stream.write("image\n")
        stream.flush()
        assert not target.exists()  # nobody sees it half-written
        (temporary,) = (tmp_path / "sub").iterdir()
        match = TEMPORARY_PATTERN.match(temporary.name)
        assert match and int(match.group(1)) == os.getpid()
        assert temporary_target(temporary.name) == "table.csv"
    assert target.read_text() == "image\n"
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["table.csv"]
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~current_umask()


def test_a_failed_write_leaves_the_old_file_and_nothing_else(tmp_path):
    target = tmp_path / "a.png"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError), open_atomic(target) as stream:
        stream.write(b"new, partial")
        raise RuntimeError("the encoder failed")
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"]


def test_writing_over_a_link_replaces_the_link_not_what_it_points_to(tmp_path):
    elsewhere = tmp_path / "elsewhere.png"
    elsewhere.write_bytes(b"someone else's")
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.png").symlink_to(elsewhere)
    write_atomic(out / "a.png", b"ours", root=out)
    assert not (out / "a.png").is_symlink() and (out / "a.png").read_bytes() == b"ours"
    assert elsewhere.read_bytes() == b"someone else's"


def test_a_write_outside_the_root_is_refused_before_any_directory_is_made(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "away").symlink_to(tmp_path)
    with pytest.raises(OutsideOutputError):
        write_atomic(out / "away" / "new" / "a.png", b"x", root=out)
    assert not (tmp_path / "new").exists()


def test_stale_temporaries_of_dead_processes_go_and_live_ones_stay(tmp_path):
    dead, alive = dead_pid(), os.getpid()
    names = {
        "stale": f".a.png.gsrwt-{dead}-x1y2.part", "live": f".b.png.gsrwt-{alive}-z3.part",
        "other": f".c.png.gsrwt-{dead}-q9.part", "not ours": f".d.png.other-{dead}-q9.part",
        "plain": "e.png",
    }
    for name in names.values():
        (tmp_path / name).write_bytes(b"")
    removed = remove_stale_temporaries(tmp_path, names={"a.png"})
    assert [p.name for p in removed] == [names["stale"]]
    removed = remove_stale_temporaries(tmp_path)
    assert [p.name for p in removed] == [names["other"]]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [names["live"], names["not ours"], names["plain"]])
    # Known dead (a worker that was killed): removed even if the id is alive.
    assert [p.name for p in remove_stale_temporaries(tmp_path, pids={alive})] == [names["live"]]
    assert remove_stale_temporaries(tmp_path / "missing") == []


def test_the_umask_is_read_without_changing_it():
    before = os.umask(0o027)
    try:
        assert current_umask() == 0o027
        assert current_umask() == 0o027
    finally:
        os.umask(before)
