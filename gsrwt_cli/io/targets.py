"""Which files a command may write: inside the output the user named, over no input.

:mod:`.outputs` writes a file whole and refuses a write that would leave the output; this
module decides, before anything is written, where each file goes and whether it may: a name
taken from user data stays inside the output (:func:`output_target`), an input is never
overwritten and an existing file only when asked (:func:`check_new_files`), two results never
share one file (:class:`Drawings`). Refusals are :class:`TargetError` carrying the path, for
the command to word in terms of its options.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path, PurePosixPath

from .outputs import (
    OutsideOutputError,
    check_inside,
    remove_stale_temporaries,
    write_atomic,
)
from .storage import Location


class TargetError(ValueError):
    """A file or directory a command would write cannot be written; ``path`` names it, and
    ``reason`` says why (the class's own reason unless given: the system's words)."""

    default_reason = "cannot be written"

    def __init__(self, path: Path, reason: str | None = None) -> None:
        self.path, self.reason = path, reason or self.default_reason
        super().__init__(f"{path}: {self.reason}")


class ExistingOutputError(TargetError):
    """The output exists, and replacing it was not asked for."""

    default_reason = "exists"


class InputOverwriteError(TargetError):
    """The output is one of the command's inputs."""

    default_reason = "would overwrite an input"


class NotADirectoryTargetError(TargetError):
    """An output directory exists and is not a directory."""

    default_reason = "exists and is not a directory"


class DirectoryTargetError(TargetError):
    """An output file is a directory."""

    default_reason = "is a directory"


class UncreatableDirectoryError(TargetError):
    """An output directory cannot be created; ``reason`` says why (the system's words)."""


class UnwritableFileError(TargetError):
    """An output file cannot be written; ``reason`` says why (the system's words)."""


def is_inside(real_root: str, real_path: str) -> bool:
    """Whether the real path ``real_path`` is ``real_root`` or lies below it."""
    return real_path == real_root or real_path.startswith(real_root.rstrip(os.sep) + os.sep)


def output_target(root: Path, relative: PurePosixPath | str) -> Path:
    """``root / relative``, a file a command may write, checked against the output rule.

    ``relative`` must already be a checked relative name
    (:func:`~gsrwt_cli.io.outputs.relative_output`, or a plain file name). Raises
    :class:`~gsrwt_cli.io.outputs.OutsideOutputError` when writing there would leave ``root``:
    a directory on the way is a symbolic link leading out of it, or the file itself is a
    symbolic link to a file outside it (which we refuse rather than silently replace the link).
    ``root`` should exist: nothing inside a missing directory can be a link.
    """
    target = root / relative
    if not os.path.lexists(root):
        return target
    check_inside(root, target)
    if os.path.islink(target):
        pointed_to = os.path.realpath(target)
        if not is_inside(os.path.realpath(root), pointed_to):
            raise OutsideOutputError(
                f"is a symbolic link to {pointed_to}, outside the output {root}"
            )
    return target


def file_identity(path: Path | Location) -> str:
    """What a name stands for, to tell whether two names are one file: a URL as it is, a
    local path with its links resolved (the one comparison every command's refusal to write
    over an input makes)."""
    return str(path) if isinstance(path, Location) else os.path.realpath(path)


def protected_files(paths: Iterable[Path | Location | None]) -> set[str]:
    """The :func:`file_identity` of every file a command was given (inputs, sidecars):
    what it must never write over."""
    return {file_identity(path) for path in paths if path is not None}


def check_new_files(targets: Iterable[Path], inputs: Iterable[Path | Location],
                    overwrite: bool) -> None:
    """Raise, for the first target in order that is one: :class:`InputOverwriteError` if
    it is one of ``inputs``, :class:`DirectoryTargetError` if it is a directory (no file can
    replace it), :class:`ExistingOutputError` if it exists (unless ``overwrite``)."""
    protected = protected_files(inputs)
    for target in targets:
        if file_identity(target) in protected:
            raise InputOverwriteError(target)
        if os.path.isdir(target):
            raise DirectoryTargetError(target)
        if os.path.lexists(target) and not overwrite:
            raise ExistingOutputError(target)


def make_output_directory(directory: Path) -> None:
    """Create the output directory (and its parents), or raise :class:`TargetError`."""
    if directory.exists() and not directory.is_dir():
        raise NotADirectoryTargetError(directory)
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UncreatableDirectoryError(directory, str(error.strerror or error)) from None
    remove_stale_temporaries(directory)  # what a killed earlier run left half-written


class Drawings:
    """Where the pictures of what was found go: ``DIR/STEM.png`` for an image, inside DIR.

    A picture is refused (an error for that image, the others still drawn) when its file
    would lie outside DIR (a symbolic link in DIR leading out), would replace an input
    (an image, a template, the sidecar), or would replace the picture of an earlier image of
    the same run: ``a/door.jpg`` and ``b/door.png`` both draw to ``DIR/door.png``, and the
    second is refused rather than silently given another name or drawn over the first.
    """

    def __init__(self, directory: Path, inputs: Iterable[Path | Location]) -> None:
        self.directory = directory
        self.protected = protected_files(inputs)
        self.drawn: dict[str, Path] = {}  # real path of a picture -> the image it shows

    def target(self, image: Path | Location) -> Path:
        """The picture's file for ``image``, or :class:`ValueError` saying why there is none."""
        target = self.directory / (image.stem + ".png")
        try:
            output_target(self.directory, target.name)
        except OutsideOutputError as error:
            raise ValueError(f"its picture {target} {error}") from None
        real = file_identity(target)
        if real in self.protected:
            raise ValueError(f"its picture {target} would overwrite an input")
        if real in self.drawn:
            raise ValueError(f"its picture {target} would replace the picture of "
                             f"{self.drawn[real]} (same name); draw them in separate runs")
        self.drawn[real] = image
        return target

    def save(self, target: Path, png: bytes) -> None:
        """Write a picture's PNG bytes whole, inside the directory (or raise OSError,
        ValueError)."""
        write_atomic(target, png, root=self.directory)
