"""A video's frames worked on by worker processes, their rows handed back in frame order
(``gsrwt estimate VIDEO -j N``).

The main process decodes (:func:`~gsrwt_cli.batch.frame_sequences.sequence_frames`); each
frame goes to a worker (:class:`FrameRows`: the command's work, a picklable callable, built
once per process) through
:meth:`~gsrwt_cli.batch.executor.ProcessExecutor.map_stream`, at most
:data:`~gsrwt_cli.batch.executor.ITEMS_IN_FLIGHT` frames in flight per worker and a bounded
number waiting to be put back in order. With one process the work is done here, frame by
frame. Every failure of a frame's work, and a worker that dies on it, is that frame's
``error`` row.
"""

from __future__ import annotations

import multiprocessing
import warnings
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .executor import ProcessExecutor
from .frame_sequences import SequenceFrame
from .job_errors import error_text
from .workers import ProcessWorker

Row = dict[str, Any]
#: The work of one frame: its rows (without ``frame``, ``time``), each with its ``status``.
FrameWork = Callable[[SequenceFrame], list[Row]]


def rows_of(frame: SequenceFrame, work: FrameWork) -> list[Row]:
    """The frame's rows: its ``error`` row when it came with one (decoding, its pose) or
    when its work fails, else what its work gives."""
    if frame.error is not None:
        return [{"status": "error", "error": frame.error}]
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return work(frame)
    except Exception as failure:  # every failure of one frame is that frame's row
        return [{"status": "error", "error": error_text(failure)}]


class FrameRows(ProcessWorker):
    """One worker: the command's work of a frame (:func:`rows_of`)."""

    def __init__(self, work: FrameWork, opencv_threads: int = 0) -> None:
        super().__init__(opencv_threads)
        self.work = work

    def __call__(self, frame: SequenceFrame) -> list[Row]:  # type: ignore[override]
        return rows_of(frame, self.work)


def _died(frame: SequenceFrame, reason: str) -> list[Row]:
    return [{"status": "error", "error": reason}]


def rows_in_order(frames: Iterator[SequenceFrame], work: FrameWork, processes: int = 1,
                  context: multiprocessing.context.BaseContext | None = None
                  ) -> Iterator[tuple[SequenceFrame, list[Row]]]:
    """Each frame (its pixels dropped) and its rows, in frame order: worked on by
    ``processes`` worker processes, or here with one."""
    if processes <= 1:
        for frame in frames:
            yield replace(frame, pixels=None), rows_of(frame, work)
        return
    heads: dict[int, SequenceFrame] = {}

    def sent() -> Iterator[SequenceFrame]:
        for number, frame in enumerate(frames):
            heads[number] = replace(frame, pixels=None)
            yield frame

    executor: ProcessExecutor[SequenceFrame, list[Row]] = ProcessExecutor(
        FrameRows.in_own_process, (work, 1), processes, on_death=_died,
        context=context or multiprocessing.get_context())
    waiting: dict[int, list[Row]] = {}
    following = 0
    results = executor.map_stream(sent())
    try:
        for number, rows in results:
            waiting[number] = rows
            while following in waiting:
                yield heads.pop(following), waiting.pop(following)
                following += 1
    finally:
        results.close()


@dataclass(frozen=True)
class EstimateFrames:
    """``estimate``'s work on a frame (picklable, for the workers): the pose from its lines,
    as a sidecar row with its evidence. ``options``:
    :class:`~gsrwt_cli.batch.estimate_jobs.EstimateOptions`; ``own``: the options' camera
    values (``--focal``, ``--camera``...; none: the focal length is estimated)."""

    options: Any
    own: Mapping[str, Any]

    @property
    def source(self) -> str:
        """Where the focal length comes from: ``option``, ``camera`` or ``estimated``."""
        if any(self.own.get(name) not in (None, "") for name in ("focal", "fx")):
            return "option"
        return "camera" if self.own.get("camera") else "estimated"

    def __call__(self, frame: SequenceFrame) -> list[Row]:
        from ..api.estimate import EstimateError, estimate_pose
        from ..inputs.records import view_from_values
        from .estimate_jobs import checked, estimate_row, estimated_values

        assert frame.pixels is not None
        height, width = frame.pixels.shape[:2]
        values = {**self.own, "pan": 0, "tilt": 0}
        if values.get("width") in (None, "") and values.get("cx") in (None, ""):
            values["width"], values["height"] = width, height
        camera, principal_point, source = None, None, self.source
        if source != "estimated":
            camera = view_from_values(values, "options").intrinsics
        elif self.own.get("cx") not in (None, ""):
            view = view_from_values({**values, "focal": 1.0}, "options")
            principal_point = (view.cx, view.cy)
        estimate = estimate_pose(frame.pixels, camera, principal_point=principal_point,
                                 wall=self.options.wall)
        row = estimate_row(estimate, source)
        try:
            checked(estimate, self.options)
        except EstimateError as error:
            return [{**row, "status": "error", "error": str(error)}]
        row.update(estimated_values(estimate, camera, width, height, principal_point))
        return [{**row, "status": "ok"}]
