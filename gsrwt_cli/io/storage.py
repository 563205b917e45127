"""Files in object stores and other fsspec file systems, named by URL (``s3://bucket/run1/``,
``gs://``, ``memory://``), beside local paths.

A :class:`Location` is a URL with the few methods of :class:`pathlib.Path` that the batch
uses (``name``, ``suffix``, ``parent``, ``/``, ``exists``, ``is_file``, ``read_bytes``), so
that jobs, sidecars and tables carry either; local paths never come here (``file://`` URLs
become paths: :func:`location`), so they keep their own code path. fsspec (the ``dask``
extra) is imported on first use; credentials and endpoints come from its usual
configuration (``AWS_ACCESS_KEY_ID``, ``AWS_ENDPOINT_URL``, ``FSSPEC_S3_ENDPOINT_URL``...).

Writes are whole: :meth:`Location.write_whole` sends the object in one request (one PUT on
S3, or a multipart upload that the store shows only once complete), never a partial
object. A process keeps the names of the directories it listed (:func:`list_files`), so
that looking for ``NAME.yaml`` beside 100,000 listed images asks the store nothing more;
:meth:`Location.exists` always asks (outputs change while a batch runs).

Every failure of a store is an ``OSError`` whose ``strerror`` says what went wrong in the
store's words (:class:`StoreError` for what is no ``OSError`` of its own: an endpoint that
cannot be reached, a missing profile, fsspec or the store's package not installed), so
callers word it as they word a local file's. The first time a process uses a store (a
bucket), it is asked once with no retries and short timeouts (:func:`_check_reachable`): an
unreachable endpoint fails in seconds, not after botocore's retries.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import posixpath
import re
import threading
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import IO, Any

#: ``scheme://``: a URL, not a path.
URL_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*://")

_LISTED: dict[str, set[str]] = {}  # directory URL -> names of the files listed in it
_FETCHED = threading.local()  # the object a job of this thread read whole: url, bytes
_REACHED: set[str] = set()  # stores (scheme://bucket) this process has reached
_PROBED: set[str] = set()  # prefixes this process has written a probe object to

#: How the first request to an S3 store is made (:func:`_check_reachable`): one attempt,
#: short timeouts, so that an unreachable endpoint is an error in seconds. Later requests
#: keep botocore's retries, for a long batch's passing faults.
FIRST_REQUEST_CONFIG = {"connect_timeout": 3, "read_timeout": 10,
                        "retries": {"max_attempts": 1, "mode": "standard"}}
#: Characters of a store's own error message kept in ours.
STORE_MESSAGE_LIMIT = 240
#: The ``OSError`` classes a store's error keeps, with their error numbers (callers tell a
#: missing object by its class); any other failure becomes a :class:`StoreError`.
_KEPT_ERRORS: dict[type[OSError], int] = {
    FileNotFoundError: errno.ENOENT, PermissionError: errno.EACCES,
    IsADirectoryError: errno.EISDIR, NotADirectoryError: errno.ENOTDIR,
    FileExistsError: errno.EEXIST,
}


class StoreError(OSError):
    """A store named by URL cannot be used; ``strerror`` says why in one line: it cannot
    be reached, refuses the credentials, or its package is not installed."""


def _store_message(error: BaseException) -> str:
    """A store's error on one bounded line: its own words, else its type's name."""
    text = " ".join(str(error.strerror if isinstance(error, OSError) and error.strerror
                        else error).split())
    if len(text) > STORE_MESSAGE_LIMIT:
        text = text[: STORE_MESSAGE_LIMIT - 3] + "..."
    return text or type(error).__name__


@contextlib.contextmanager
def _asking(url: str) -> Iterator[None]:
    """While the block asks the store about ``url``, any failure leaves as an ``OSError``
    with a ``strerror`` (:data:`_KEPT_ERRORS` keep their class, the rest are
    :class:`StoreError`), naming ``url``."""
    try:
        yield
    except StoreError:
        raise
    except tuple(_KEPT_ERRORS) as error:
        kind = next(kind for kind in _KEPT_ERRORS if isinstance(error, kind))
        raise kind(error.errno or _KEPT_ERRORS[kind], _store_message(error), url) from error
    except Exception as error:  # botocore's, aiohttp's...: not OSErrors of their own
        raise StoreError(errno.EIO, _store_message(error), url) from error


def is_url(text: object) -> bool:
    """Whether ``text`` (a string) is a URL such as ``s3://bucket/key``."""
    return isinstance(text, str) and bool(URL_PATTERN.match(text))


