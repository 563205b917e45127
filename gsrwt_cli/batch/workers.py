"""The one shape of a batch's worker: its state built once per process, then called per job.

:class:`~gsrwt_cli.batch.executor.ProcessExecutor` (and the Dask executor's worker plugin)
builds a worker with ``in_own_process(*args)`` in each process it starts and calls it with
each job; ``rectify`` and ``estimate`` subclass :class:`ProcessWorker` with their state.
"""

from __future__ import annotations

from typing import Any, TypeVar

import cv2

from ..imaging.images import keep_freed_memory

W = TypeVar("W", bound="ProcessWorker")


class ProcessWorker:
    """A worker's per-process state. ``opencv_threads``: OpenCV's threads in this process
    (0: OpenCV's default), 1 where several worker processes share the cores."""

    def __init__(self, opencv_threads: int = 0) -> None:
        if opencv_threads:
            cv2.setNumThreads(opencv_threads)

    @classmethod
    def in_own_process(cls: type[W], *args: Any, **kwargs: Any) -> W:
        """A worker for a process of its own, tuned as only such a process may be
        (:func:`~gsrwt_cli.imaging.images.keep_freed_memory`)."""
        keep_freed_memory()
        return cls(*args, **kwargs)

    def __call__(self, job: Any) -> dict[str, Any]:
        raise NotImplementedError
