"""Which files are the inputs: images in directories (sorted, optionally recursive) and paths
read from standard input, each with the relative path its output keeps."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from ..base.messages import one_line
from ..imaging.images import IMAGE_EXTENSIONS
from ..io.storage import Location, list_files


@dataclass(frozen=True)
class Source:
    """An input image and the relative path its output keeps."""

    path: Path | Location  # a local path, or a URL (:mod:`~gsrwt_cli.io.storage`)
    relative: PurePosixPath


def is_image_name(path: Path | Location) -> bool:
    return path.suffix.lower() in IMAGE_EXTENSIONS and not path.name.startswith(".")


def sources_from_directory(
    directory: Path, recursive: bool, unreadable: list[str] | None = None
) -> list[Source]:
    """Images in a directory (sorted), with paths relative to it; hidden files are skipped.

    Symbolic links to directories are not followed. A subdirectory that cannot be listed is
    reported in ``unreadable`` (``"DIR: cannot read directory (reason)"``); if the directory
    itself cannot be listed, ``OSError`` is raised.
    """
    if recursive:
        found = []
        problems: list[OSError] = []
        for root, dirs, files in os.walk(directory, onerror=problems.append):
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            found += [Path(root) / name for name in sorted(files)]
        for problem in problems:
            if os.path.abspath(problem.filename or "") == os.path.abspath(directory):
                raise problem
            if unreadable is not None:
                unreadable.append(
                    f"{problem.filename}: cannot read directory ({problem.strerror})"
                )
    else:
        found = sorted(p for p in directory.iterdir() if p.is_file())
    return [
        Source(p, PurePosixPath(p.relative_to(directory).as_posix()))
        for p in found
        if is_image_name(p)
    ]


def source_from_listed_path(text: str) -> Source:
    """A path read from standard input: relative paths keep their tree, others their name."""
    path = Path(text)
    pure = PurePosixPath(path.as_posix())
    if path.is_absolute() or ".." in pure.parts:
        return Source(path, PurePosixPath(path.name))
    return Source(path, PurePosixPath(*[part for part in pure.parts if part != "."]))


def sources_from_location(prefix: Location, recursive: bool,
                          unreadable: list[str] | None = None) -> list[Source]:
    """Images below a URL prefix (sorted; its own level unless ``recursive``), with paths
    relative to it, hidden names skipped: one listing of the store
    (:func:`~gsrwt_cli.io.storage.list_files`). An image whose key has an empty, ``.`` or
    ``..`` part (no path can name its output) is reported in ``unreadable``."""
    unusable: list[str] = []
    sources = [Source(item, relative) for item, relative in list_files(prefix, recursive,
                                                                        unusable)
               if is_image_name(item)]
    if unreadable is not None:
        unreadable += [
            f"{one_line(url, 300)}: its key has an empty, '.' or '..' part, which names no "
            "output file; rename the object" for url in unusable
            if PurePosixPath(url).suffix.lower() in IMAGE_EXTENSIONS]
    return sources