def location(text: str | Path) -> Path | Location:
    """A local :class:`~pathlib.Path` for a path or a ``file://`` URL, else a
    :class:`Location`."""
    if isinstance(text, Location | Path):
        return text
    if is_url(text):
        if text.lower().startswith("file://"):
            return Path(text[len("file://"):] or "/")
        return Location(text)
    return Path(text)


def _filesystem(url: str) -> tuple[Any, str]:
    """The file system of ``url`` and its path there; the first time this process uses
    the store, it is asked whether it answers (:func:`_check_reachable`). Raises
    :class:`StoreError` when fsspec or the store's package is missing, the scheme is
    unknown, or the store cannot be reached."""
    found = _open_filesystem(url)
    store = _store_of(url)
    if store not in _REACHED:
        _check_reachable(url)
        _REACHED.add(store)
    return found


def _open_filesystem(url: str, **options: Any) -> tuple[Any, str]:
    try:
        import fsspec  # the dask extra; imported here so that local runs never import it
    except ImportError as error:
        raise StoreError(errno.ENOSYS, f"URLs need fsspec ({error}); install it with "
                         "pip install 'gsrwt[dask]'", url) from None
    scheme = url.split("://", 1)[0]
    try:
        # No listings cache: outputs appear while a batch runs, and a stale listing would
        # call a written object missing (this module keeps its own names of listed inputs).
        return fsspec.core.url_to_fs(url, use_listings_cache=False, **options)
    except ImportError as error:  # fsspec knows the scheme; its package is missing
        raise StoreError(errno.ENOSYS, f"{scheme}:// URLs need a package that is not "
                         f"installed ({_store_message(error)})", url) from None
    except Exception as error:  # an unknown scheme (ValueError), a bad configuration...
        raise StoreError(errno.EINVAL, f"cannot use {scheme}:// URLs "
                         f"({_store_message(error)})", url) from None


def _store_of(url: str) -> str:
    """``scheme://bucket``: what one check of a store covers (its endpoint, credentials)."""
    scheme, rest = url.split("://", 1)
    return f"{scheme.lower()}://{rest.lstrip('/').split('/', 1)[0]}"


def _check_reachable(url: str) -> None:
    """Ask the store about ``url`` once, without retries and with short timeouts on S3
    (:data:`FIRST_REQUEST_CONFIG`). Its answer may be that nothing is there, or that the
    credentials may not look (the caller's own request says so in its words); anything
    else (no endpoint, no such profile, no credentials) raises :class:`StoreError`."""
    scheme = url.split("://", 1)[0].lower()
    options = {}
    if scheme in ("s3", "s3a"):  # the user's fsspec configuration (addressing style...) kept
        from fsspec.config import conf

        configured = conf.get(scheme, {}).get("config_kwargs") or {}
        options["config_kwargs"] = {**configured, **FIRST_REQUEST_CONFIG}
    fs, path = _open_filesystem(url, **options)
    try:
        fs.info(path)
    except OSError:
        return
    except Exception as error:  # botocore's, aiohttp's...: the store did not answer
        raise StoreError(errno.EIO, _store_message(error), url) from error


