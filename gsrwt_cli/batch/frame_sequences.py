"""A video's frames for the commands that look at pixels one frame at a time (``params``,
``estimate``, ``lines``, ``match``, ``track`` on a video): each decoded frame with the view
values of its moment, and its canonical (frontal) view.

Decoded once, in this process, one frame at a time
(:class:`~gsrwt_cli.batch.frame_sources.VideoSource`): memory holds the frame being worked on,
never the video. Each frame's pose is the pose file's at its time (slerp:
:class:`~gsrwt_cli.geometry.timeline.Timeline`), as ``gsrwt rectify VIDEO --poses`` finds it.
A frame the decoder refuses, or without a pose within ``max_gap``, comes with its ``error``;
a file cut short ends with one more item, after its last frame, whose ``error`` says so.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..api.rectify import rectify_image, view_for_image
from ..geometry.camera import View
from ..inputs.pose_log import PoseLog
from ..inputs.records import RecordError, view_from_values
from ..vision.edges import pixels8
from .canonical_views import CanonicalView
from .frame_sources import CachedTimeline, LogPoses, SourceEndedError, VideoSource
from .job_errors import JobError


@dataclass(frozen=True)
class SequenceFrame:
    """One frame of a video: its ``index`` (from 0; for the end of a file cut short, the
    index the next frame would have had), ``time`` (seconds from the first frame; None when
    unknown), ``pixels`` (BGR, 8 bits; None for a failure), its view ``values`` (None
    without a pose file or pose options) and where they came from, or the ``error`` that
    makes it an error row."""

    index: int
    time: float | None
    pixels: np.ndarray | None = None
    values: Mapping[str, Any] | None = None
    where: str = ""
    error: str | None = None
    #: True for the item after the last frame of a file cut short (not a frame of its own).
    end: bool = False

    def view(self) -> View:
        """The frame's :class:`View` (its size from its pixels); raises
        :class:`~gsrwt_cli.inputs.records.RecordError` for values that make none."""
        assert self.values is not None and self.pixels is not None
        height, width = self.pixels.shape[:2]
        values = dict(self.values)
        if values.get("width") in (None, "") and values.get("cx") in (None, ""):
            values["width"], values["height"] = width, height
        return view_for_image(view_from_values(values, self.where), width, height)


def sequence_frames(path: Path, poses: PoseLog | None = None, *, time_mode: str = "relative",
                    max_gap: float = 0.5, fallback: Mapping[str, Any] | None = None,
                    max_pixels: float = math.inf,
                    frames: tuple[int, int | None, int] | None = None
                    ) -> Iterator[SequenceFrame]:
    """Every frame of the video at ``path``, in presentation order, with its view values:
    the pose file's at the frame's time (``time_mode``: ``relative`` or ``absolute``) merged
    over ``fallback``, or ``fallback`` alone when there is no pose file and it gives a pose
    (every frame the same view), else None. ``frames``: ``(start, stop, step)``, only the
    frames of that slice of indices (every frame is still decoded up to ``stop``, where
    decoding ends). Raises :class:`~gsrwt_cli.inputs.videos.VideoError` when the file is no
    video at all.

    The frames and their poses are ``rectify VIDEO``'s own
    (:class:`~.frame_sources.VideoSource`, :class:`~.frame_sources.LogPoses`)."""
    start, stop, step = frames or (0, None, 1)
    fallback = dict(fallback or {})
    fixed = None
    if poses is None and {"pan", "tilt", "roll"} & set(fallback):
        fixed = fallback
    looked_up = (CachedTimeline(LogPoses(poses, time_mode, max_gap, fallback, {}))
                 if poses is not None else None)
    source = VideoSource(path, max_pixels)
    try:
        stream = source.frames()
        count = 0
        while True:
            try:
                item = next(stream)
            except StopIteration:
                return
            except SourceEndedError as error:
                yield SequenceFrame(count, None, error=str(error), end=True)
                return
            count = item.index + 1
            if stop is not None and item.index >= stop:
                return
            if item.index < start or (item.index - start) % step:
                continue
            if item.pixels is None:
                yield SequenceFrame(item.index, item.time, error=item.error)
                continue
            if looked_up is None:
                yield SequenceFrame(item.index, item.time, item.pixels, fixed, "options")
                continue
            try:
                values, where, _ = looked_up.values_at(item)
            except JobError as error:
                yield SequenceFrame(item.index, item.time, error=str(error))
                continue
            yield SequenceFrame(item.index, item.time, item.pixels, values, where)
    finally:
        source.close()


def frame_canonical_view(video: Path, frame: SequenceFrame) -> CanonicalView:
    """The frame's frontal view, as ``lines`` and ``match`` see a still image: rectified
    with its view (the map back to its pixels kept), or the frame as it is when it has no
    view values. Raises :class:`ValueError` (a
    :class:`~gsrwt_cli.inputs.records.RecordError` among them) for a view that cannot be
    rectified."""
    assert frame.pixels is not None
    image = pixels8(frame.pixels)
    if frame.values is None:
        return CanonicalView(video, image, None)
    try:
        view = frame.view()
    except RecordError as error:
        raise ValueError(str(error)) from None
    frontal, info = rectify_image(image, view)
    units = None if view.distance is None else view.distance / view.focal
    return CanonicalView(video, frontal, info.pixel_map, (image.shape[1], image.shape[0]), units)
