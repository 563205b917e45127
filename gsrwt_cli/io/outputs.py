"""Where gsrwt writes: files that appear whole, only inside the output the user named.

Every file any command writes (images, sidecars, tables, drawings) goes through
:func:`open_atomic`: a temporary file in the target's directory, renamed over the target when
complete, so no reader ever sees a partial file. Temporary names carry the writer's process id
(``.NAME.gsrwt-PID-XXXX.part``), so that a later run can remove those whose process is gone
(:func:`remove_stale_temporaries`). On an object store (a
:class:`~gsrwt_cli.io.storage.Location`) there is no rename: the data is sent in one request
when complete, so no partial object exists either. Given the output ``root``, a write whose
real location
(symbolic links resolved) is not inside the root's real location is refused with
:class:`OutsideOutputError`, before any directory is created.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path, PurePosixPath
from typing import IO, Any

from .storage import Location

#: Temporary files of ours: ``.NAME.gsrwt-PID-RANDOM.part``.
TEMPORARY_PATTERN = re.compile(r"^\..*\.gsrwt-(\d+)-[A-Za-z0-9_]+\.part$")


class OutsideOutputError(ValueError):
    """A file would be written outside the output the user named (``..``, absolute, symlink)."""


def current_umask() -> int:
    """The process's umask: from ``/proc/self/status`` where Linux gives it (reading it
    there changes nothing, so threads creating files meanwhile are unaffected), else by
    setting and restoring it."""
    with contextlib.suppress(OSError, ValueError), open("/proc/self/status") as status:
        for line in status:
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def relative_output(name: str) -> PurePosixPath:
    """A relative path taken from user data (a sidecar's ``image`` column), checked.

    Raises :class:`OutsideOutputError` for an absolute path, a ``..`` part, an empty name or
    one with a NUL byte: such a name could point anywhere.
    """
    text = str(name).replace("\\", "/")
    pure = PurePosixPath(text)
    if "\x00" in text or not text.strip():
        raise OutsideOutputError("not a usable file name")
    if pure.is_absolute() or re.match(r"^[A-Za-z]:", text):
        raise OutsideOutputError("is an absolute path; give a path relative to the output")
    if ".." in pure.parts:
        raise OutsideOutputError("has a '..' part, which would leave the output")
    parts = [part for part in pure.parts if part != "."]
    if not parts:
        raise OutsideOutputError("not a usable file name")
    return PurePosixPath(*parts)


def check_inside(root: str | Path | Location, target: str | Path | Location) -> None:
    """Raise :class:`OutsideOutputError` unless ``target``'s directory lies inside ``root``.

    ``target``'s directory is resolved (symbolic links followed, as far as it exists) and
    must be ``root``'s real path or below it. The target itself may be a
    symbolic link: :func:`open_atomic` replaces the link, never what it points to.
    """
    if isinstance(root, Location) or isinstance(target, Location):
        if not (isinstance(root, Location) and isinstance(target, Location)
                and target.parent.is_inside(root)):
            raise OutsideOutputError(f"would be written outside the output {root}")
        return
    real_root = os.path.realpath(root)  # the parts that do not exist yet are taken as given
    real_parent = os.path.realpath(Path(os.path.abspath(target)).parent)
    if real_parent != real_root and not real_parent.startswith(real_root.rstrip(os.sep) + os.sep):
        raise OutsideOutputError(
            f"would be written outside the output {root} (through a symbolic link to "
            f"{real_parent})"
        )


@contextlib.contextmanager
def open_atomic(
    path: str | Path | Location, mode: str = "wb", *, root: str | Path | Location | None = None,
    **kwargs: Any,
) -> Iterator[IO]:
    """A file that appears at ``path`` whole, when the ``with`` block ends without error.

    It is written as a hidden temporary file in the same directory, then renamed over
    ``path`` (``os.replace`` is atomic within a file system), so no reader ever sees a
    partial file. On error (or interruption) the temporary file is removed and ``path`` is
    untouched. ``root``: the output the user named; the file must lie inside it
    (:func:`check_inside`), checked before and after the directories are made.
    """
    if isinstance(path, Location):
        with _open_whole(path, mode, root=root, **kwargs) as stream:
            yield stream
        return
    path = Path(path)
    if root is not None:
        check_inside(root, path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if root is not None:
        check_inside(root, path)
    descriptor, temporary = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.name}.gsrwt-{os.getpid()}-", suffix=".part"
    )
    handle = os.fdopen(descriptor, mode, **kwargs)
    try:
        yield handle
        handle.close()  # a full disk shows here, when the last buffer is flushed
        os.chmod(temporary, 0o666 & ~current_umask())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):  # the first error is the one to report
            handle.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


@contextlib.contextmanager
def _open_whole(
    path: Location, mode: str, *, root: str | Path | Location | None, **kwargs: Any
) -> Iterator[IO]:
    """:func:`open_atomic` on an object store: the data is kept in memory and sent in one
    request when the block ends without error (:meth:`~.storage.Location.write_whole`),
    so the object appears whole or not at all and nothing is left behind on error."""
    if root is not None:
        check_inside(root, path)
    if "b" in mode:
        binary = io.BytesIO()
        yield binary
        path.write_whole(binary.getvalue())
        return
    text = io.StringIO(newline=kwargs.get("newline"))  # type: ignore[arg-type]
    yield text
    encoding = str(kwargs.get("encoding") or "utf-8")
    path.write_whole(text.getvalue().encode(encoding, str(kwargs.get("errors") or "strict")))


def write_atomic(
    path: str | Path | Location, data: bytes, *, root: str | Path | Location | None = None
) -> None:
    """Write ``data`` to ``path`` whole or not at all (:func:`open_atomic`)."""
    with open_atomic(path, "wb", root=root) as handle:
        handle.write(data)


def temporary_target(name: str) -> str:
    """The file name a temporary of ours stands for: ``.a.jpg.gsrwt-12-x.part`` -> ``a.jpg``."""
    return name[1:].rsplit(".gsrwt-", 1)[0]


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` (a temporary's writer) still runs: ours, or any that
    answers signal 0 or is someone else's."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    except OSError as error:
        return error.errno != errno.ESRCH
    return True


def remove_stale_temporaries(
    directory: str | Path, pids: set[int] | None = None, names: set[str] | None = None
) -> list[Path]:
    """Remove our temporary files in ``directory`` whose writing process is gone.

    ``pids``: remove only those of these processes (known dead, e.g. a killed worker),
    whether or not the id has been reused since. ``names``: remove only temporaries of these
    file names (the outputs of one shard, whose neighbours may be written by other machines,
    where a live process's id means nothing here). Returns what was removed; a directory
    that does not exist or cannot be listed has nothing to remove.
    """
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = TEMPORARY_PATTERN.match(entry.name)
        if match is None:
            continue
        pid = int(match.group(1))
        if names is not None and temporary_target(entry.name) not in names:
            continue
        stale = pid in pids if pids is not None else not process_alive(pid)
        if stale and not entry.is_dir(follow_symlinks=False):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed
