"""Run one function over many items in worker processes that may die, and stop cleanly.

:class:`ProcessExecutor` hands items to workers over a pipe each, :data:`ITEMS_IN_FLIGHT` at
a time (so that a worker never waits for the parent between two small images), and watches
every worker's process sentinel, so that:

- a worker that dies (kill -9, the OOM killer, a crash in a codec) costs only the item it was
  working on, which is reported through ``on_death``; the items queued behind it go to other
  workers, and a fresh worker takes its place;
- a parent that dies takes its workers with it: a worker exits quietly when its pipe closes,
  and on Linux the kernel sends it SIGTERM when its parent goes (``PR_SET_PDEATHSIG``);
- stopping (an exception in the caller: Ctrl-C, SIGTERM, a closed pipe) ends every worker
  with SIGTERM, which unwinds its work (temporary files are removed on the way out), then
  SIGKILL for any that does not end within a grace period; ``on_abandon`` is told which items
  were in flight, and in which process, so the caller can clean up after them.

Workers ignore SIGINT: Ctrl-C reaches the whole process group, and only the parent decides.
Results arrive as ``(index, result)`` in completion order.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import queue
import signal
import sys
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from typing import Any, Generic, Protocol, TypeVar

Item = TypeVar("Item")
Result = TypeVar("Result")

#: Seconds a worker is given to end after SIGTERM before it is killed.
STOP_GRACE_SECONDS = 5.0
#: Items sent to a worker ahead of its results: the next is in its pipe when it finishes one
#: (a 640x480 frame takes 4 ms; a round trip through the parent, up to a scheduling delay).
ITEMS_IN_FLIGHT = 2


def death_reason(exitcode: int | None) -> str:
    """``worker died: signal 9 (SIGKILL)`` or ``worker died: exit code 3``."""
    if exitcode is not None and exitcode < 0:
        try:
            name = f" ({signal.Signals(-exitcode).name})"
        except ValueError:
            name = ""
        return f"worker died: signal {-exitcode}{name}"
    return f"worker died: exit code {exitcode}"


def _die_with_parent() -> None:
    """Ask Linux to send this process SIGTERM when its parent ends (no-op elsewhere)."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGTERM, 0, 0, 0)