def check_writable(prefix: Location) -> None:
    """Prove that objects can be written below ``prefix``: a probe object of a name like
    our temporary files' (``.gsrwt-probe.gsrwt-PID-XXXX.part``, hidden from listings) is
    written and removed, once per prefix and process. Raises an ``OSError`` naming
    ``prefix`` with the store's reason (no such bucket, access denied, no endpoint)."""
    if prefix.url in _PROBED:
        return
    probe = prefix / f".gsrwt-probe.gsrwt-{os.getpid()}-{uuid.uuid4().hex[:8]}.part"
    fs, path = _filesystem(probe.url)
    with _asking(prefix.url):
        fs.pipe_file(path, b"")
    with contextlib.suppress(Exception):  # a store that lets us write but not remove
        fs.rm_file(path)
    _PROBED.add(prefix.url)


@dataclass(frozen=True)
class Location:
    """An object (or a prefix) in an fsspec file system, named by its URL."""

    url: str

    def __post_init__(self) -> None:
        scheme, rest = self.url.split("://", 1)
        object.__setattr__(self, "url", f"{scheme}://{rest.rstrip('/') or rest}")

    def __str__(self) -> str:
        return self.url

    def __fspath__(self) -> str:  # never a local file by mistake: open() refuses it
        raise TypeError(f"{self.url} is a URL, not a local path")

    # -- names ---------------------------------------------------------------------------
    @property
    def _key(self) -> str:
        return self.url.split("://", 1)[1]

    @property
    def name(self) -> str:
        return posixpath.basename(self._key)

    @property
    def suffix(self) -> str:
        return PurePosixPath(self.name).suffix

    @property
    def stem(self) -> str:
        return PurePosixPath(self.name).stem

    @property
    def parent(self) -> Location:
        head = posixpath.dirname(self._key)
        return Location(f"{self.url.split('://', 1)[0]}://{head or self._key}")

    def __truediv__(self, other: str | PurePosixPath) -> Location:
        relative = PurePosixPath(str(other).replace("\\", "/")).as_posix().lstrip("/")
        return Location(f"{self.url}/{relative}")

    def with_name(self, name: str) -> Location:
        return self.parent / name

    def with_suffix(self, suffix: str) -> Location:
        return self.with_name(PurePosixPath(self.name).with_suffix(suffix).name)

    def is_absolute(self) -> bool:
        return True

    def is_inside(self, root: Location) -> bool:
        """Whether this URL is ``root`` or below it (the same store and a longer key)."""
        return self.url == root.url or self.url.startswith(root.url.rstrip("/") + "/")

    # -- the store -----------------------------------------------------------------------
    def exists(self) -> bool:
        """Whether an object (or a prefix) is there now: the store is asked."""
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            return bool(fs.exists(path))

    def is_file(self) -> bool:
        """Whether an object is there: from this process's listing of its directory
        (:func:`list_files`) if it made one, else the store is asked."""
        listed = _LISTED.get(self.parent.url)
        if listed is not None:
            return self.name in listed
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            try:
                return bool(fs.isfile(path))
            except OSError:
                return False

    def is_dir(self) -> bool:
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            try:
                return bool(fs.isdir(path))
            except OSError:
                return False

    def read_bytes(self, limit: int | None = None) -> bytes:
        """The object's bytes (its first ``limit``): the one a job of this thread fetched
        (:func:`fetched`) if it is this one, else from the store (``FileNotFoundError``...)."""
        cached = getattr(_FETCHED, "item", None)
        if cached is not None and cached[0] == self.url:
            return cached[1] if limit is None else cached[1][:limit]
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            if fs.isdir(path):
                raise IsADirectoryError(errno.EISDIR, "Is a directory", self.url)
            return fs.cat_file(path, start=None, end=limit)

    def read_text(self, encoding: str = "utf-8", errors: str = "strict") -> str:
        return self.read_bytes().decode(encoding, errors)

    def open_read(self) -> IO[bytes]:
        """A binary stream of the object: from the fetched bytes if a job fetched it, else a
        buffered reader that fetches what is read (headers stay small reads)."""
        cached = getattr(_FETCHED, "item", None)
        if cached is not None and cached[0] == self.url:
            return io.BytesIO(cached[1])
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            if fs.isdir(path):
                raise IsADirectoryError(errno.EISDIR, "Is a directory", self.url)
            return fs.open(path, "rb", block_size=1 << 16, cache_type="readahead")

    def write_whole(self, data: bytes) -> None:
        """Write the object in one request: it appears whole or not at all."""
        with _asking(self.url):
            fs, path = _filesystem(self.url)
            fs.pipe_file(path, bytes(data))

    def list_objects(self) -> set[str]:
        """The URLs of every object below this prefix (one listing), empty if none."""
        with _asking(self.url):
            fs, _ = _filesystem(self.url)
            base = fs._strip_protocol(self.url).rstrip("/")
            try:
                names = fs.find(base, withdirs=False, detail=False)
            except (FileNotFoundError, NotADirectoryError):
                return set()
        return {(self / fs._strip_protocol(name)[len(base) + 1:]).url for name in names
                if fs._strip_protocol(name).startswith(base + "/")}


