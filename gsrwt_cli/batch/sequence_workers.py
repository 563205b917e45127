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
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..geometry.rotations import PoseError, pose_from_rotation, rotation_from_pose
from ..geometry.smoothing import one_wall, smooth_samples
from ..geometry.timeline import PoseGapError, PoseSample, Timeline
from .executor import ProcessExecutor
from .frame_sequences import SequenceFrame
from .frame_sources import StreamFrame, focal_source_of, merged_values
from .job_errors import JobError, error_text
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
        from ..api.estimate import EstimateError
        from ..inputs.records import view_from_values
        from .estimate_jobs import (
            checked,
            estimate_as_given,
            estimate_row,
            estimated_values,
            without_guides,
        )

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
        # as a photo is: checked for a lens where none is known (no camera, or a focal
        # length given alone), whatever the check costs
        estimate = estimate_as_given(frame.pixels, camera, source, self.own, principal_point,
                                     self.options)
        row = estimate_row(estimate, source)
        try:
            checked(estimate, self.options)
        except EstimateError as error:
            return [{**row, "status": "error", "error": without_guides(str(error))}]
        row.update(estimated_values(estimate, camera, width, height, principal_point))
        return [{**row, "status": "ok"}]


@dataclass
class EstimatedPoses:
    """Poses estimated from each frame's own lines (``rectify VIDEO --auto``): a first pass
    over the video (``frames``: a fresh iterator of its frames, with pixels) estimates every
    frame's pose with ``work`` (:class:`~gsrwt_cli.batch.sequence_workers.EstimateFrames`)
    on ``processes`` workers; the estimates it accepts, all turned to one wall
    (:func:`~gsrwt_cli.geometry.smoothing.one_wall`), are the samples of a timeline,
    smoothed over ``smooth`` seconds when above 0 (:func:`~gsrwt_cli.geometry.smoothing.
    smooth_samples`, weighted by their confidence). A frame whose own estimate was refused
    takes the pose interpolated between the accepted ones around it, as a pose file's frame
    between two samples, if one is within ``max_gap`` seconds; else it is an error row that
    gives its own estimate's reason. ``fallback``: the view options (the focal length, if
    given, is the estimates').

    :meth:`timeline` runs the first pass; :attr:`confidence` and :attr:`refused` then hold
    each frame's own estimate's confidence, or why it was refused, by frame index.
    """

    frames: Callable[[], Iterator[Any]]
    work: Any
    smooth: float
    max_gap: float
    fallback: Mapping[str, Any]
    processes: int = 1
    context: Any = None
    camera: Mapping[str, Any] = field(default_factory=dict)
    pose_source: str = "estimated"
    confidence: dict[int, float] = field(default_factory=dict)
    refused: dict[int, str] = field(default_factory=dict)

    def timeline(self) -> Timeline:

        accepted: list[tuple[float, float, float, float, dict[str, float]]] = []
        for frame, rows in rows_in_order(self.frames(), self.work, self.processes,
                                         self.context):
            row = rows[0]
            if getattr(frame, "end", False) or frame.time is None:
                continue
            if row.get("status") != "ok":
                self.refused[frame.index] = str(row.get("error") or "no estimate")
                continue
            self.confidence[frame.index] = float(row["confidence"])
            numbers = ({"focal": float(row["focal"])} if row.get("focal_source") == "estimated"
                       and row.get("focal") not in (None, "") else {})
            accepted.append((float(frame.time), float(row["pan"]), float(row["tilt"]),
                             float(row["roll"]), numbers))
        pans = one_wall([pan for _, pan, _, _, _ in accepted])
        samples = [PoseSample(time, rotation_from_pose(pan, tilt, roll), numbers)
                   for (time, _, tilt, roll, numbers), pan in zip(accepted, pans)]
        weights = list(self.confidence.values())
        if self.smooth > 0:
            samples = smooth_samples(samples, self.smooth, weights)
        return Timeline(samples, self.max_gap)

    def values_at(self, frame: StreamFrame, timeline: Timeline | None = None
                  ) -> tuple[dict[str, Any], str, str]:
        timeline = timeline or self.timeline()
        where = f"the estimate at frame {frame.index} ({frame.time:.6g} s)"
        try:
            at = timeline.at(float(frame.time))  # type: ignore[arg-type]
            pose = pose_from_rotation(at.rotation)
        except PoseGapError as error:
            own = self.refused.get(frame.index, "no estimate")
            nearest = ("no frame's estimate was accepted" if error.nearest is None else
                       f"the nearest accepted estimate is {abs(error.time - error.nearest):.6g}"
                       f" s away (--max-pose-gap {error.max_gap:g})")
            raise JobError(f"{own}; {nearest}") from None
        except PoseError as error:
            raise JobError(f"frame {frame.index}: {error}") from None
        own_values = {**at.numbers, "pan": pose.pan, "tilt": pose.tilt, "roll": pose.roll}
        values = merged_values(own_values, {}, self.fallback, self.camera)
        source = "estimated" if "focal" in at.numbers else focal_source_of({}, self.fallback,
                                                                        self.camera)
        return values, where, source
