"""Run the per-image work as tasks of a Dask cluster: the :class:`~.executor.Executor` shape
over ``dask.distributed``.

Imported only when ``--scheduler`` asks for it (Dask is an optional extra,
``pip install 'gsrwt[dask]'``). Each worker process builds its per-worker state once, with
the same ``make_worker(*args)`` as :class:`~.executor.ProcessExecutor`, in a worker plugin
(so a worker that the nanny restarts after a crash builds it again); each item is one task,
``work(item)`` on whatever worker the scheduler picks. Items and results are small (jobs
carry paths or URLs, rows are values): image bytes never go through the scheduler or the
client.

- Tasks are submitted in a bounded window (``window`` in flight at most, refilled as they
  complete), so a million-image batch is never a million futures in the client; a big
  batch puts up to :data:`MAX_CHUNK` items in one task (run one after another).
- A worker that dies mid-task costs nothing: the scheduler runs the task again on another
  worker, up to its ``distributed.scheduler.allowed-failures`` (``retries`` for the local
  cluster this module starts). A task that still fails (or raises ``retries`` times) is
  reported through ``on_death`` with the reason, never lost.
- Closing the generator (Ctrl-C in the caller) cancels every outstanding task.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Generic, TypeVar

import dask
import distributed
from distributed import Client, LocalCluster, WorkerPlugin, as_completed, get_worker

Item = TypeVar("Item")
Result = TypeVar("Result")

#: Seconds to wait for a scheduler before giving up (an unreachable address fails fast).
CONNECT_TIMEOUT_SECONDS = 5.0
#: Tasks in flight per worker thread: enough to hide the scheduler's latency, few enough
#: that the client holds a bounded number of futures.
TASKS_PER_THREAD = 8
#: The fewest tasks kept in flight, whatever the cluster's size.
MIN_WINDOW = 16
#: The most items one task runs (one after another, in the same worker): with many small
#: images, the scheduler's cost of a task (a few ms on a loaded 2-core machine) is shared.
MAX_CHUNK = 8
#: Items per worker thread from which tasks take several items: below it, one item per
#: task, so that the last tasks of a batch of big images end together (a two-image task
#: left running alone cost 10 % of a 32-image batch of 12 MP images, measured).
CHUNK_AFTER = 64
#: Seconds to wait, after cancelling, for the tasks that were running to end.
STOP_GRACE_SECONDS = 30.0


class SchedulerError(Exception):
    """The scheduler cannot be reached (or the local cluster cannot start); names it."""


class _WorkerState(WorkerPlugin):
    """Builds ``make_worker(*args)`` once in each worker process, for the tasks of one run."""

    def __init__(self, name: str, make_worker: Callable[..., Callable[[Any], Any]],
                 args: tuple) -> None:
        self.name = name
        self.make_worker = make_worker
        self.args = args
        self.work: Callable[[Any], Any] | None = None

    def setup(self, worker: distributed.Worker) -> None:
        self.work = self.make_worker(*self.args)

    def teardown(self, worker: distributed.Worker) -> None:
        self.work = None


def _run_items(plugin_name: str, items: list[Any]) -> list[Any]:
    """The task of a few items: the worker's own callable applied to each in turn."""
    state = get_worker().plugins[plugin_name]
    if state.work is None:  # a plugin registered while this worker was starting
        state.setup(get_worker())
    return [state.work(item) for item in items]


def _running(prefix: str, dask_worker: distributed.Worker) -> int:
    """How many tasks whose keys start with ``prefix`` this worker is still running
    (cancelled tasks run to their end: a thread cannot be stopped)."""
    state = dask_worker.state
    tasks = set(state.executing) | set(state.long_running)
    return sum(1 for task in tasks if str(task.key).startswith(prefix))


def _failure_reason(future: distributed.Future) -> str:
    """``worker died: ... (the task was tried N times)`` or ``task failed: Type: text``."""
    if future.status == "cancelled":
        return "task cancelled: the scheduler lost it"
    error = future.exception()
    if isinstance(error, distributed.KilledWorker):
        return "worker died: its worker was lost each time the task ran (KilledWorker)"
    text = " ".join(str(error).split())
    return f"task failed: {type(error).__name__}: {text}" if text else (
        f"task failed: {type(error).__name__}")


