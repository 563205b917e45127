"""The one runner of every batch (:func:`gsrwt_cli.batch.in_order.run_in_order`): rows in
input order from results in any order, parent rows made in turn, and a row for every index
however the run stops."""

from __future__ import annotations

import os
import signal
import time

import pytest

from gsrwt_cli.batch.in_order import run_in_order
from gsrwt_cli.cli.batch_run import stop_on_signals


def finishing(order: list[int], closed: list[bool]):
    """Results of the indices in ``order`` (the order workers finish in), noting its close."""
    try:
        for index in order:
            yield index, {"index": index, "status": "ok"}
    finally:
        closed.append(True)


def test_rows_come_out_in_input_order_with_parent_rows_in_their_turn():
    out, closed, progress = [], [], []
    run_in_order(6, finishing([4, 0, 2, 5], closed), out.append,
                 lambda index: pytest.fail("nothing stopped"),
                 parent={1, 3}, parent_row=lambda index: {"index": index, "status": "parent"},
                 on_progress=lambda: progress.append(1))
    assert [row["index"] for row in out] == [0, 1, 2, 3, 4, 5]
    assert [row["status"] for row in out] == ["ok", "parent", "ok", "parent", "ok", "ok"]
    assert closed and len(progress) == 6


def test_positions_map_to_indices():
    out, closed = [], []
    workers = [1, 3]  # the jobs that went to workers; the others are the parent's
    run_in_order(4, finishing([1, 0], closed), out.append, lambda index: {},
                 index_of=workers.__getitem__, parent={0, 2},
                 parent_row=lambda index: {"index": index, "status": "parent"})
    # Worker rows carry their position: position 0 is job 1, position 1 is job 3.
    assert [(row["index"], row["status"]) for row in out] == [
        (0, "parent"), (0, "ok"), (2, "parent"), (1, "ok")]


def test_a_stop_rows_every_index_once_and_stops_the_workers():
    """A stop inside ``on_row`` (Ctrl-C while a row is written) leaves that row written
    once; the rest, even a result not yet read, get their stopped (or parent) rows; the
    exception goes on."""
    out, closed = [], []

    def on_row(row):
        out.append(row)
        if row["index"] == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_in_order(6, finishing([0, 1, 2, 3], closed), on_row,
                     lambda index: {"index": index, "status": "interrupted"},
                     parent={4}, parent_row=lambda index: {"index": index, "status": "parent"})
    assert [row["index"] for row in out] == [0, 1, 2, 3, 4, 5]
    assert [row["status"] for row in out] == ["ok"] * 3 + ["interrupted", "parent",
                                                            "interrupted"]
    assert closed


def slowly_finishing(count: int, closed: list[bool]):
    """Results as a batch's workers send them: the first two a tenth of a second apart, the
    rest a second apart, so that a stop delivered again 50 ms after the row in hand lands
    while the third is awaited, however late a loaded machine runs the timer (the main
    thread sees it when it next runs Python: here, when the wait ends)."""
    try:
        for index in range(count):
            time.sleep(0.1 if index < 2 else 1.0)
            yield index, {"index": index, "status": "ok"}
    finally:
        closed.append(True)


def test_ctrl_c_while_a_row_is_written_waits_for_the_row():
    """A real SIGINT, sent while a row is half-written, through gsrwt's own handler: the row
    is finished and kept, the stop lands while the next result is awaited, and every index
    has one row. (Before, the KeyboardInterrupt landed inside ``on_row``, after the index had
    counted out: the image had no row at all.)"""
    out, closed = [], []

    def on_row(row):
        if row["index"] == 1:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)  # the handler runs here, inside the writing of the row
        out.append(row)

    with pytest.raises(KeyboardInterrupt), stop_on_signals():
        run_in_order(5, slowly_finishing(5, closed), on_row,
                     lambda index: {"index": index, "status": "interrupted"})
    assert [row["index"] for row in out] == [0, 1, 2, 3, 4]
    assert [row["status"] for row in out] == ["ok", "ok", "interrupted", "interrupted",
                                              "interrupted"]
    assert closed
