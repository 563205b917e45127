"""Video files as outputs: frames encoded with their own timestamps (PyAV).

``h264`` (libx264, ``yuv420p``, CRF 18, preset ``veryfast``) in an MP4 container; ``ffv1``
(lossless, the pixels in ``bgr0``) in Matroska. Each frame keeps the ``pts`` it had in the
input, in the input's ``time_base``, so the output has the input's frame rate and timing
(a frame left out, an error, leaves a gap rather than shifting the ones after it). The
encoder writes into a binary stream the caller gives
(:func:`~gsrwt_cli.io.outputs.open_atomic`'s temporary file, renamed when complete).
PyAV is imported when an encoder is made.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from fractions import Fraction
from typing import IO, Any

import numpy as np

from .yuv import Yuv420


class VideoEncodeError(Exception):
    """The encoder cannot take this output (a codec missing, a size it refuses)."""


@dataclass(frozen=True)
class VideoCodec:
    """An output codec: its ``name`` in ``--codec``, the container file ``extension``, the
    FFmpeg ``container`` and ``encoder`` names, the ``pixel_format`` encoded and the encoder's
    ``options``."""

    name: str
    extension: str
    container: str
    encoder: str
    pixel_format: str
    options: tuple[tuple[str, str], ...] = ()


#: The video codecs of ``--codec`` (``png``, an image sequence, is not a video codec).
VIDEO_CODECS = {
    "h264": VideoCodec("h264", ".mp4", "mp4", "libx264", "yuv420p",
                       (("crf", "18"), ("preset", "veryfast"))),
    "ffv1": VideoCodec("ffv1", ".mkv", "matroska", "ffv1", "bgr0",
                       (("level", "3"), ("slicecrc", "1"))),
}


def codec_available(codec: VideoCodec) -> bool:
    """Whether this PyAV's FFmpeg has the codec's encoder."""
    import av

    return codec.encoder in av.codecs_available


class VideoEncoder:
    """Frames (BGR, 8 bits, or YUV 4:2:0 planes) to a video in ``stream``, opened on the
    first frame (whose size every later frame must have). Call :meth:`close` to finish the
    file; on an error, drop the stream (the caller's temporary file) instead."""

    def __init__(self, stream: IO[bytes], codec: VideoCodec, time_base: Fraction,
                 rate: Fraction | None) -> None:
        self.stream = stream
        self.codec = codec
        self.time_base = time_base
        self.rate = rate
        self.size: tuple[int, int] | None = None
        self._container: Any = None
        self._video: Any = None
        self._last_pts: int | None = None
        self.frames = 0

    def _open(self, width: int, height: int) -> None:
        import av

        if self.codec.pixel_format == "yuv420p" and (width % 2 or height % 2):
            raise VideoEncodeError(f"{self.codec.name} needs an even width and height, the "
                                   f"output is {width}x{height}")
        container = av.open(self.stream, mode="w", format=self.codec.container)
        try:
            video = container.add_stream(self.codec.encoder, rate=self.rate,
                                         options=dict(self.codec.options))
            video.width, video.height = width, height
            video.pix_fmt = self.codec.pixel_format
            video.time_base = self.time_base
            video.codec_context.time_base = self.time_base
        except Exception:
            container.close()
            raise
        self._container, self._video, self.size = container, video, (width, height)

    def write(self, pixels: np.ndarray | Yuv420, pts: int) -> None:
        """Encode one frame (BGR, or :class:`~gsrwt_cli.imaging.yuv.Yuv420` planes, taken
        as they are by a ``yuv420p`` codec) at ``pts`` (in the input's ``time_base``); pts
        must increase."""
        import av

        height, width = pixels.shape[:2]
        if self._container is None:
            self._open(width, height)
        if (width, height) != self.size:
            raise VideoEncodeError(f"the frame is {width}x{height}, the video "
                                   f"{self.size[0]}x{self.size[1]}")  # type: ignore[index]
        if self._last_pts is not None and pts <= self._last_pts:
            raise VideoEncodeError(f"timestamp {pts} does not follow {self._last_pts}")
        if isinstance(pixels, Yuv420) and self.codec.pixel_format != "yuv420p":
            pixels = pixels.to_bgr()
        if isinstance(pixels, Yuv420):  # its memory, not a copy (each frame's planes are new)
            frame = av.VideoFrame.from_numpy_buffer(pixels.stacked(), format="yuv420p")
        else:
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(pixels), format="bgr24")
        frame.pts = pts
        frame.time_base = self.time_base
        for packet in self._video.encode(frame):
            self._container.mux(packet)
        self._last_pts = pts
        self.frames += 1

    def close(self) -> None:
        """Flush the encoder and finish the container (nothing if no frame was written)."""
        if self._container is None:
            return
        for packet in self._video.encode():
            self._container.mux(packet)
        self._container.close()
        self._container = None

    def abandon(self) -> None:
        """Close without finishing (the file is to be thrown away)."""
        if self._container is not None:
            with contextlib.suppress(Exception):  # the file is dropped anyway
                self._container.close()
            self._container = None
