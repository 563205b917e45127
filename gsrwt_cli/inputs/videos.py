"""Video files as inputs: their frames, each with its index, its timestamp and its pixels.

Decoded by PyAV (FFmpeg's libraries; ``pip install 'gsrwt[video]'``), imported only when a
video is read. Every container and codec FFmpeg reads works; :data:`VIDEO_EXTENSIONS` are the
names ``gsrwt rectify`` takes for a video.

A frame's ``time`` is seconds from the first frame (``pts * time_base`` less the first
frame's); ``absolute`` is the container's own clock (``pts * time_base``). Packets are
decoded one at a time, so that a packet the decoder refuses costs only its frame
(:class:`FrameFailure`, yielded in its place), and the end of the stream is checked against
the duration the container's header announced: a file cut short ends with
:class:`VideoTruncatedError` after the frames it holds.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..base.messages import one_line

if TYPE_CHECKING:  # cv2 and the pixel map only when a frame's planes are warped
    from ..imaging.yuv import Yuv420

#: File name extensions of videos (``gsrwt rectify`` reads these as videos).
VIDEO_EXTENSIONS = (".mp4", ".mkv", ".avi", ".mov", ".webm", ".m4v")


class VideoError(Exception):
    """A video that cannot be read at all (no such file, no video stream, not a video)."""


class VideoTruncatedError(VideoError):
    """The stream ends before the container says it does, or the demuxer fails mid-file."""


def is_video_name(name: str | Path) -> bool:
    """Whether a file name ends in one of :data:`VIDEO_EXTENSIONS` (any case)."""
    return Path(name).suffix.lower() in VIDEO_EXTENSIONS


def import_av() -> Any:
    """PyAV, or :class:`VideoError` saying how to install it."""
    try:
        import av
    except ImportError as error:
        raise VideoError(f"reading videos needs PyAV ({error.msg}); install it with "
                         "pip install 'gsrwt[video]'") from None
    return av


@dataclass(frozen=True)
class VideoFrame:
    """One decoded frame: its ``index`` (presentation order, from 0), ``time`` (seconds from
    the first frame), ``absolute`` (``pts * time_base``), ``pts`` (in the stream's
    ``time_base``; None if the container gives none) and ``pixels`` (BGR, 8 bits; or, when
    :meth:`VideoReader.frames` is asked for ``planes`` and the frame has them, its
    :class:`~gsrwt_cli.imaging.yuv.Yuv420` planes as decoded)."""

    index: int
    time: float
    absolute: float
    pts: int | None
    pixels: np.ndarray | Yuv420


@dataclass(frozen=True)
class FrameFailure:
    """A packet the decoder refused: the frame it held, by ``index`` and times, and why."""

    index: int
    time: float | None
    absolute: float | None
    pts: int | None
    reason: str


@dataclass(frozen=True)
class VideoInfo:
    """A video stream's shape: ``width``, ``height``, ``time_base``, ``rate`` (frames per
    second, None if unknown), ``codec`` and ``duration`` (seconds from its start, None if the
    header does not say)."""

    width: int
    height: int
    time_base: Fraction
    rate: Fraction | None
    codec: str
    duration: float | None


#: Colour tags of a frame whose planes :class:`~gsrwt_cli.imaging.yuv.Yuv420` takes as they
#: are (FFmpeg's numbers): colourspace unspecified (2), BT.470BG (5) or SMPTE 170M (6), both
#: BT.601 as swscale converts an unspecified one; range unspecified (0) or limited (1).
_PLANAR_COLORSPACES = (2, 5, 6)
_PLANAR_RANGES = (0, 1)


def _planes(frame: Any) -> Yuv420 | None:
    """The frame's 8-bit YUV 4:2:0 planes when they mean what
    :meth:`~gsrwt_cli.imaging.yuv.Yuv420.to_bgr` and the H.264 encoder take them to mean
    (``yuv420p``, an even size, BT.601 limited range); else None."""
    if (frame.format.name != "yuv420p" or frame.width % 2 or frame.height % 2
            or frame.colorspace not in _PLANAR_COLORSPACES
            or frame.color_range not in _PLANAR_RANGES):
        return None
    from ..imaging.yuv import Yuv420

    return Yuv420.from_stacked(frame.to_ndarray())


def _reason(error: BaseException) -> str:
    text = getattr(error, "strerror", None) or str(error)
    return one_line(str(text), 200)


class VideoReader:
    """A video file's first video stream, opened (a context manager); :meth:`frames` decodes.

    Raises :class:`VideoError` when the file cannot be opened as a video, naming why.
    """

    def __init__(self, path: str | Path, max_pixels: float = math.inf) -> None:
        av = import_av()
        self.path = Path(path)
        self._av = av
        try:
            self.container = av.open(str(path), mode="r")
        except FileNotFoundError:
            raise VideoError("no such file") from None
        except (av.FFmpegError, OSError, ValueError) as error:
            if self.path.is_file() and self.path.stat().st_size == 0:
                raise VideoError("empty file") from None  # as an image's
            raise VideoError(f"not a video FFmpeg can read ({_reason(error)})") from None
        streams = self.container.streams.video
        if not streams:
            self.container.close()
            raise VideoError("has no video stream")
        self.stream = streams[0]
        # Slice threads only: frame threads report a refused packet on a later one (the
        # error row would name the wrong frame); 640x480 H.264 decodes at about 300 frames/s
        # so, against 440 with frame threads (2 cores).
        self.stream.thread_type = "SLICE"
        context = self.stream.codec_context
        width, height = int(context.width or 0), int(context.height or 0)
        if width * height > max_pixels:
            self.container.close()
            raise VideoError(f"its frames are {width}x{height} pixels, above --max-input-pixels")
        rate = self.stream.average_rate or self.stream.guessed_rate
        duration = None
        if self.stream.duration is not None and self.stream.time_base is not None:
            duration = float(self.stream.duration * self.stream.time_base)
        elif self.container.duration is not None:
            duration = self.container.duration / 1e6
        self.info = VideoInfo(width, height, Fraction(self.stream.time_base or Fraction(1, 1)),
                              Fraction(rate) if rate else None,
                              str(context.name or "unknown"), duration)

    def __enter__(self) -> VideoReader:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.container.close()

    def frames(self, planes: bool = False) -> Iterator[VideoFrame | FrameFailure]:
        """Every frame in presentation order (a refused packet as a :class:`FrameFailure`,
        placed by its timestamp among the frames decoded: decoders hand frames out later
        than their packets come in); raises :class:`VideoTruncatedError` at the end when
        the file is cut short. ``planes``: a frame that has 8-bit YUV 4:2:0 planes comes as
        them (:class:`~gsrwt_cli.imaging.yuv.Yuv420`, no colour converted), any other as
        BGR."""
        av = self._av
        time_base = self.info.time_base
        state = {"first": None, "index": 0}
        last_end: float | None = None
        failed: list[tuple[float, int | None, str]] = []  # refused packets, not yet placed

        def times(pts: int | None, index: int) -> tuple[float, float]:
            if pts is None:
                absolute = index / float(self.info.rate) if self.info.rate else float(index)
                return absolute, absolute
            first = state["first"] if state["first"] is not None else pts
            return float((pts - first) * time_base), float(pts * time_base)

        def failures_before(pts: float) -> Iterator[FrameFailure]:
            failed.sort(key=lambda failure: failure[0])
            while failed and failed[0][0] < pts:
                _, failed_pts, reason = failed.pop(0)
                index = state["index"]
                time, absolute = times(failed_pts, index)
                yield FrameFailure(index, time, absolute, failed_pts, reason)
                state["index"] = index + 1

        packets = self.container.demux(self.stream)
        while True:
            try:
                packet = next(packets)
            except StopIteration:
                break
            except (av.FFmpegError, OSError) as error:
                index = state["index"]
                yield from failures_before(math.inf)
                raise VideoTruncatedError(
                    f"the file ends or breaks after frame {index - 1} ({_reason(error)})"
                    if index else f"no frame could be read ({_reason(error)})") from None
            try:
                decoded = packet.decode()
            except (av.FFmpegError, ValueError) as error:
                if packet.size == 0:  # the flush at the end
                    break
                order = packet.pts if packet.pts is not None else math.inf
                failed.append((order, packet.pts,
                               f"the frame cannot be decoded ({_reason(error)})"))
                continue
            for frame in decoded:
                pts = frame.pts
                if pts is not None and state["first"] is None:
                    state["first"] = pts
                yield from failures_before(pts if pts is not None else -math.inf)
                index = state["index"]
                time, absolute = times(pts, index)
                yuv = _planes(frame) if planes else None
                pixels = yuv if yuv is not None else frame.to_ndarray(format="bgr24")
                yield VideoFrame(index, time, absolute, pts, pixels)
                duration = (float(frame.duration * time_base) if frame.duration else
                            1 / float(self.info.rate) if self.info.rate else 0.0)
                last_end = absolute + duration
                state["index"] = index + 1
        yield from failures_before(math.inf)
        self._check_complete(state["index"], last_end)

    def _check_complete(self, count: int, last_end: float | None) -> None:
        """:class:`VideoTruncatedError` when the header's duration runs past the last frame
        by more than a frame and a half (containers round durations)."""
        if count == 0:
            raise VideoTruncatedError("no frame could be decoded")
        duration, rate = self.info.duration, self.info.rate
        if duration is None or last_end is None:
            return
        start = self.stream.start_time
        start_s = float(start * self.info.time_base) if start is not None else 0.0
        frame = 1 / float(rate) if rate else 0.0
        # Containers disagree on whether the duration counts from the first timestamp
        # (MP4) or from zero (Matroska): the earlier end is the one expected.
        expected_end = min(duration, start_s + duration)
        if expected_end - last_end > 1.5 * frame + 1e-3:
            raise VideoTruncatedError(
                f"the file is cut short: its header says {duration:.3f} s, its frames end at "
                f"{last_end - start_s:.3f} s (after frame {count - 1})")
