"""The run of a batch command (``rectify``, ``estimate``): signals that stop it cleanly, the
table's stream, and its last line and exit status."""

from __future__ import annotations

import _thread
import contextlib
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from types import FrameType
from typing import IO, Any

import click

from ..batch.in_order import a_row_is_in_hand
from ..io.outputs import open_atomic
from ..io.storage import location


class _NoProgress:
    """A progress bar that is not drawn (``-q``, or stderr is not a terminal): what a batch
    calls on one, without importing tqdm (a fiftieth of a second of start-up)."""

    def update(self, count: int = 1) -> None:
        """Nothing to draw."""

    def write(self, line: str, file: IO[str] | None = None) -> None:
        """The line, as ``tqdm.write`` prints it beside a bar (to stderr unless ``file``)."""
        print(line, file=file or sys.stderr)

    def close(self) -> None:
        """Nothing to close."""


def progress_bar(quiet: bool, **options: Any) -> Any:
    """A batch's progress bar on stderr (tqdm, imported here, with ``options``), drawn only
    on a terminal and not with ``quiet``; else one that draws nothing (:class:`_NoProgress`).
    tqdm's monitor thread is off: workers may fork from this process."""
    if quiet or not sys.stderr.isatty():
        return _NoProgress()
    from tqdm import tqdm

    tqdm.monitor_interval = 0
    return tqdm(file=sys.stderr, dynamic_ncols=True, **options)


class TableWriteError(Exception):
    """The table could not be written (a full disk, say): the run cannot keep its record."""


class Terminated(BaseException):
    """SIGTERM, raised in the main process like KeyboardInterrupt is for SIGINT."""


def end_batch(summary: str, where: str, stopped: BaseException | None, failed: int,
              quiet: bool) -> None:
    """A batch command's last line on stderr (``gsrwt: SUMMARY; table: ...``, unless
    ``quiet``) and its exit status: 130 or 143 if ``stopped`` by SIGINT or SIGTERM (the line
    then starts ``interrupted:``; ``summary`` says what was not done), 1 if some failed."""
    if not quiet:
        click.echo(f"gsrwt: {'interrupted: ' if stopped is not None else ''}{summary}{where}",
                   err=True)
    if stopped is not None:
        sys.exit(143 if isinstance(stopped, Terminated) else 130)
    if failed:
        sys.exit(1)


def _inside_a_dask_client_call(frame: FrameType | None) -> bool:
    """Whether ``frame`` (the main thread's, when a signal came) is inside a blocking call of
    a Dask client (``distributed.utils.sync``). An exception raised there before the call's
    coroutine has started makes distributed log a ``NameError`` traceback (its ``sync``
    cancels a future it has not made yet), so a stop waits until such a call returns."""
    if "distributed.utils" not in sys.modules:
        return False
    while frame is not None:
        if frame.f_code.co_name == "sync" and frame.f_globals.get("__name__") == (
                "distributed.utils"):
            return True
        frame = frame.f_back
    return False


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt and SIGTERM raises :class:`Terminated`, once, in the
    main thread, outside any Dask client call (:func:`_inside_a_dask_client_call`) and
    outside the writing of a row (:func:`~gsrwt_cli.batch.in_order.row_in_hand`).

    After the first, both are ignored until the block ends, so that the table of what
    finished is written whole even if the user presses Ctrl-C again.
    """

    def stop(signum: int, frame: FrameType | None) -> None:
        if _inside_a_dask_client_call(frame) or a_row_is_in_hand():
            # Delivered again in 50 ms, until the call has returned or the row is out.
            threading.Timer(0.05, _thread.interrupt_main, args=(signum,)).start()
            return
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise KeyboardInterrupt if signum == signal.SIGINT else Terminated

    saved = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM)}
    for number in saved:
        signal.signal(number, stop)
    try:
        yield
    finally:
        for number, handler in saved.items():
            signal.signal(number, handler)


@contextlib.contextmanager
def open_table(path: str) -> Iterator[IO[str]]:
    """The table's stream: stdout for ``-``, else a file that appears whole at the end.

    File names that are not UTF-8 are written as their own bytes (``surrogateescape``).
    """
    if path == "-":
        yield sys.stdout
        return
    finished = False
    try:
        with open_atomic(location(path), "w", encoding="utf-8", errors="surrogateescape",
                         newline="") as stream:
            yield stream
            finished = True
    except OSError as error:
        if not finished:
            raise
        raise TableWriteError(error.strerror or str(error)) from None  # flushing at the end


@contextlib.contextmanager
def recorded_rows(path: str, columns: Sequence[str], fmt: str, counts: Any,
                  report: Callable[[str], None], place: Callable[[dict[str, Any]], str]
                  ) -> Iterator[Callable[[dict[str, Any]], None]]:
    """A batch's table at ``path`` (``-``: stdout), yielding its ``on_row``: each row is
    written as it comes (:func:`open_table`), counted in ``counts`` (``add``), and an error
    row is reported in one line through ``report``, naming ``place(row)``. The table is closed
    when the block ends (a run stopped by a signal has caught it inside, so every row is in);
    a table that cannot be written (a full disk) is a one-line error naming ``--table``."""
    from ..base.messages import one_line
    from ..tables.writer import TableWriter
    from .options import InputError

    try:
        with open_table(path) as stream:
            writer = TableWriter(stream, columns, fmt)

            def on_row(row: dict[str, Any]) -> None:
                try:
                    writer.write_row(row)
                except OSError as error:
                    if path == "-":
                        raise
                    raise TableWriteError(error.strerror or str(error)) from None
                counts.add(row)
                if row["status"] == "error":
                    report(f"Error: {one_line(place(row))}: {row['error']}")

            yield on_row
            try:
                writer.close()
            except OSError as error:
                raise TableWriteError(error.strerror or str(error)) from None
    except TableWriteError as error:
        raise InputError(f"--table {path}: cannot write the table ({error})") from None
