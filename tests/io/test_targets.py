"""Which files a command may write (``io/targets.py``): one identity of a file for every
command's refusal to write over an input, through symbolic links too; names from user data
kept inside the output; one picture per name. Real files and links in ``tmp_path``."""

from __future__ import annotations

from pathlib import Path

import pytest

from gsrwt_cli.io.outputs import OutsideOutputError
from gsrwt_cli.io.storage import Location
from gsrwt_cli.io.targets import (
    DirectoryTargetError,
    Drawings,
    ExistingOutputError,
    InputOverwriteError,
    NotADirectoryTargetError,
    TargetError,
    UncreatableDirectoryError,
    check_new_files,
    file_identity,
    make_output_directory,
    output_target,
    protected_files,
)


@pytest.fixture
def photo(tmp_path: Path) -> Path:
    (tmp_path / "in").mkdir()
    path = tmp_path / "in" / "photo.jpg"
    path.write_bytes(b"the user's photo")
    return path


def test_one_file_has_one_identity_whatever_the_name(tmp_path, photo, monkeypatch):
    """A file named relatively, absolutely, through ``..``, through a link to it or to its
    directory is one identity; a hard link is a name of its own (its own path); a URL is
    itself, nothing resolved."""
    (tmp_path / "link.jpg").symlink_to(photo)
    (tmp_path / "dirlink").symlink_to(photo.parent)
    monkeypatch.chdir(tmp_path)
    names = [photo, Path("in/photo.jpg"), tmp_path / "in" / ".." / "in" / "photo.jpg",
             Path("link.jpg"), tmp_path / "dirlink" / "photo.jpg"]
    assert {file_identity(name) for name in names} == {str(photo.resolve())}
    assert file_identity(tmp_path / "other.jpg") != file_identity(photo)
    url = "s3://bucket/in/../in/photo.jpg"
    assert file_identity(Location(url)) == url
    assert protected_files([photo, None, Path("link.jpg"), Location(url)]) == {
        str(photo.resolve()), url}


def test_an_input_is_never_overwritten_through_any_of_its_names(tmp_path, photo):
    """``check_new_files`` refuses a target that is an input: by its path, through a link
    to it, through a linked directory, even with ``overwrite``; an input given through a
    link protects the file it names."""
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "photo.jpg").symlink_to(photo)
    (tmp_path / "indir").symlink_to(photo.parent)
    for target in (photo, tmp_path / "out" / "photo.jpg", tmp_path / "indir" / "photo.jpg"):
        for overwrite in (False, True):
            with pytest.raises(InputOverwriteError) as refused:
                check_new_files([target], [photo], overwrite)
            assert refused.value.path == target and "--" not in str(refused.value)
    with pytest.raises(InputOverwriteError):
        check_new_files([photo], [tmp_path / "out" / "photo.jpg"], overwrite=True)
    assert photo.read_bytes() == b"the user's photo"


def test_an_existing_file_needs_overwrite_and_a_directory_is_never_replaced(tmp_path, photo):
    existing = tmp_path / "old.png"
    existing.write_bytes(b"x")
    (tmp_path / "folder.png").mkdir()
    with pytest.raises(ExistingOutputError):
        check_new_files([tmp_path / "new.png", existing], [photo], overwrite=False)
    check_new_files([tmp_path / "new.png", existing], [photo], overwrite=True)
    with pytest.raises(DirectoryTargetError):
        check_new_files([tmp_path / "folder.png"], [photo], overwrite=True)
    # The first target in order that is refused is the one named.
    with pytest.raises(InputOverwriteError):
        check_new_files([photo, existing], [photo], overwrite=False)
    dangling = tmp_path / "dangling.png"
    dangling.symlink_to(tmp_path / "nowhere.png")
    with pytest.raises(ExistingOutputError):  # a link that leads nowhere still exists
        check_new_files([dangling], [photo], overwrite=False)


def test_names_from_user_data_stay_inside_the_output(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "away").symlink_to(elsewhere)
    (out / "leak.png").symlink_to(elsewhere / "secret.png")
    (out / "fine.png").symlink_to(out / "target.png")
    assert output_target(out, "a.png") == out / "a.png"
    assert output_target(out, "fine.png") == out / "fine.png"
    assert output_target(tmp_path / "missing", "a.png") == tmp_path / "missing" / "a.png"
    with pytest.raises(OutsideOutputError, match="outside the output"):
        output_target(out, "away/a.png")
    with pytest.raises(OutsideOutputError, match="symbolic link to"):
        output_target(out, "leak.png")


def test_pictures_are_one_per_name_never_over_an_input_never_outside(tmp_path, photo):
    drawn = tmp_path / "drawn"
    drawn.mkdir()
    drawings = Drawings(drawn, [photo, tmp_path / "drawn" / "template.png"])
    first = drawings.target(tmp_path / "a" / "door.jpg")
    assert first == drawn / "door.png"
    with pytest.raises(ValueError, match="would replace the picture of"):
        drawings.target(tmp_path / "b" / "door.png")
    with pytest.raises(ValueError, match="would overwrite an input"):
        drawings.target(tmp_path / "x" / "template.jpg")
    (drawn / "leak.png").symlink_to(tmp_path / "outside.png")
    with pytest.raises(ValueError, match="outside the output"):
        drawings.target(tmp_path / "leak.jpg")
    drawings.save(first, b"\x89PNG...")
    assert first.read_bytes() == b"\x89PNG..."


def test_the_output_directory_is_made_or_refused_naming_it(tmp_path):
    made = tmp_path / "a" / "b"
    make_output_directory(made)
    assert made.is_dir()
    stale = made / f".x.png.gsrwt-{2**22 + 1}-ab.part"  # above Linux's largest pid, 2^22
    stale.write_bytes(b"")
    make_output_directory(made)
    assert not stale.exists()  # what a killed run left is cleaned away
    (tmp_path / "file").write_text("not a directory")
    with pytest.raises(NotADirectoryTargetError) as not_directory:
        make_output_directory(tmp_path / "file")
    with pytest.raises(UncreatableDirectoryError) as uncreatable:
        make_output_directory(tmp_path / "file" / "sub")
    for error in (not_directory.value, uncreatable.value):
        assert isinstance(error, TargetError) and str(error).startswith(str(error.path))
    assert "Not a directory" in uncreatable.value.reason
