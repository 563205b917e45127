"""The process executor on its own: items in flight, deaths, and what is put back."""

from __future__ import annotations

import multiprocessing
import os
import signal
import time

import pytest

from gsrwt_cli.batch.executor import ITEMS_IN_FLIGHT, ProcessExecutor


def _make_worker(deadly: frozenset[int]):
    def work(item: int) -> tuple[int, int]:
        if item in deadly:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.002)  # a small image's worth of work
        return item * item, os.getpid()
    return work


@pytest.mark.parametrize("processes", [1, 2, 3])
def test_every_item_once_when_workers_die_with_items_queued_behind(processes):
    """Workers get items ahead (ITEMS_IN_FLIGHT): one killed on an item costs that item
    only; the items queued behind it are done by other (or fresh) workers, each once."""
    assert ITEMS_IN_FLIGHT >= 2
    items = list(range(40))
    deadly = frozenset({3, 4, 17, 39})  # 3 and 4 back to back: a queued item dies too
    deaths: list[int] = []
    executor = ProcessExecutor(
        _make_worker, (deadly,), processes,
        on_death=lambda item, reason: deaths.append(item) or ("died", reason),
        context=multiprocessing.get_context("fork"))
    results = dict(executor.map_unordered(items))
    assert sorted(results) == items
    assert sorted(deaths) == sorted(deadly) and executor.deaths == len(deadly)
    for item in items:
        if item in deadly:
            assert results[item] == ("died", "worker died: signal 9 (SIGKILL)")
        else:
            assert results[item][0] == item * item
    if processes > 1:  # the work was shared
        assert len({result[1] for item, result in results.items() if item not in deadly}) > 1


def _make_frame_worker(deadly: frozenset[int]):
    def work(item: tuple[int, bytes]) -> tuple[int, int]:
        index, payload = item
        if index in deadly:
            os.kill(os.getpid(), signal.SIGKILL)
        return index, len(payload)  # a frame's worth back is sent by the video worker
    return work


@pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")
@pytest.mark.parametrize("processes", [1, 2])
def test_a_stream_of_large_items_with_deaths_and_a_bounded_window(processes):
    """``map_stream`` takes items from an iterator only as workers have room and the
    window allows (a video's frames, decoded as needed): large items both ways never
    deadlock the pipes, a death costs its item only, and no more than ``window`` items
    are ever taken ahead of the oldest result not out.

    A worker's pipe is closed by the thread sending it items, never under it: closed by the
    parent's loop while the thread was mid-send, its descriptor went to the next worker's
    pipe, which got the rest of a frame and died on it (seen once in CI as an item after a
    deadly one reported dead), and the thread's next write raised in it (an unhandled
    thread exception, an error here). Run a few times: the race needs the timing."""
    for _ in range(3):
        _stream_with_deaths(processes)


def _stream_with_deaths(processes: int) -> None:
    taken: list[int] = []
    out: set[int] = set()
    window = ITEMS_IN_FLIGHT * processes
    deadly = frozenset({5, 6, 23})
    ahead: list[int] = []

    def frames():
        for index in range(40):
            taken.append(index)
            ahead.append(index - min(set(range(40)) - out))
            yield index, bytes(600_000)  # larger than a pipe's buffer

    executor = ProcessExecutor(
        _make_frame_worker, (deadly,), processes,
        on_death=lambda item, reason: ("died", item[0]),
        context=multiprocessing.get_context("forkserver"))
    results = {}
    for index, result in executor.map_stream(frames(), window):
        results[index] = result
        out.add(index)
    assert sorted(results) == list(range(40)) and taken == list(range(40))
    for index, result in results.items():
        assert result == (("died", index) if index in deadly else (index, 600_000))
    assert max(ahead) < window
