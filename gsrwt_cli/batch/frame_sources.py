"""The two kinds of stream ``gsrwt rectify`` takes, behind one interface: frames from a video
file or from a ROS bag's image topic (:class:`FrameSource`), and each frame's pose from a pose
log or from a bag's pose topic (:class:`FramePoses`).

The run loop (:mod:`.video_jobs`) knows only these two interfaces: it asks the source for its
frames (:class:`StreamFrame`, one at a time), the poses for each frame's view values, and
hands the warped frames to the output (a video, an image sequence, a bag).

Clocks: a frame's ``time`` is seconds from the source's first frame; ``absolute`` seconds on
the source's own clock (a video's ``pts x time_base``, a bag's header stamps); ``pts`` the
timestamp a video output gives it (in :attr:`FrameSource.time_base`) and ``stamp_ns`` the one
a bag output gives it (a bag's frames keep their header stamps).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..geometry.camera import Intrinsics
from ..geometry.rotations import PoseError, pose_from_rotation
from ..geometry.timeline import PoseGapError, PoseSample, Timeline
from ..inputs.pose_log import PoseLog
from ..inputs.records import merge_values
from ..inputs.videos import FrameFailure, VideoError, VideoReader
from .job_errors import JobError

if TYPE_CHECKING:  # a bag's modules only when a bag is read
    from ..imaging.yuv import Yuv420
    from ..inputs.bags import PoseSamples

#: A bag's frames as a video's: pts in microseconds from the first frame's stamp.
BAG_TIME_BASE = Fraction(1, 1_000_000)
#: The pose of a chain of static transforms holds at every moment.
_ALWAYS = 1e18


@dataclass(frozen=True)
class StreamFrame:
    """One frame of a stream: its ``index`` (from 0), ``time`` (seconds from the first
    frame), ``absolute`` (seconds on the source's clock), ``pts`` (a video output's
    timestamp, in the source's ``time_base``), ``stamp_ns`` (a bag output's, nanoseconds),
    and its ``pixels`` (BGR, or a video's YUV planes when its source was opened for them),
    or None with the ``error`` that made it unreadable."""

    index: int
    time: float | None
    absolute: float | None
    pts: int | None
    stamp_ns: int | None
    pixels: np.ndarray | Yuv420 | None
    error: str | None = None


class SourceEndedError(Exception):
    """The stream breaks off after the frames given (a video cut short, a bag damaged from
    a message on): one line, the source's last row."""


class FrameSource(Protocol):
    """Frames of a stream, decoded in this process, one at a time."""

    #: The frame rate (None: unknown) and the time base of :attr:`StreamFrame.pts`.
    rate: Fraction | None
    time_base: Fraction

    def frames(self) -> Iterator[StreamFrame]:
        """Every frame in order; raises :class:`SourceEndedError` after the last one given
        when the stream breaks off."""
        ...

    def close(self) -> None:
        """Let go of the file."""
        ...


class VideoSource:
    """A video file's frames (:class:`~gsrwt_cli.inputs.videos.VideoReader`); opening it
    raises :class:`~gsrwt_cli.inputs.videos.VideoError`. ``planes``: a frame decoded as 8-bit
    YUV 4:2:0 comes as its planes (:class:`~gsrwt_cli.imaging.yuv.Yuv420`), not as BGR."""

    def __init__(self, path: Path, max_pixels: float = math.inf, planes: bool = False) -> None:
        self.reader = VideoReader(path, max_pixels)
        self.rate = self.reader.info.rate
        self.time_base = self.reader.info.time_base
        self.planes = planes

    def frames(self) -> Iterator[StreamFrame]:
        frames = self.reader.frames(self.planes)
        while True:
            try:
                item = next(frames)
            except StopIteration:
                return
            except VideoError as error:
                raise SourceEndedError(str(error)) from None
            if isinstance(item, FrameFailure):
                yield StreamFrame(item.index, item.time, item.absolute, item.pts, None, None,
                                  item.reason)
            else:
                yield StreamFrame(item.index, item.time, item.absolute, item.pts, None,
                                  item.pixels)

    def close(self) -> None:
        self.reader.__exit__(None, None, None)


class BagSource:
    """An image topic's frames (:func:`~gsrwt_cli.inputs.bags.image_frames`): ``pts`` in
    microseconds from the first frame's stamp; a frame larger than ``max_pixels`` is its
    own error."""

    time_base = BAG_TIME_BASE

    def __init__(self, bag: Path, topic: str, max_pixels: float = math.inf) -> None:
        self.bag, self.topic, self.max_pixels = bag, topic, max_pixels
        self.rate: Fraction | None = None
        self._frames: Iterator[Any] | None = None

    def frames(self) -> Iterator[StreamFrame]:
        from ..inputs.bags import DamagedBagError, image_frames

        self._frames = image_frames(self.bag, self.topic)
        first: int | None = None
        while True:
            try:
                frame = next(self._frames)
            except StopIteration:
                return
            except DamagedBagError as error:
                raise SourceEndedError(str(error)) from None
            first = frame.stamp_ns if first is None else first
            pts = (frame.stamp_ns - first) // 1000
            pixels, error_text = frame.image, frame.error
            if pixels is not None and pixels.shape[0] * pixels.shape[1] > self.max_pixels:
                pixels, error_text = None, (f"frame {frame.index}: {pixels.shape[1]}x"
                                            f"{pixels.shape[0]} pixels, above "
                                            "--max-input-pixels")
            yield StreamFrame(frame.index, frame.time, frame.stamp_ns / 1e9, pts,
                              frame.stamp_ns, pixels, error_text)

    def close(self) -> None:
        if self._frames is not None:
            self._frames.close()  # type: ignore[attr-defined]


# --------------------------------------------------------------------------------------------
# Poses


class FramePoses(Protocol):
    #: The table's ``pose_source`` of the frames (``poses``, ``bag``, ``estimated``).
    pose_source: str

    def timeline(self) -> Timeline:
        """The samples' timeline (built once per run: :class:`CachedTimeline`)."""
        ...
    """Where each frame's pose comes from."""

    def values_at(self, frame: StreamFrame) -> tuple[dict[str, Any], str, str]:
        """The frame's view values, where they came from, and its ``focal_source``; raises
        :class:`~gsrwt_cli.batch.job_errors.JobError` for a frame without a pose."""
        ...


def focal_source_of(own: Mapping[str, Any], fallback: Mapping[str, Any],
                  camera: Mapping[str, Any]) -> str:
    """``poses`` (the pose file gives it), ``option``, or ``camera`` (a calibration file or
    the bag's camera_info)."""
    if {"focal", "fx"} & set(own):
        return "poses"
    if fallback.get("focal") is not None or fallback.get("fx") is not None:
        return "option"
    return "camera" if fallback.get("camera") or camera else "option"


def merged_values(own: dict[str, Any], defaults: Mapping[str, Any], fallback: Mapping[str, Any],
            camera: Mapping[str, Any]) -> dict[str, Any]:
    """The frame's values over the pose file's defaults, the options and, last, the bag's
    camera (whose focal length and principal point any other source replaces)."""
    given = set(own) | set(defaults) | set(fallback)
    under = {name: value for name, value in camera.items()
             if not (name in ("fx", "fy", "focal") and {"focal", "fx", "fy"} & given)
             and not (name in ("cx", "cy") and name in given)}
    return merge_values(own, defaults, fallback, under)


@dataclass(frozen=True)
class LogPoses:
    """Poses from a pose file (:class:`~gsrwt_cli.inputs.pose_log.PoseLog`), its ``time``
    seconds from the first frame (``relative``) or on the source's clock (``absolute``)."""

    log: PoseLog
    time_mode: str
    max_gap: float
    fallback: Mapping[str, Any]
    camera: Mapping[str, Any]
    pose_source: str = "poses"

    def timeline(self) -> Timeline:
        return self.log.timeline(self.max_gap)

    def values_at(self, frame: StreamFrame, timeline: Timeline | None = None
                  ) -> tuple[dict[str, Any], str, str]:
        timeline = timeline or self.timeline()
        moment = frame.absolute if self.time_mode == "absolute" else frame.time
        name = self.log.path.name
        where = f"{name} at frame {frame.index} ({moment:.6g} s)"
        try:
            at = timeline.at(float(moment))  # type: ignore[arg-type]
            pose = pose_from_rotation(at.rotation)
        except (PoseGapError, PoseError) as error:
            raise JobError(f"{name}: {error}") from None
        own = {**at.numbers, "pan": pose.pan, "tilt": pose.tilt, "roll": pose.roll}
        values = merged_values(own, self.log.defaults, self.fallback, self.camera)
        return values, where, focal_source_of({**at.numbers, **self.log.defaults},
                                            self.fallback, self.camera)


class CachedTimeline:
    """A :class:`FramePoses` with its timeline built once (the pose file's, the topic's, or
    the estimates')."""

    def __init__(self, poses: FramePoses) -> None:
        self.poses = poses
        self.pose_source = poses.pose_source
        self.timeline = poses.timeline()
        #: Each frame's own estimate's confidence, by index (an estimated video's; else none).
        self.confidence: dict[int, float] = getattr(poses, "confidence", {})

    def values_at(self, frame: StreamFrame) -> tuple[dict[str, Any], str, str]:
        return self.poses.values_at(frame, self.timeline)


@dataclass(frozen=True)
class TopicPoses:
    """Poses from a bag's pose topic (:class:`~gsrwt_cli.inputs.bags.PoseSamples`), matched
    to each frame's header stamp. Samples with the same stamp: the last in the bag's order
    counts. A chain of static transforms holds at every moment."""

    samples: PoseSamples
    topic: str
    max_gap: float
    fallback: Mapping[str, Any]
    camera: Mapping[str, Any]
    pose_source: str = "bag"

    def timeline(self) -> Timeline:
        stamps = self.samples.stamps_ns
        origin = int(stamps[0])
        last: dict[int, int] = {}
        for row, stamp in enumerate(stamps):  # sorted stably: the last of equal stamps wins
            last[int(stamp)] = row
        samples = [PoseSample((stamp - origin) / 1e9, self.samples.world_from_camera[row])
                   for stamp, row in last.items()]
        return _OffsetTimeline(samples, _ALWAYS if self.samples.constant else self.max_gap,
                               origin)

    def values_at(self, frame: StreamFrame, timeline: Timeline | None = None
                  ) -> tuple[dict[str, Any], str, str]:
        timeline = timeline or self.timeline()
        assert isinstance(timeline, _OffsetTimeline) and frame.stamp_ns is not None
        moment = (frame.stamp_ns - timeline.origin_ns) / 1e9
        where = f"{self.topic} at frame {frame.index} (stamp {frame.stamp_ns} ns)"
        try:
            at = timeline.at(moment)
            pose = pose_from_rotation(at.rotation)
        except PoseGapError as error:
            text = (f"no pose on {self.topic} within {error.max_gap:g} s of the frame's stamp "
                    f"(the nearest sample is {abs(error.time - error.nearest):.6g} s away)"
                    if error.nearest is not None else f"no pose on {self.topic}")
            raise JobError(text) from None
        except PoseError as error:
            raise JobError(f"{self.topic} at frame {frame.index}: {error}") from None
        own = {"pan": pose.pan, "tilt": pose.tilt, "roll": pose.roll}
        values = merged_values(own, {}, self.fallback, self.camera)
        return values, where, focal_source_of({}, self.fallback, self.camera)


class _OffsetTimeline(Timeline):
    """A timeline whose times are seconds from ``origin_ns`` (a stamp in nanoseconds: whole
    stamps as seconds in a float would keep only a quarter of a microsecond)."""

    def __init__(self, samples: list[PoseSample], max_gap: float, origin_ns: int) -> None:
        super().__init__(samples, max_gap)
        self.origin_ns = origin_ns


def camera_values(intrinsics: Intrinsics) -> dict[str, Any]:
    """A camera (a bag's ``camera_info``) as the view values a record gives: ``fx``, ``fy``,
    ``cx``, ``cy``, ``skew``, ``width``, ``height`` and the lens (``distortion_model`` and
    its coefficients by name)."""
    values: dict[str, Any] = {"fx": intrinsics.fx, "fy": intrinsics.fy}
    for name in ("cx", "cy", "width", "height"):
        if getattr(intrinsics, name) is not None:
            values[name] = getattr(intrinsics, name)
    if intrinsics.skew:
        values["skew"] = intrinsics.skew
    if intrinsics.lens is not None:
        values["distortion_model"] = intrinsics.lens.model
        values.update(dict(intrinsics.lens.coefficients))
    return values

