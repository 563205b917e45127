"""Rows in input order from work that finishes in any order: the runner of every batch of files.

``gsrwt rectify`` and ``gsrwt estimate`` hand images to an executor's workers, whose rows come
back as they finish; the table wants them in input order, and a stopped run still wants a
row for every image. :func:`run_in_order` is that loop, once. (A video's or bag's frames,
whose count is not known until the stream ends, are put in order as they are decoded:
:mod:`~gsrwt_cli.batch.video_jobs` and :mod:`~gsrwt_cli.batch.sequence_workers`.)
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Collection, Generator, Iterator
from typing import Any

Row = dict[str, Any]

_rows_in_hand = 0


@contextlib.contextmanager
def row_in_hand() -> Iterator[None]:
    """A row taken from the waiting ones and being written: a stop that comes meanwhile
    (the signal handler of :func:`~gsrwt_cli.cli.batch_run.stop_on_signals` asks
    :func:`a_row_is_in_hand`) waits until the row is out, so that it is neither lost nor
    written twice. Exceptions raised by the writing itself still go on at once."""
    global _rows_in_hand
    _rows_in_hand += 1
    try:
        yield
    finally:
        _rows_in_hand -= 1


def a_row_is_in_hand() -> bool:
    """Whether the main thread is inside :func:`row_in_hand`."""
    return _rows_in_hand > 0


def run_in_order(
    count: int,
    results: Generator[tuple[int, Row], None, None],
    on_row: Callable[[Row], None],
    stopped_row: Callable[[int], Row],
    *,
    index_of: Callable[[int], int] = int,
    parent: Collection[int] = (),
    parent_row: Callable[[int], Row] | None = None,
    on_progress: Callable[[], None] | None = None,
) -> None:
    """Hand ``on_row`` the row of every index ``0 .. count - 1``, in order.

    ``results`` yields ``(position, row)`` as workers finish, in any order; ``index_of``
    turns a position into its index. The indices in ``parent`` need no worker: their rows
    are made here by ``parent_row`` when their turn comes. A row waits until the rows before
    it are out; ``on_progress`` is called as each is made.

    If anything stops the run (an exception such as ``KeyboardInterrupt``, from the results
    or from ``on_row``), ``results`` is closed (which stops its workers), every index not yet
    out gets its row (``parent_row`` for the parent's, ``stopped_row`` for the others) and
    the exception goes on. An index counts as out before ``on_row`` sees its row, so an
    exception raised by ``on_row`` never rows an image twice, and a signal's stop waits until
    the row is written (:func:`row_in_hand`), so it never loses one.
    """
    rows: dict[int, Row] = {}
    following = 0

    def made(row: Row) -> Row:
        if on_progress is not None:
            on_progress()
        return row

    def emit(stopped: bool = False) -> None:
        nonlocal following
        while following < count:
            index = following
            if index not in rows:
                if index in parent and parent_row is not None:
                    rows[index] = made(parent_row(index))
                elif stopped:
                    rows[index] = stopped_row(index)
                else:
                    return
            with row_in_hand():
                row = rows.pop(index)
                following += 1
                on_row(row)

    try:
        emit()
        for position, row in results:
            rows[index_of(position)] = made(row)
            emit()
        emit()
    except BaseException:
        results.close()  # stops the workers (and removes what they left half-written)
        emit(stopped=True)
        raise
    finally:
        results.close()
