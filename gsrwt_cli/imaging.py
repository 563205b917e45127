"""Image files and pixels: read any depth and channel layout, warp with OpenCV, encode."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .geometry import Matrix

#: File types gsrwt looks for in directories (OpenCV reads them all).
IMAGE_EXTENSIONS = (".jpg", ".jpeg", ".jpe", ".png", ".tif", ".tiff", ".bmp", ".webp")

INTERPOLATIONS = {
    "nearest": cv2.INTER_NEAREST,
    "linear": cv2.INTER_LINEAR,
    "cubic": cv2.INTER_CUBIC,
    "lanczos": cv2.INTER_LANCZOS4,
}

# What each output format can hold: sample types and channel counts.
_WRITABLE: dict[str, tuple[frozenset[str], frozenset[int]]] = {
    ".jpg": (frozenset({"uint8"}), frozenset({1, 3})),
    ".png": (frozenset({"uint8", "uint16"}), frozenset({1, 3, 4})),
    ".tif": (frozenset({"uint8", "uint16", "float32"}), frozenset({1, 3, 4})),
    ".bmp": (frozenset({"uint8"}), frozenset({1, 3})),
    ".webp": (frozenset({"uint8"}), frozenset({3, 4})),
}
_CANONICAL_EXTENSION = {".jpeg": ".jpg", ".jpe": ".jpg", ".tiff": ".tif"}

# OpenCV's own warnings would break the one-line-per-problem promise.
with contextlib.suppress(AttributeError):  # older OpenCV builds lack cv2.utils.logging
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)


class ImageError(Exception):
    """An image that cannot be read or written; the message says why (not which file)."""


def canonical_extension(extension: str) -> str:
    """``.JPEG`` -> ``.jpg``: the key of an output format."""
    ext = extension.lower()
    if not ext.startswith("."):
        ext = "." + ext
    return _CANONICAL_EXTENSION.get(ext, ext)


def check_writable(extension: str, dtype: np.dtype, channels: int) -> None:
    """Raise :class:`ImageError` if a file of ``extension`` cannot hold such pixels."""
    ext = canonical_extension(extension)
    if ext not in _WRITABLE:
        raise ImageError(f"cannot write '{extension}' files; use one of {', '.join(_WRITABLE)}")
    dtypes, channel_counts = _WRITABLE[ext]
    depth = {"uint8": "8-bit", "uint16": "16-bit", "float32": "32-bit float"}.get(
        np.dtype(dtype).name, np.dtype(dtype).name
    )
    if np.dtype(dtype).name not in dtypes:
        raise ImageError(f"{ext} cannot store {depth} images; use --ext png or --ext tif")
    if channels not in channel_counts:
        what = {1: "grey", 3: "colour", 4: "alpha (RGBA)"}.get(channels, f"{channels}-channel")
        raise ImageError(f"{ext} cannot store {what} images; use --ext png or --ext tif")



# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


def _check_complete(path: str) -> None:
    """Refuse empty files, and truncated JPEG and PNG files (OpenCV decodes those partially)."""
    with open(path, "rb") as handle:
        head = handle.read(8)
        if not head:
            raise ImageError("empty file")
        handle.seek(max(0, os.fstat(handle.fileno()).st_size - 64))
        tail = handle.read().rstrip(b"\x00")
    if head[:3] == b"\xff\xd8\xff" and not tail.endswith(b"\xff\xd9"):
        raise ImageError("truncated JPEG (no end-of-image marker)")
    if head == b"\x89PNG\r\n\x1a\n" and b"IEND" not in tail:
        raise ImageError("truncated PNG (no IEND chunk)")


@contextlib.contextmanager
def _codec_messages() -> Iterator[list[str]]:
    """Collect what the C codecs (libjpeg, libpng) print on stderr instead of letting it out.

    libjpeg reports damaged data only there ("Corrupt JPEG data: ...", "Premature end of JPEG
    file") and still returns an image; collected, such messages become errors.
    """
    messages: list[str] = []
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield messages
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            text = sink.read().decode(errors="replace")
            messages.extend(line.strip() for line in text.splitlines() if line.strip())


def read_image(path: str | Path, into: np.ndarray | None = None) -> np.ndarray:
    """Read an image file as it is stored: 8/16-bit or float, grey, colour (BGR) or BGRA.

    ``into``: an array to decode into if the image has its shape and type (see
    :class:`Scratch`); otherwise a new array. Raises :class:`ImageError` for a file that is
    missing, empty, truncated, damaged or not decodable. EXIF orientation is not applied
    (pan and tilt describe the sensor, not the display).
    """
    name = os.fspath(path)
    try:
        _check_complete(name)
    except OSError as error:
        raise ImageError(f"cannot read ({error.strerror or error})") from None
    image = None
    with _codec_messages() as messages:
        if into is not None:
            with contextlib.suppress(cv2.error):  # another shape or type: decode afresh
                image = cv2.imread(name, into, cv2.IMREAD_UNCHANGED)
        if image is None:
            try:
                image = cv2.imread(name, cv2.IMREAD_UNCHANGED)
            except cv2.error:
                image = None
    if image is None or image.size == 0:
        reason = f" ({messages[0]})" if messages else ""
        raise ImageError(f"not an image OpenCV can decode (corrupt or unsupported){reason}")
    damage = [m for m in messages if "Corrupt JPEG" in m or "Premature end" in m]
    if damage:
        raise ImageError(f"corrupt JPEG ({damage[0]})")
    return image


# --------------------------------------------------------------------------------------------
# Warping
# --------------------------------------------------------------------------------------------


def _full_value(dtype: np.dtype) -> float:
    return float(np.iinfo(dtype).max) if np.issubdtype(dtype, np.integer) else 1.0


@dataclass(frozen=True)
class Working:
    """Pixels in the layout the warp works in.

    Colour images are warped as BGRA, which OpenCV does about twice as fast as BGR;
    ``padded`` says the fourth channel is such padding rather than the image's alpha.
    """

    pixels: np.ndarray
    padded: bool = False


def to_working(image: np.ndarray, alpha: bool = False, out: np.ndarray | None = None) -> Working:
    """The layout to warp ``image`` in.

    An opaque alpha channel is added when ``alpha`` asks for one, colour images get BGRA
    padding (into ``out`` if given), anything else is warped as it is.
    """
    channels = 1 if image.ndim == 2 else image.shape[2]
    if alpha and channels in (1, 3):
        code = cv2.COLOR_GRAY2BGRA if channels == 1 else cv2.COLOR_BGR2BGRA
        return Working(cv2.cvtColor(image, code, dst=out))
    if channels == 3:
        return Working(cv2.cvtColor(image, cv2.COLOR_BGR2BGRA, dst=out), padded=True)
    return Working(image)


def warp_working(
    source: Working,
    output_from_input: Matrix,
    size: tuple[int, int],
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    out: np.ndarray | None = None,
) -> Working:
    """Backward-map the pixels through a homography in one OpenCV pass (thesis Sec. 5.1).

    ``size`` is the output's ``(width, height)``. Output pixels with no source get ``fill``
    (in the image's own units), opaque, or transparent with ``alpha``. Output pixels that
    map to the far side of the vanishing line (``w <= 0``: what the camera saw beyond the
    wall's horizon) get the same: ``output_from_input`` must be scaled so that ``w > 0``
    where the wall is visible, as the framing module's homographies are. ``out``: an array
    of the output's shape and type to write into (see :class:`Scratch`).
    """
    width, height = size
    pixels = source.pixels
    channels = 1 if pixels.ndim == 2 else pixels.shape[2]
    border = [fill] * min(channels, 3)
    if channels == 4:
        border.append(0.0 if alpha else _full_value(pixels.dtype))
    warped = cv2.warpPerspective(
        pixels,
        np.asarray(output_from_input, dtype=np.float64),
        (width, height),
        dst=out,
        flags=INTERPOLATIONS[interpolation],
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=tuple(border + [0.0] * (4 - len(border))),
    )
    _fill_beyond_horizon(warped, output_from_input, border)
    return Working(warped, source.padded)


def from_working(warped: Working) -> np.ndarray:
    """The image in its own layout again (BGRA padding dropped)."""
    if warped.padded:
        return cv2.cvtColor(warped.pixels, cv2.COLOR_BGRA2BGR)
    return warped.pixels


def warp_image(
    image: np.ndarray,
    output_from_input: Matrix,
    size: tuple[int, int],
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
) -> np.ndarray:
    """Warp ``image`` (any depth; grey, BGR or BGRA) into a new array: see :func:`warp_working`.

    With ``alpha`` the result has an alpha channel (added if the image had none).
    """
    source = to_working(image, alpha)
    return from_working(
        warp_working(source, output_from_input, size, interpolation, fill, alpha)
    )


class Scratch:
    """One worker's memory for decoding and warping, reused from image to image.

    Fresh memory costs page faults (the warp writes about 40% slower into it), and OpenCV
    decodes straight into an array of the right shape, where otherwise it briefly holds the
    image twice. Two regions trade places: a colour image is decoded into region 0, padded
    to BGRA in region 1 and warped back into region 0, whose decoded pixels are dead by then.
    A worker so holds about two images' worth of memory. Use :meth:`read`, then :meth:`warp`.
    """

    def __init__(self) -> None:
        self._regions: list[np.ndarray] = [np.empty(0, np.uint8), np.empty(0, np.uint8)]
        self._decoded: np.ndarray | None = None
        self._shape: tuple[tuple[int, ...], np.dtype] | None = None

    def array(self, region: int, shape: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
        """An uninitialized array of ``shape`` and ``dtype`` in ``region`` (0 or 1)."""
        dtype = np.dtype(dtype)
        nbytes = int(np.prod(shape)) * dtype.itemsize
        if self._regions[region].nbytes < nbytes:
            self._regions[region] = np.empty(0, np.uint8)  # free before allocating
            self._regions[region] = np.empty(nbytes, np.uint8)
        return self._regions[region][:nbytes].view(dtype).reshape(shape)

    def read(self, path: str | Path) -> tuple[tuple[int, ...], np.dtype]:
        """Decode an image into region 0 (:func:`read_image`); its shape and sample type.

        The previous image's shape is the guess; an image of another shape is decoded
        afresh and its memory becomes region 0.
        """
        self._decoded = None
        into = self.array(0, *self._shape) if self._shape is not None else None
        image = read_image(path, into)
        if not np.shares_memory(image, self._regions[0]):
            self._regions[0] = image.reshape(-1).view(np.uint8)
        self._decoded, self._shape = image, (image.shape, image.dtype)
        return image.shape, image.dtype

    @property
    def decoded(self) -> np.ndarray | None:
        """The image :meth:`read` decoded, until :meth:`warp` takes it."""
        return self._decoded

    def warp(
        self,
        output_from_input: Matrix,
        size: tuple[int, int],
        interpolation: str = "linear",
        fill: float = 0.0,
        alpha: bool = False,
    ) -> Working:
        """Warp the image :meth:`read` decoded (see :func:`warp_working`)."""
        image, self._decoded = self._decoded, None
        if image is None:
            raise RuntimeError("Scratch.warp needs an image from Scratch.read first")
        width, height = size
        channels = 1 if image.ndim == 2 else image.shape[2]
        converts = channels == 3 or (alpha and channels == 1)
        if converts:
            padded = self.array(1, (*image.shape[:2], 4), image.dtype)
            source = to_working(image, alpha, padded)
            del image  # region 0 is free for the output
        else:
            source = to_working(image, alpha)
        out_shape = (height, width, *source.pixels.shape[2:])
        out = self.array(0 if converts else 1, out_shape, source.pixels.dtype)
        return warp_working(source, output_from_input, size, interpolation, fill, alpha, out)


def _fill_beyond_horizon(warped: np.ndarray, output_from_input: Matrix, value: list) -> None:
    """Fill output pixels whose source lies beyond the vanishing line (``w <= 0``).

    In the output that region is a half-plane, ``(H^-1)[2] . (col, row, 1) <= 0``, given
    ``H`` scaled so that ``w > 0`` on the visible side (as :func:`~gsrwt_cli.framing.
    output_from_input` makes it); it is clipped to the image and filled.
    """
    height, width = warped.shape[:2]
    homography = np.asarray(output_from_input, dtype=np.float64)
    line = np.linalg.inv(homography)[2]  # (H^-1 o)_3 = 1 / w(p) for o ~ H p
    corners = [(-0.5, -0.5), (width - 0.5, -0.5), (width - 0.5, height - 0.5), (-0.5, height - 0.5)]
    polygon = _clip_to_half_plane(corners, line)
    if len(polygon) >= 3:
        scale = 256  # 8 fractional bits
        points = np.round((np.array(polygon) + 0.5) * scale - 0.5).astype(np.int32)
        color = tuple(value + [0.0] * (4 - len(value)))
        cv2.fillPoly(warped, [points], color, lineType=cv2.LINE_8, shift=8)


def _clip_to_half_plane(polygon: list[tuple[float, float]], line: np.ndarray):
    """The part of a convex polygon where ``line . (x, y, 1) <= 0`` (Sutherland-Hodgman)."""
    clipped = []
    count = len(polygon)
    for index in range(count):
        current, following = polygon[index], polygon[(index + 1) % count]
        d_current = line[0] * current[0] + line[1] * current[1] + line[2]
        d_following = line[0] * following[0] + line[1] * following[1] + line[2]
        if d_current <= 0:
            clipped.append(current)
        if (d_current <= 0) != (d_following <= 0):
            t = d_current / (d_current - d_following)
            clipped.append(
                (
                    current[0] + t * (following[0] - current[0]),
                    current[1] + t * (following[1] - current[1]),
                )
            )
    return clipped


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------


def encode_image(image: np.ndarray | Working, extension: str, quality: int = 95) -> bytes:
    """Encode pixels as a file of type ``extension``; JPEG and WebP at ``quality`` (1-100).

    A padded :class:`Working` image goes to JPEG as it is (the encoder drops the fourth
    channel itself, at no cost); other formats get it without the padding.
    """
    ext = canonical_extension(extension)
    padded_jpeg = isinstance(image, Working) and image.padded and ext == ".jpg"
    if isinstance(image, Working):
        image = image.pixels if padded_jpeg else from_working(image)
    channels = 3 if padded_jpeg else 1 if image.ndim == 2 else image.shape[2]
    check_writable(ext, image.dtype, channels)
    params: list[int] = []
    if ext == ".jpg":
        params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)]
    elif ext == ".webp":
        params = [cv2.IMWRITE_WEBP_QUALITY, int(quality)]
    ok, encoded = cv2.imencode(ext, image, params)
    if not ok:
        raise ImageError(f"OpenCV could not encode the image as {ext}")
    return encoded.tobytes()