def _on_sigterm(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


def _worker_main(
    connection: Connection, make_worker: Callable[..., Callable[[Any], Any]], args: tuple
) -> None:
    """A worker's life: take an item, send its result, until told to stop or orphaned."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _on_sigterm)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    _die_with_parent()
    try:
        work = make_worker(*args)
        while True:
            item = connection.recv()
            if item is None:
                return
            connection.send(work(item))
    except (EOFError, BrokenPipeError, ConnectionResetError, SystemExit):
        # The parent is gone or stopped us: leave quietly (no traceback on a dead stderr).
        return
    finally:
        with contextlib.suppress(OSError):
            sys.stderr.flush()


class Executor(Protocol[Item, Result]):
    """What the batch runner needs of an engine: results of items as they complete.

    ``map_unordered`` yields ``(index, result)`` for every item, in any order, and stops its
    work when the generator is closed (as the runner does on Ctrl-C). :class:`ProcessExecutor`
    is the local one; a cluster's (a Dask client's ``map`` and ``as_completed``) fits the same
    shape, with its workers built by the same ``make_worker``.
    """

    def map_unordered(self, items: Sequence[Item]) -> Iterator[tuple[int, Result]]: ...


@dataclass
class _Worker:
    process: multiprocessing.process.BaseProcess
    connection: Connection
    #: The indices of the items sent, in order: the first is the one being worked on.
    in_flight: deque[int] = field(default_factory=deque)
    #: The thread that sends this worker's items, when they are sent by one
    #: (:meth:`ProcessExecutor.map_stream`); it then owns the connection's end.
    sender: _Sender | None = None

    def send(self, item: Any) -> None:
        """Send an item (or ``None``, to stop) through the sender thread, if any."""
        if self.sender is not None:
            self.sender.send(item)
        else:
            # A worker that died since its last result breaks the pipe: its sentinel
            # then reports the death, and the item is reported with it.
            with contextlib.suppress(OSError):
                self.connection.send(item)

    def close(self) -> None:
        """Close the parent's end of the pipe, or have the sender thread close it once it
        is done: closing it under a thread still writing would free its descriptor for the
        next file or pipe opened, and the rest of the item would be written there."""
        if self.sender is not None:
            self.sender.close()
        else:
            self.connection.close()


class ProcessExecutor(Generic[Item, Result]):
    """``processes`` workers running over items, surviving the death of workers.

    Each worker process calls ``make_worker(*args)`` once, and the callable it returns once per
    item (so per-worker state, such as reusable memory, lives in that callable, not in module
    globals). ``on_death(item, reason)`` makes the result of an item whose worker died;
    ``on_abandon(item, pid)`` is called, in the parent, for an item whose worker was stopped
    or died while working on it (its process ``pid``). Items, results, ``make_worker`` and
    ``args`` must be picklable.
    """

    def __init__(
        self,
        make_worker: Callable[..., Callable[[Item], Result]],
        args: tuple,
        processes: int,
        *,
        on_death: Callable[[Item, str], Result],
        on_abandon: Callable[[Item, int], None] | None = None,
        context: multiprocessing.context.BaseContext | None = None,
    ) -> None:
        self.make_worker = make_worker
        self.args = args
        self.processes = max(1, processes)
        self.on_death = on_death
        self.on_abandon = on_abandon
        self.context = context or multiprocessing.get_context()
        self.deaths = 0

    def _start(self, threaded: bool = False) -> _Worker:
        """A new worker; with ``threaded``, its items are sent by a thread of its own."""
        parent_end, child_end = self.context.Pipe(duplex=True)
        process = self.context.Process(
            target=_worker_main,
            args=(child_end, self.make_worker, self.args),
            daemon=True,
        )
        process.start()
        child_end.close()
        return _Worker(process, parent_end, sender=_Sender(parent_end) if threaded else None)

    def map_unordered(self, items: Sequence[Item]) -> Iterator[tuple[int, Result]]:
        """``(index, result)`` for every item, as they complete."""
        queue = deque(range(len(items)))
        workers: list[_Worker] = []

        def dispatch(worker: _Worker, up_to: int = ITEMS_IN_FLIGHT) -> None:
            while queue and len(worker.in_flight) < up_to:
                worker.in_flight.append(queue.popleft())
                worker.send(items[worker.in_flight[-1]])

        try:
            for _ in range(min(self.processes, len(items))):
                workers.append(self._start())
            for up_to in range(1, ITEMS_IN_FLIGHT + 1):  # each its first item, then its second
                for worker in workers:
                    dispatch(worker, up_to)
            while any(worker.in_flight for worker in workers):
                for worker, index, done, outcome in self._outcomes(workers):
                    if done:
                        dispatch(worker)
                        yield index, outcome
                        continue
                    self._abandoned(items[index], worker)
                    queue.extendleft(reversed(worker.in_flight))
                    yield index, self.on_death(items[index], outcome)
                    if queue:
                        workers.append(self._start())
                        dispatch(workers[-1])
                    for other in workers:  # items put back go to whoever has room
                        dispatch(other)
        finally:
            self._stop(workers, items)

    def map_stream(self, items: Iterable[Item], window: int | None = None
                   ) -> Iterator[tuple[int, Result]]:
        """``(index, result)`` for every item of an iterable taken as workers have room (a
        video's frames, decoded as they are needed), as they complete.

        At most :data:`ITEMS_IN_FLIGHT` items are in flight per worker, and no item is taken
        more than ``window`` (default: twice that per worker) after the oldest whose result has
        not been yielded, so that a caller putting results back in order holds a bounded
        number of them. Items are dropped once their result is out.
        """
        window = window or ITEMS_IN_FLIGHT * self.processes
        source = iter(items)
        held: dict[int, Item] = {}  # taken, result not yet out
        queue: deque[int] = deque()  # taken, not yet sent (put back after a death)
        taken = 0
        exhausted = False
        workers: list[_Worker] = []

        def take() -> bool:
            nonlocal taken, exhausted
            if queue:
                return True
            if exhausted or (held and taken - min(held) >= window):
                return False
            try:
                item = next(source)
            except StopIteration:
                exhausted = True
                return False
            held[taken] = item
            queue.append(taken)
            taken += 1
            return True

        def dispatch(worker: _Worker, up_to: int = ITEMS_IN_FLIGHT) -> None:
            while len(worker.in_flight) < up_to and take():
                index = queue.popleft()
                worker.in_flight.append(index)
                worker.send(held[index])

        try:
            if not take():
                return
            for _ in range(self.processes):
                workers.append(self._start(threaded=True))
            for up_to in range(1, ITEMS_IN_FLIGHT + 1):
                for worker in workers:
                    dispatch(worker, up_to)
            while any(worker.in_flight for worker in workers):
                for worker, index, done, outcome in self._outcomes(workers):
                    if done:
                        del held[index]
                        yield index, outcome
                        for other in workers:
                            dispatch(other)
                        continue
                    self._abandoned(held[index], worker)
                    queue.extendleft(reversed(worker.in_flight))
                    yield index, self.on_death(held.pop(index), outcome)
                    workers.append(self._start(threaded=True))
                    for other in workers:
                        dispatch(other)
        finally:
            self._stop(workers, _Held(held))

    def _outcomes(self, workers: list[_Worker]) -> Iterator[tuple[_Worker, int, bool, Any]]:
        """Wait until some busy worker has news, then give each one's: ``(worker, index,
        True, result)`` for a result received (taken off its in-flight items), or ``(worker,
        index, False, reason)`` for a worker that died on its first item (no result, and its
        process ended or its pipe broke): joined, counted, its connection closed, taken out
        of ``workers``; the items behind the first, never started, are left in its in-flight
        list for the caller to put back."""
        busy = [worker for worker in workers if worker.in_flight]
        ready = set(wait([w.connection for w in busy] + [w.process.sentinel for w in busy]))
        for worker in busy:
            index = worker.in_flight[0]
            if worker.connection in ready or worker.connection.poll():
                try:
                    result = worker.connection.recv()
                except (EOFError, OSError):
                    pass
                else:
                    worker.in_flight.popleft()
                    yield worker, index, True, result
                    continue
            if worker.connection in ready or worker.process.sentinel in ready:
                worker.process.join(STOP_GRACE_SECONDS)
                self.deaths += 1
                worker.close()
                workers.remove(worker)
                worker.in_flight.popleft()
                yield worker, index, False, death_reason(worker.process.exitcode)

    def _abandoned(self, item: Item, worker: _Worker) -> None:
        """Tell ``on_abandon`` of the item a dead worker was working on."""
        if self.on_abandon is not None and worker.process.pid is not None:
            self.on_abandon(item, worker.process.pid)

    def _stop(self, workers: list[_Worker], items: Sequence[Item]) -> None:
        """End every worker: politely if idle, with SIGTERM (then SIGKILL) if busy."""
        for worker in workers:
            if not worker.in_flight:
                worker.send(None)
            elif worker.process.is_alive():
                worker.process.terminate()
        for worker in workers:
            worker.process.join(STOP_GRACE_SECONDS)
            if worker.process.is_alive():
                worker.process.kill()
                worker.process.join()
            pid = worker.process.pid
            if self.on_abandon is not None and pid is not None:
                for index in worker.in_flight:
                    self.on_abandon(items[index], pid)
            worker.close()
        for worker in workers:  # a sender blocked on a pipe is freed by its worker's end
            if worker.sender is not None:
                worker.sender.thread.join(STOP_GRACE_SECONDS)


class _Held(Sequence):  # type: ignore[type-arg]
    """The items :meth:`ProcessExecutor.map_stream` holds, by index, for :meth:`_stop`."""

    def __init__(self, held: dict[int, Any]) -> None:
        self.held = held

    def __getitem__(self, index: Any) -> Any:
        return self.held[index]

    def __len__(self) -> int:
        return len(self.held)


class _Sender:
    """Items sent to one worker's pipe by a thread of their own, in order, which closes the
    pipe when told to stop.

    Used for large items (a video's frames): sent from the parent's loop, one would fill the
    pipe while the worker is itself blocked sending its large result back, and neither would
    read.
    """

    def __init__(self, connection: Connection) -> None:
        self.connection = connection
        self.items: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            item = self.items.get()
            if item is _Sender:
                self.connection.close()
                return
            # A worker that died breaks the pipe: its sentinel reports the death.
            with contextlib.suppress(OSError, ValueError):
                self.connection.send(item)

    def send(self, item: Any) -> None:
        self.items.put(item)

    def close(self) -> None:
        """Close the pipe once the items queued are sent (or their pipe is broken)."""
        self.items.put(_Sender)
