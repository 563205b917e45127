"""``gsrwt rectify --scheduler``: the per-image work as tasks of a real Dask cluster.

Real ``dask.distributed.LocalCluster`` processes, real ``gsrwt`` subprocesses: outputs byte
for byte and the table as the worker-process pool gives them, a worker killed with SIGKILL
mid-batch costing nothing, Ctrl-C writing the table of what finished, an unreachable
scheduler and a missing Dask as one line with exit code 2.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest

from tests.helpers.cli import run_gsrwt, start_gsrwt
from tests.helpers.faults import (
    POSE,
    assert_clean_stderr,
    assert_table_is_the_record,
    make_photos,
    sha256_tree,
    stray_files,
    wait_for_outputs,
    wait_until_gone,
)
from tests.helpers.paths import SAMPLE_VIEWS as SAMPLES
from tests.helpers.tables import read_table

# Skipped only where the test extra is not installed; CI installs it and must run them.
distributed = (__import__("distributed") if os.environ.get("CI")
               else pytest.importorskip("distributed"))

from gsrwt_cli.batch.dask_executor import DaskExecutor  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    """A real local cluster of two single-threaded worker processes on the loopback."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as local, \
            distributed.Client(local, set_as_default=False) as client:
        yield local, client


@pytest.fixture(scope="module")
def mixed(tmp_path_factory) -> Path:
    """The sample views, and images that fail: undecodable, truncated, without parameters."""
    folder = tmp_path_factory.mktemp("mixed")
    for path in SAMPLES.iterdir():
        shutil.copy(path, folder / path.name)
    (folder / "broken.jpg").write_bytes(b"not an image")
    door = (SAMPLES / "door_p20_t-8_f800.jpg").read_bytes()
    (folder / "door_cut.jpg").write_bytes(door[: len(door) // 2])
    shutil.copy(SAMPLES / "door_p40_t-12_f700.jpg", folder / "unlisted.jpg")
    return folder


def rectify_mixed(mixed: Path, cwd: Path, *extra: str, env: dict | None = None):
    cwd.mkdir(exist_ok=True)
    args = ["rectify", str(mixed), "--sidecar", str(mixed / "views.csv"), "-o", "out", "-q",
            "-j", "2", *extra]
    return run_gsrwt(*args, cwd=cwd, env=env)


@pytest.mark.slow
def test_a_local_cluster_gives_the_process_pools_outputs_and_table(mixed, tmp_path):
    pool = rectify_mixed(mixed, tmp_path / "pool")
    dask = rectify_mixed(mixed, tmp_path / "dask", "--scheduler", "local")
    assert (pool.returncode, dask.returncode) == (1, 1), dask.stderr
    assert dask.stderr == pool.stderr  # the same per-image error lines
    assert dask.stderr.count("Error: ") == 3
    assert sha256_tree(tmp_path / "dask" / "out") == sha256_tree(tmp_path / "pool" / "out")


@pytest.mark.slow
def test_a_remote_scheduler_from_the_environment(mixed, tmp_path, cluster):
    local, _ = cluster
    pool = rectify_mixed(mixed, tmp_path / "pool")
    dask = rectify_mixed(mixed, tmp_path / "dask", env={"DASK_SCHEDULER_ADDRESS":
                                                        local.scheduler_address})
    assert dask.returncode == pool.returncode == 1, dask.stderr
    assert sha256_tree(tmp_path / "dask" / "out") == sha256_tree(tmp_path / "pool" / "out")


@pytest.mark.slow
def test_a_worker_killed_mid_batch_loses_nothing(tmp_path, cluster):
    local, client = cluster
    sources = make_photos(tmp_path / "in", 24)
    before = sha256_tree(tmp_path / "in")
    process = start_gsrwt("rectify", "in", *POSE, "-o", "out", "--scheduler",
                          local.scheduler_address, cwd=tmp_path, own_session=True)
    wait_for_outputs(tmp_path / "out", 2, process)
    victim = next(iter(client.run(os.getpid).values()))
    os.kill(victim, signal.SIGKILL)
    stdout, stderr = process.communicate(timeout=180)
    assert process.returncode == 0, stderr
    assert_clean_stderr(stderr)
    assert "24 ok, 0 skipped, 0 failed" in stderr
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    assert [Path(row["image"]).name for row in rows] == [p.name for p in sources]
    assert_table_is_the_record(rows, tmp_path / "out", sources)
    assert stray_files(tmp_path) == []  # the dead worker's temporary is gone too
    assert sha256_tree(tmp_path / "in") == before
    client.wait_for_workers(2, timeout=60)  # the nanny brought the worker back
    rerun = run_gsrwt("rectify", "in", *POSE, "-o", "out", "--scheduler",
                      local.scheduler_address, cwd=tmp_path)
    assert rerun.returncode == 0 and "0 ok, 24 skipped, 0 failed" in rerun.stderr


@pytest.mark.slow
def test_ctrl_c_cancels_the_tasks_and_writes_the_table_of_what_finished(tmp_path):
    sources = make_photos(tmp_path / "in", 120)  # so that Ctrl-C lands mid-batch
    process = start_gsrwt("rectify", "in", *POSE, "-o", "out", "-j", "2", "--scheduler", "local",
                          cwd=tmp_path, own_session=True)
    wait_for_outputs(tmp_path / "out", 3, process)
    os.killpg(process.pid, signal.SIGINT)  # the whole group, as a terminal's Ctrl-C does
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert_clean_stderr(stderr)
    assert "interrupted:" in stderr
    assert wait_until_gone(process.pid, 30), "the local cluster outlived the command"
    rows = read_table(tmp_path / "out" / "gsrwt.csv")
    statuses = [row["status"] for row in rows]
    assert set(statuses) <= {"ok", "interrupted"} and "interrupted" in statuses, statuses
    assert_table_is_the_record(rows, tmp_path / "out", sources)
    assert stray_files(tmp_path) == []


@pytest.mark.slow  # waits out the connect timeout
def test_an_unreachable_scheduler_is_one_line_exit_2(tmp_path):
    import socket

    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    result = run_gsrwt("rectify", str(SAMPLES / "door_p8_t-2_f1500.jpg"), *POSE, "-o", "out",
                       "--scheduler", f"tcp://127.0.0.1:{port}", cwd=tmp_path)
    assert result.returncode == 2
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: --scheduler tcp://127.0.0.1:{port}: cannot connect")
    assert not (tmp_path / "out" / "gsrwt.csv").exists()


@pytest.mark.parametrize("address", ["garbage", "tls://127.0.0.1:1", "foo://127.0.0.1:1"])
def test_a_scheduler_address_it_cannot_use_is_one_line_exit_2(tmp_path, address):
    """No port, a tls:// address without TLS settings, an unknown scheme: one line naming the
    address and why, exit 2, and nothing after it (no half-made Client's traceback from its
    finalizer, which waited 10 s to print one)."""
    result = run_gsrwt("rectify", str(SAMPLES / "door_p8_t-2_f1500.jpg"), *POSE, "-o", "out",
                       "--scheduler", address, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: --scheduler {address}: cannot connect to the scheduler ("), line
    assert not (tmp_path / "out" / "gsrwt.csv").exists()


def test_without_dask_the_scheduler_option_says_how_to_install_it(tmp_path):
    blocker = tmp_path / "blocker"  # an interpreter on which dask cannot be imported
    for name in ("dask", "distributed"):
        (blocker / name).mkdir(parents=True)
        (blocker / name / "__init__.py").write_text(
            f"raise ModuleNotFoundError(\"No module named '{name}'\", name='{name}')\n")
    result = run_gsrwt("rectify", str(SAMPLES / "door_p8_t-2_f1500.jpg"), *POSE, "-o", "out",
                       "--scheduler", "local", cwd=tmp_path, env={"PYTHONPATH": str(blocker)},
                       timeout=60)
    assert result.returncode == 2
    (line,) = result.stderr.splitlines()
    assert line.endswith("pip install 'gsrwt[dask]'"), line
    assert not (tmp_path / "out" / "gsrwt.csv").exists()


class Doubler:
    """A worker whose state counts its items; item 3 raises, as a bug in a task would."""

    def __init__(self, offset: int) -> None:
        self.offset, self.seen = offset, 0

    def __call__(self, item: int) -> tuple[int, int]:
        self.seen += 1
        if item == 3:
            raise RuntimeError("item three is bad")
        return item * 2 + self.offset, os.getpid()


def test_tasks_run_in_a_bounded_window_and_only_a_raising_item_is_an_error_row(cluster):
    _, client = cluster
    peak = []
    executor = DaskExecutor(client, Doubler, (1,), retries=1, window=5, chunk=3,
                            on_death=lambda item, reason: (-item, reason))
    results = {}
    for index, result in executor.map_unordered(list(range(60))):
        peak.append(sum(1 for key in client.futures if str(key).startswith("gsrwt-")))
        results[index] = result
    assert sorted(results) == list(range(60))
    assert results[3] == (-3, "task failed: RuntimeError: item three is bad")
    assert all(results[i][0] == 2 * i + 1 for i in results if i != 3)
    assert {pid for i, (_, pid) in results.items() if i != 3} <= set(
        client.run(os.getpid).values())
    # the window of 5 tasks (of 3 items), the failed task's items run again one per task,
    # and the task being handed over
    assert max(peak) <= 5 + 3 + 1


def test_closing_the_results_cancels_what_is_outstanding(cluster):
    _, client = cluster
    executor = DaskExecutor(client, Doubler, (0,), window=8, on_death=lambda i, r: None)
    results = executor.map_unordered(list(range(4, 500)))
    next(results)
    results.close()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(
            str(key).startswith("gsrwt-") for key in client.futures):
        time.sleep(0.05)
    assert not [key for key in client.futures if str(key).startswith("gsrwt-")]


if sys.platform != "linux":  # the kill and signal tests read /proc
    pytestmark = pytest.mark.skip("Linux only")


def _worker_settings(dask_worker) -> dict:
    """What a worker process runs with: its statistical profiler, memory and allocator."""
    import dask

    return {"profile": dask.config.get("distributed.worker.profile.enabled"),
            "arenas": os.environ.get("MALLOC_ARENA_MAX"),
            "profiling": dask_worker.periodic_callbacks.get("profile") is not None}


def test_the_local_cluster_runs_its_workers_without_the_dashboards_profiler():
    """The cluster gsrwt starts has no dashboard, so its workers sample no stacks (their
    other threads took a third of the CPU they took with the profiler, measured), and keep
    one malloc arena (freed image memory reused)."""
    from gsrwt_cli.batch.dask_executor import connect

    with connect("local", 2, 1) as client:
        settings = list(client.run(_worker_settings).values())
    assert len(settings) == 2
    assert all(found == {"profile": False, "arenas": "1", "profiling": False}
               for found in settings), settings


def test_ctrl_c_during_a_client_call_waits_for_it_and_logs_nothing(cluster, caplog):
    """Ctrl-C landing inside a Dask client call before its coroutine has started (here: the
    client's event loop held busy, as it is while the cluster starts or a batch of results
    arrives) made distributed log a ``NameError`` traceback (its ``sync`` cancels a future it
    has not yet made). gsrwt's stop waits until the call returns, then stops the batch."""
    import _thread
    import logging
    import threading

    from gsrwt_cli.cli.rectify import stop_on_signals

    _, client = cluster
    caplog.set_level(logging.ERROR)
    client.loop.add_callback(time.sleep, 0.6)  # the loop busy: the call's coroutine waits
    threading.Timer(0.2, _thread.interrupt_main, args=(signal.SIGINT,)).start()
    finished = []
    with pytest.raises(KeyboardInterrupt), stop_on_signals():
        finished.append(client.nthreads())  # a sync() call, interrupted while it waits
        time.sleep(5)  # the stop comes here, once the call has returned
    assert finished and sum(finished[0].values()) == 2
    errors = [record for record in caplog.records if record.levelno >= logging.ERROR]
    assert not errors, [record.getMessage() for record in errors]
