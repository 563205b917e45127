"""A video frame's pixels as its decoder gives them and its encoder takes them: the three
planes of 8-bit YUV 4:2:0 (``yuv420p``), warped plane by plane.

A 640x480 H.264 frame costs about 3 ms to convert to BGR and 3 ms to convert back to
``yuv420p`` for the encoder (FFmpeg's swscale, measured on a 2-core machine), twice the
warp itself (1.6 ms). When the camera has no lens and the output is H.264, a frame is warped
in the encoder's own layout instead: the luma plane through the frame's
:class:`~gsrwt_cli.geometry.pixelmap.PixelMap`, each chroma plane (half the width and height)
through the same map on half-size pixels (:func:`chroma_map`), and no colour is converted.

Chroma siting: H.264's default (MPEG-2's, ``left``): a chroma sample sits on the even luma
column, halfway between two luma rows. The input's and the output's chroma share that
convention, so a frame whose chroma sits elsewhere is off by less than a quarter of a chroma
pixel, not shifted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.pixelmap import PixelMap

#: Where a chroma sample sits, in chroma pixels, relative to the centre of the 2x2 luma
#: pixels it covers: H.264's default (``left``): on the even luma column, between the rows.
CHROMA_SITING = (0.25, 0.0)


@dataclass(frozen=True)
class Yuv420:
    """One frame's planes, ``yuv420p`` (limited range, BT.601, as the encoder's input and the
    BGR conversion both assume), in one array ``data`` of ``width * height * 3 / 2`` bytes:
    Y (``height x width``), then U and V (``height/2 x width/2`` each); width and height even.
    """

    data: np.ndarray
    width: int
    height: int

    def __post_init__(self) -> None:
        if self.width % 2 or self.height % 2:
            raise ValueError(f"yuv420p planes need an even size, got {self.width}x{self.height}")
        if self.data.dtype != np.uint8 or self.data.size != self.width * self.height * 3 // 2:
            raise ValueError(f"not the yuv420p planes of a {self.width}x{self.height} frame")

    @classmethod
    def empty(cls, width: int, height: int) -> Yuv420:
        """Uninitialised planes of a ``width x height`` frame."""
        return cls(np.empty(width * height * 3 // 2, np.uint8), width, height)

    @classmethod
    def from_stacked(cls, stacked: np.ndarray) -> Yuv420:
        """PyAV's ``yuv420p`` array (``to_ndarray()``: ``height * 3/2`` rows of ``width``)."""
        rows, width = stacked.shape
        return cls(np.ascontiguousarray(stacked).reshape(-1), width, rows * 2 // 3)

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``, as an image array's ``shape[:2]``."""
        return self.height, self.width

    def planes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Y, U and V as views of :attr:`data` (writing into them writes the frame)."""
        luma = self.width * self.height
        half = (self.height // 2, self.width // 2)
        return (self.data[:luma].reshape(self.height, self.width),
                self.data[luma:luma * 5 // 4].reshape(half),
                self.data[luma * 5 // 4:].reshape(half))

    def stacked(self) -> np.ndarray:
        """The frame as PyAV's ``VideoFrame.from_ndarray(..., format="yuv420p")`` takes it."""
        return self.data.reshape(self.height * 3 // 2, self.width)

    def to_bgr(self) -> np.ndarray:
        """BGR, converted by FFmpeg's swscale exactly as PyAV's ``to_ndarray(format="bgr24")``
        converts a decoded frame (PyAV imported here)."""
        import av

        return av.VideoFrame.from_ndarray(self.stacked(), format="yuv420p").to_ndarray(
            format="bgr24")


def chroma_map(pixel_map: PixelMap) -> PixelMap:
    """``pixel_map`` between the chroma planes of its input and output (half the size of
    each, :data:`CHROMA_SITING`): ``C_out H C_in^-1`` with ``C`` the luma-to-chroma pixel
    map, ``x_c = (x + 0.5) / 2 - 0.5 + siting``. The local shrink is the same as the luma's
    (the map is conjugated by one scaling), so antialiasing filters the same."""
    width, height = pixel_map.size
    dx, dy = CHROMA_SITING
    chroma_from_luma = np.array([[0.5, 0.0, -0.25 + dx], [0.0, 0.5, -0.25 + dy],
                                 [0.0, 0.0, 1.0]])
    return pixel_map.reduced(2, CHROMA_SITING).then(chroma_from_luma,
                                                    (width // 2, height // 2))


def yuv_fill(fill: float) -> tuple[float, float]:
    """The luma and chroma of the grey ``fill`` (0-255 in each of B, G and R), as swscale
    converts it (BT.601, limited range): ``16 + 219 fill / 255`` and 128."""
    return 16.0 + 219.0 * float(np.clip(fill, 0.0, 255.0)) / 255.0, 128.0


def warp_yuv420(frame: Yuv420, pixel_map: PixelMap, interpolation: int, fill: float,
                antialias: bool) -> Yuv420:
    """``frame`` warped through ``pixel_map`` (no lens: :meth:`PixelMap.warp`'s one
    ``warpPerspective`` per plane, the antialiasing and the horizon's fill included) into
    new planes of the map's size, which must be even. ``fill``: a grey in BGR units.

    ``antialias``: the chroma is filtered where the luma is; whether any of it is, is
    measured once, on the luma (:meth:`PixelMap.filters`: the chroma map shrinks alike), not
    once per plane (each measure costs about a third of a plane's warp)."""
    if pixel_map.lens is not None or pixel_map.output_lens is not None:
        raise ValueError("planes are warped through a pinhole only")
    antialias = antialias and pixel_map.filters((frame.width, frame.height))
    width, height = pixel_map.size
    out = Yuv420.empty(width, height)
    luma_fill, chroma_fill = yuv_fill(fill)
    y, u, v = frame.planes()
    out_y, out_u, out_v = out.planes()
    pixel_map.warp(y, interpolation, (luma_fill,) * 4, out_y, antialias)
    chroma = chroma_map(pixel_map)
    for plane, into in ((u, out_u), (v, out_v)):
        chroma.warp(plane, interpolation, (chroma_fill,) * 4, into, antialias)
    return out