class DaskExecutor(Generic[Item, Result]):
    """Items as tasks on the cluster ``client`` talks to, results as they complete.

    ``on_death(item, reason)`` makes the result of an item whose task failed for good (its
    workers died, or it raised); ``on_close(items)`` runs in the client when the map ends,
    however it ends (the caller removes what dead workers left half-written).
    ``retries``: how many times a task that raised is run again. ``send(item)`` is what a
    task is given instead of the item, and ``receive(item, result)`` what its result becomes
    (absolute paths for workers elsewhere, and back). ``chunk``: items per task (default:
    1 for small batches, up to :data:`MAX_CHUNK` for big ones); a task of several items
    that fails is run again as one task per item, so only the failing item fails.
    """

    def __init__(
        self,
        client: Client,
        make_worker: Callable[..., Callable[[Item], Result]],
        args: tuple,
        *,
        on_death: Callable[[Item, str], Result],
        on_close: Callable[[Sequence[Item]], None] | None = None,
        retries: int = 2,
        window: int | None = None,
        send: Callable[[Item], Any] | None = None,
        receive: Callable[[Item, Any], Result] | None = None,
        chunk: int | None = None,
    ) -> None:
        self.client = client
        self.make_worker = make_worker
        self.args = args
        self.on_death = on_death
        self.on_close = on_close
        self.retries = retries
        self.window = window
        self.send = send
        self.receive = receive
        self.chunk = chunk

    def _window(self) -> int:
        if self.window is not None:
            return max(1, self.window)
        threads = sum(self.client.nthreads().values()) or 1
        return max(MIN_WINDOW, TASKS_PER_THREAD * threads)

    def _wait_until_stopped(self, prefix: str) -> None:
        """Wait (up to :data:`STOP_GRACE_SECONDS`) until no worker runs a task of ours, so
        that what they wrote is on record before the caller rows what was not done."""
        deadline = time.monotonic() + STOP_GRACE_SECONDS
        while time.monotonic() < deadline:
            try:
                running = self.client.run(_running, prefix, on_error="ignore")
            except Exception:
                return
            if not any(isinstance(count, int) and count for count in running.values()):
                return
            time.sleep(0.05)

    def _chunk(self, count: int) -> int:
        """Items per task: 1 for batches under :data:`CHUNK_AFTER` items per worker thread,
        then up to :data:`MAX_CHUNK`."""
        if self.chunk is not None:
            return max(1, self.chunk)
        threads = sum(self.client.nthreads().values()) or 1
        return max(1, min(MAX_CHUNK, count // (CHUNK_AFTER * threads)))

    def map_unordered(self, items: Sequence[Item]) -> Iterator[tuple[int, Result]]:
        """``(index, result)`` for every item, as their tasks complete."""
        if not items:
            return
        run = uuid.uuid4().hex[:12]
        plugin = f"gsrwt-{run}"
        self.client.register_plugin(_WorkerState(plugin, self.make_worker, self.args),
                                    name=plugin)
        pending = iter(range(len(items)))
        in_flight: dict[distributed.Future, list[int]] = {}
        window, chunk = self._window(), self._chunk(len(items))
        serial = itertools.count()

        def submit_groups(groups: list[list[int]]) -> list[distributed.Future]:
            if not groups:
                return []
            futures = self.client.map(
                _run_items, [plugin] * len(groups),
                [[self.send(items[i]) if self.send else items[i] for i in group]
                 for group in groups],
                key=[f"gsrwt-{run}-{next(serial)}" for _ in groups], retries=self.retries,
                pure=False,
            )
            in_flight.update(zip(futures, groups))
            return futures

        def submit(count: int) -> list[distributed.Future]:
            groups = []
            for _ in range(count):
                group = list(itertools.islice(pending, chunk))
                if not group:
                    break
                groups.append(group)
            return submit_groups(groups)

        try:
            completed = as_completed(submit(window), loop=self.client.loop)
            for future in completed:
                indices = in_flight.pop(future)
                results: list[tuple[int, Result]] = []
                if future.status == "finished":
                    for index, result in zip(indices, future.result()):
                        if self.receive is not None:
                            result = self.receive(items[index], result)
                        results.append((index, result))
                elif len(indices) > 1:  # each item alone, so only a failing one fails
                    for more in submit_groups([[index] for index in indices]):
                        completed.add(more)
                else:
                    results.append((indices[0],
                                    self.on_death(items[indices[0]], _failure_reason(future))))
                future.release()
                if len(in_flight) <= window // 2:  # refill in batches: fewer round trips
                    for more in submit(window - len(in_flight)):
                        completed.add(more)
                yield from results
        finally:
            if in_flight:
                with contextlib.suppress(Exception):
                    self.client.cancel(list(in_flight), force=True)
                in_flight.clear()
                self._wait_until_stopped(f"gsrwt-{run}-")
            with contextlib.suppress(Exception):
                self.client.unregister_worker_plugin(plugin)
            if self.on_close is not None:
                self.on_close(items)


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """SIGINT ignored while the local cluster's processes start, so that they ignore it too
    (a terminal's Ctrl-C reaches the whole process group; the client stops the tasks)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, saved)


def _reach(address: str) -> None:
    """Open and close one connection to the scheduler at ``address``, with the security
    settings a :class:`Client` would use, or raise :class:`SchedulerError` saying why not.

    A ``Client`` that fails to connect stays half-made: its finalizer waits 10 s and prints
    a traceback long after our error line. An address it could not use (no port, a
    ``tls://`` address without TLS settings, nobody listening) is found here instead,
    within :data:`CONNECT_TIMEOUT_SECONDS`, and no ``Client`` is made."""
    from distributed import client as client_module
    from distributed.comm import connect as open_comm
    from distributed.security import Security

    loader = getattr(client_module, "_maybe_call_security_loader", None)  # as Client does
    security = (loader(address) if loader is not None else None) or Security()
    arguments = security.get_connection_args("client")
    if address.lower().startswith("tls://") and arguments.get("ssl_context") is None:
        raise SchedulerError("cannot connect to the scheduler (a tls:// address needs Dask's "
                             "TLS settings: distributed.comm.tls.ca-file, .client.cert, "
                             ".client.key)")

    async def reach() -> None:
        comm = await open_comm(address, timeout=CONNECT_TIMEOUT_SECONDS, **arguments)
        await comm.close()

    try:
        asyncio.run(reach())
    except Exception as error:  # ValueError (no port), OSError, TimeoutError, TypeError...
        reason = " ".join(str(error).split()) or type(error).__name__
        raise SchedulerError(f"cannot connect to the scheduler ({reason})") from None


@contextlib.contextmanager
def connect(address: str, workers: int, retries: int) -> Iterator[Client]:
    """A client of the scheduler at ``address``, or of a :class:`LocalCluster` of ``workers``
    single-threaded worker processes for ``local``; closed (the local cluster stopped) at the
    end. Raises :class:`SchedulerError` naming the address when it cannot be reached.

    For the local cluster, a task whose worker dies is run again up to ``retries`` times
    (``distributed.scheduler.allowed-failures``); a remote scheduler keeps its own setting.
    """
    with contextlib.ExitStack() as stack:
        if address == "local":
            stack.enter_context(dask.config.set({
                "distributed.scheduler.allowed-failures": retries,
                # Tasks run in a thread of the worker: one malloc arena for the process keeps
                # freed image memory for the next image (imaging.keep_freed_memory), as in
                # the main thread of a pool's worker, instead of fresh pages per image.
                "distributed.nanny.pre-spawn-environ.MALLOC_ARENA_MAX": 1,
                # No dashboard, so nothing reads the workers' statistical profile (a stack
                # sample every 10 ms) or their system monitor; the event loop's tick is
                # only a health check. Off or slowed, the workers' other threads took 3 ms
                # of CPU per 12 MP image instead of 10 (measured), and images 5 % less time.
                "distributed.worker.profile.enabled": False,
                "distributed.admin.system-monitor.interval": "2s",
                "distributed.admin.tick.interval": "1s",
            }))
            try:
                with _sigint_ignored():  # inherited: Ctrl-C is the client's to handle
                    cluster = stack.enter_context(LocalCluster(
                        n_workers=workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, host="127.0.0.1",
                    ))
            except Exception as error:
                raise SchedulerError(f"cannot start a local cluster ({error})") from None
            target: Any = cluster
        else:
            _reach(address)
            target = address
        try:
            client = stack.enter_context(Client(target, timeout=CONNECT_TIMEOUT_SECONDS,
                                                set_as_default=False))
        except (OSError, TimeoutError, ValueError) as error:
            reason = " ".join(str(error).split()) or type(error).__name__
            raise SchedulerError(f"cannot connect to the scheduler ({reason})") from None
        yield client


def worker_processes(client: Client) -> list[int]:
    """The process ids of the cluster's workers (for tests that kill one)."""
    return sorted(client.run(os.getpid).values())