def walk_order(relative: PurePosixPath) -> tuple[tuple[int, str], ...]:
    """The order in which a sorted ``os.walk`` meets files: a directory's own files (by
    name) before its subdirectories (by name, each walked in turn)."""
    *directories, name = relative.parts
    return (*((1, part) for part in directories), (0, name))


def list_files(prefix: Location, recursive: bool, unusable: list[str] | None = None,
               ) -> list[tuple[Location, PurePosixPath]]:
    """Every object below ``prefix`` (only its own level unless ``recursive``), in the order
    a local directory's walk gives (:func:`walk_order`), with its path relative to
    ``prefix``; names beginning with a dot (and what lies below them) are left out. The
    names are kept for :meth:`Location.is_file`. One listing of the store.

    A key is any text, but a path is not: a key below ``prefix`` with an empty, ``.`` or
    ``..`` part (``in//a.jpg``, ``in/./a.jpg``, ``in/x/../a.jpg``) names no file an output
    could keep, so it is left out and its full URL added to ``unusable``.
    """
    with _asking(prefix.url):
        fs, _ = _filesystem(prefix.url)
        base = fs._strip_protocol(prefix.url).rstrip("/")
        found = fs.find(base, maxdepth=None if recursive else 1, withdirs=False, detail=False)
    listed = []
    for name in found:
        stripped = fs._strip_protocol(name)
        if not stripped.startswith(base + "/"):
            continue
        key = stripped[len(base) + 1:]
        if any(part in ("", ".", "..") for part in key.split("/")):
            if unusable is not None:
                unusable.append(f"{prefix.url.rstrip('/')}/{key}")
            continue
        listed.append(PurePosixPath(key))
    files = []
    for relative in sorted(listed, key=walk_order):
        item = prefix / relative.as_posix()
        _LISTED.setdefault(item.parent.url, set()).add(item.name)
        if any(part.startswith(".") for part in relative.parts):
            continue
        files.append((item, relative))
    _LISTED.setdefault(prefix.url, set())
    return files


@contextlib.contextmanager
def fetched(source: object) -> Iterator[None]:
    """While the block runs, this thread reads ``source`` (a :class:`Location`) from one
    whole fetch of it: a job's header, EXIF and pixels cost one request, not three. A
    local path, or an object that cannot be read (the job says why later), is left alone."""
    if not isinstance(source, Location):
        yield
        return
    try:
        fs, path = _filesystem(source.url)
        data = fs.cat_file(path)
    except Exception:
        yield
        return
    _FETCHED.item = (source.url, data)
    try:
        yield
    finally:
        _FETCHED.item = None


def open_input(path: str | Path | Location) -> IO[bytes]:
    """A binary stream of a local file (``open``) or of an object named by URL."""
    if isinstance(path, Location):
        return path.open_read()
    if is_url(path):
        resolved = location(str(path))
        if isinstance(resolved, Location):
            return resolved.open_read()
        path = resolved
    return open(path, "rb")
