"""Which files are the inputs (``inputs/sources.py``): real directory trees with hidden
files, links and other files beside the images; paths as read from standard input; a URL
prefix on fsspec's in-memory store."""

from __future__ import annotations

from pathlib import Path, PurePosixPath

import pytest

from gsrwt_cli.inputs.sources import (
    Source,
    is_image_name,
    source_from_listed_path,
    sources_from_directory,
    sources_from_location,
)


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    """``in/`` with images at two depths, in a mixed order of creation, beside a hidden file,
    a hidden directory, a text file, an image with an upper-case suffix and a link to a
    directory outside."""
    root = tmp_path / "in"
    for name in ("b.png", "a.JPG", "notes.txt", ".hidden.png", "sub/z.tif", "sub/deep/c.webp",
                 ".cache/x.png", "sub/readme.md"):
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"")
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "o.png").write_bytes(b"")
    (root / "linked").symlink_to(tmp_path / "outside")
    return root


def relatives(sources: list[Source]) -> list[str]:
    return [str(source.relative) for source in sources]


def test_a_directory_gives_its_own_images_sorted(tree):
    sources = sources_from_directory(tree, recursive=False)
    assert relatives(sources) == ["a.JPG", "b.png"]
    assert [source.path for source in sources] == [tree / "a.JPG", tree / "b.png"]


def test_many_images_come_in_name_order_whatever_the_directorys_order(tmp_path):
    names = [f"{index * 7919 % 100:02d}.png" for index in range(40)]  # created out of order
    for name in names:
        (tmp_path / name).write_bytes(b"")
    assert relatives(sources_from_directory(tmp_path, recursive=False)) == sorted(names)
    assert relatives(sources_from_directory(tmp_path, recursive=True)) == sorted(names)


def test_recursive_keeps_each_images_tree_and_follows_no_link(tree):
    """Sorted as a walk gives them (each directory's files, then its subdirectories), hidden
    files and directories left out, the linked directory not entered."""
    sources = sources_from_directory(tree, recursive=True)
    assert relatives(sources) == ["a.JPG", "b.png", "sub/z.tif", "sub/deep/c.webp"]
    assert all(source.path == tree / source.relative for source in sources)


def test_a_directory_that_cannot_be_listed_is_an_error(tmp_path):
    with pytest.raises(OSError):
        sources_from_directory(tmp_path / "missing", recursive=False)
    with pytest.raises(OSError):
        sources_from_directory(tmp_path / "missing", recursive=True)


@pytest.mark.parametrize(("text", "relative"), [
    ("a/b.jpg", "a/b.jpg"), ("./a/./b.jpg", "a/b.jpg"), ("b.jpg", "b.jpg"),
    ("/abs/dir/b.jpg", "b.jpg"), ("../up/b.jpg", "b.jpg"), ("a/../b.jpg", "b.jpg"),
])
def test_a_listed_path_keeps_its_tree_unless_it_leaves_the_working_directory(text, relative):
    """Read from standard input: a relative path keeps its tree under the output; an absolute
    one, or one with ``..``, only its name (its tree could lead anywhere)."""
    source = source_from_listed_path(text)
    assert source.path == Path(text) and source.relative == PurePosixPath(relative)


def test_only_image_suffixes_and_no_hidden_names_are_images():
    assert [is_image_name(Path(name)) for name in
            ("a.png", "a.JPEG", "a.tiff", "a.txt", ".a.png", "a.png.part", "a")] == [
        True, True, True, False, False, False, False]


def test_a_url_prefix_gives_its_images_relative_to_it_in_one_listing():
    """On fsspec's in-memory store: the prefix's own level, or its whole tree, hidden names
    left out, and keys no path can name (``//``, ``.``) reported, never listed."""
    fsspec = pytest.importorskip("fsspec")
    from gsrwt_cli.io.storage import Location

    store = fsspec.filesystem("memory")
    for key in ("src/in/b.png", "src/in/a.jpg", "src/in/notes.txt", "src/in/.h.png",
                "src/in/sub/c.png", "src/in//odd.png", "src/in/./dot.png", "src/in/x/../up.png"):
        store.pipe_file(f"memory://{key}", b"x")
    try:
        prefix = Location("memory://src/in/")
        assert relatives(sources_from_location(prefix, recursive=False)) == ["a.jpg", "b.png"]
        unreadable: list[str] = []
        found = sources_from_location(prefix, recursive=True, unreadable=unreadable)
        assert relatives(found) == ["a.jpg", "b.png", "sub/c.png"]
        assert [str(source.path) for source in found] == [
            "memory://src/in/a.jpg", "memory://src/in/b.png", "memory://src/in/sub/c.png"]
        assert sorted(problem.partition(": ")[0] for problem in unreadable) == [
            "memory://src/in/./dot.png", "memory://src/in//odd.png",
            "memory://src/in/x/../up.png"]
        assert all(problem.endswith("which names no output file; rename the object")
                   for problem in unreadable)
    finally:
        store.rm("memory://src", recursive=True)
