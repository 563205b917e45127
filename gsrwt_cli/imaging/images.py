"""Image files and pixels: read any depth and channel layout, warp with OpenCV, encode.

Reading measures a file's header before decoding it and checks what the codec returns; the
pixels are warped in the layout OpenCV is fastest with (:class:`Working`) and encoded from it
without converting back. The three share that layout, which is why they live in one module
of a little over 400 lines.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import os
import sys
import tempfile
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING

import cv2
import numpy as np

from ..base.messages import one_line
from ..geometry.orientation import ORIENTATION_TAG, orientation_steps, valid_orientation
from ..geometry.pixelmap import PixelMap
from ..io.storage import open_input

if TYPE_CHECKING:
    from ..io.metadata import PhotoExif

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
    ".tif": (frozenset({"uint8", "uint16", "int16", "float32", "float64"}),
             frozenset({1, 3, 4})),
    ".bmp": (frozenset({"uint8"}), frozenset({1, 3})),
    ".webp": (frozenset({"uint8"}), frozenset({3, 4})),
}
#: Inputs whose header claims more pixels than this are refused before decoding.
DEFAULT_MAX_INPUT_PIXELS = 300e6

_CANONICAL_EXTENSION = {".jpeg": ".jpg", ".jpe": ".jpg", ".tiff": ".tif"}



def silence_opencv_logging() -> None:
    """Stop OpenCV's own log lines (process-wide: for the ``gsrwt`` command, not a library).

    They would break the one-line-per-problem promise; what gsrwt needs from the codecs it
    collects itself (:func:`_codec_messages`).
    """
    with contextlib.suppress(AttributeError):  # older OpenCV builds lack cv2.utils.logging
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)


def keep_freed_memory() -> None:
    """Let this process reuse freed image memory instead of returning it to the system.

    OpenCV decodes every image into fresh memory; glibc serves such large blocks with
    ``mmap`` and unmaps them when freed, so each image pays page faults for ~2 frames
    (measured: 62 ms against 42 ms to decode a 12-megapixel JPEG). Raising glibc's mmap and
    trim thresholds (``mallopt``) keeps the blocks in the heap for the next image. Process-
    wide: for a batch worker's own process, not a library. No-op where glibc is absent.
    """
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL("libc.so.6")
        m_trim_threshold, m_mmap_threshold = -1, -3
        libc.mallopt(m_mmap_threshold, 1 << 30)
        libc.mallopt(m_trim_threshold, 2**31 - 1)


class ImageError(Exception):
    """An image that cannot be read or written; the message says why (not which file)."""


class ImageFormatError(ImageError):
    """A file format that cannot hold an image (``what``: which images; None: a format gsrwt
    does not write at all): ``reason`` says why, ``alternatives`` lists the formats
    (extensions without the dot) that could."""

    def __init__(self, extension: str, what: str | None, alternatives: list[str]) -> None:
        self.extension, self.alternatives = extension, alternatives
        self.reason = (f"cannot write '{extension}' files" if what is None
                       else f"{extension} cannot store {what}")
        advice = (f"formats that can: {', '.join(alternatives)}" if alternatives
                  else "no output format gsrwt writes can hold them")
        super().__init__(f"{self.reason}; {advice}")


def canonical_extension(extension: str) -> str:
    """``.JPEG`` -> ``.jpg``: the key of an output format."""
    ext = extension.lower()
    if not ext.startswith("."):
        ext = "." + ext
    return _CANONICAL_EXTENSION.get(ext, ext)


#: Largest width and height each output format can hold.
_MAX_SIDE = {".jpg": 65535, ".webp": 16383, ".png": 2**31 - 1, ".tif": 2**31 - 1,
             ".bmp": 2**31 - 1}
_DEPTH_NAMES = {"uint8": "8-bit", "uint16": "16-bit", "float32": "32-bit float",
                "float64": "64-bit float", "int16": "signed 16-bit", "int8": "signed 8-bit",
                "int32": "signed 32-bit"}
_CHANNEL_NAMES = {1: "grey", 3: "colour", 4: "alpha (RGBA)"}


def check_writable(
    extension: str, dtype: np.dtype, channels: int, size: tuple[int, int] | None = None
) -> None:
    """Raise :class:`ImageError` if a file of ``extension`` cannot hold such pixels.

    ``size``: the image's ``(width, height)``, checked against the format's largest side.
    The message names the formats that can hold the image, or says that none can.
    """
    ext = canonical_extension(extension)
    dtype_name = np.dtype(dtype).name
    alternatives = [
        other.lstrip(".") for other, (other_dtypes, other_channels) in _WRITABLE.items()
        if other != ext and dtype_name in other_dtypes and channels in other_channels
        and (size is None or max(size) <= _MAX_SIDE[other])
    ]
    if ext not in _WRITABLE:
        raise ImageFormatError(extension, None, alternatives)
    dtypes, channel_counts = _WRITABLE[ext]
    what = None
    if dtype_name not in dtypes:
        what = f"{_DEPTH_NAMES.get(dtype_name, dtype_name)} images"
    elif channels not in channel_counts:
        what = f"{_CHANNEL_NAMES.get(channels, f'{channels}-channel')} images"
    elif size is not None and max(size) > _MAX_SIDE[ext]:
        what = (f"images over {_MAX_SIDE[ext]} pixels wide or high (this one is "
                f"{size[0]}x{size[1]})")
    if what is not None:
        raise ImageFormatError(ext, what, alternatives)


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


def read_file_bytes(path: str | Path) -> bytes:
    """The bytes of a file, read by Python (any file name the system allows, none to OpenCV)."""
    try:
        with open_input(path) as handle:
            return handle.read()
    except IsADirectoryError:
        raise ImageError("is a directory, not an image") from None
    except OSError as error:
        raise ImageError(f"cannot read ({error.strerror or error})") from None


def header_size(data: bytes | IO[bytes]) -> tuple[int, int] | None:
    """``(width, height)`` from an image file's header, without decoding it; None if unknown.

    ``data``: the file's bytes or an open binary file. Uses the ``imagesize`` package, which
    reads the header of JPEG, PNG, TIFF, BMP, WebP and other formats (EXIF rotation ignored,
    as everywhere in gsrwt).
    """
    import imagesize  # here: a video's run measures no image file

    stream = io.BytesIO(data) if isinstance(data, (bytes, bytearray, memoryview)) else data
    try:
        width, height = imagesize.get(stream, exif_rotation=False)
    except Exception:  # a damaged header: imagesize's parsers raise many kinds of errors
        return None
    if not (isinstance(width, int) and isinstance(height, int)) or width < 1 or height < 1:
        return None
    return width, height


def image_file_size(path: str | Path) -> tuple[int, int] | None:
    """``(width, height)`` of an image file from its header (:func:`header_size`)."""
    try:
        with open_input(path) as handle:
            return header_size(handle)
    except OSError:
        return None


def file_orientation(path: str | Path) -> int:
    """The EXIF orientation (1-8) of an image file, 1 when it has none or an invalid one
    (:func:`~gsrwt_cli.geometry.orientation.valid_orientation`): JPEG, PNG (``eXIf``), TIFF
    and WebP, read by Pillow (``Image.open`` reads the header, never the pixels); whatever
    Pillow raises on a damaged file means 1. A PNG's ``eXIf`` is looked for before its pixels
    only (where Pillow, ExifTool and ImageMagick write it): one after them would need the
    pixels decoded (Pillow's ``getexif`` would decode them to find it)."""
    import warnings

    from PIL import Image  # Pillow only when an image is read

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Corrupt EXIF data", "Truncated File Read", ...
        try:
            with open_input(path) as handle, Image.open(handle) as image:
                if image.format == "PNG" and "exif" not in image.info:
                    return 1  # none before the pixels
                value = image.getexif().get(ORIENTATION_TAG)
        except Exception:  # noqa: BLE001 - a damaged file of a third-party parser: upright
            return 1
    return valid_orientation(value)


def displayed_pixels(image: np.ndarray, orientation: int) -> np.ndarray:
    """The stored ``image`` as its EXIF ``orientation`` (1-8) displays it, a new array (the
    image itself for 1): turned and mirrored as :mod:`~gsrwt_cli.geometry.orientation`'s table
    says, by OpenCV (``cv2.rotate``, ``flip``, ``transpose``: a 12 MP BGRA turned in about a
    third of the time numpy's copy of a transposed view takes)."""
    if orientation == 1:
        return image
    swap, flip_x, flip_y = orientation_steps(orientation)
    if swap and flip_x != flip_y:  # a quarter turn, one pass
        code = cv2.ROTATE_90_CLOCKWISE if flip_x else cv2.ROTATE_90_COUNTERCLOCKWISE
        return cv2.rotate(image, code)
    turned = cv2.transpose(image) if swap else image
    if flip_x or flip_y:
        turned = cv2.flip(turned, -1 if flip_x and flip_y else 1 if flip_x else 0)
    return turned


def measure_image_file(path: str | Path, max_pixels: float) -> tuple[int, int]:
    """``(width, height)`` of an image file from its header, refused as :func:`decode_image`
    would refuse it (empty, unreadable, unmeasurable, above ``max_pixels``), undecoded."""
    try:
        with open_input(path) as handle:
            if not handle.read(1):
                raise ImageError("empty file")
            handle.seek(0)
            size = header_size(handle)
    except IsADirectoryError:
        raise ImageError("is a directory, not an image") from None
    except OSError as error:
        raise ImageError(f"cannot read ({error.strerror or error})") from None
    return check_input_size(size, max_pixels)


def _check_complete(data: bytes) -> None:
    """Refuse empty files, and truncated JPEG and PNG files (OpenCV decodes those partially).

    A JPEG is complete when its stream reaches its end-of-image marker, wherever the file
    ends: phones append a video (motion photos) or a second picture (MPO) after it. The last
    bytes are checked first (no cost for the usual file), else the stream's markers are walked
    (:func:`~gsrwt_cli.io.jpeg_stream.jpeg_stream_end`, about 2 ms for a 12 MP file).
    """
    from ..io.jpeg_stream import jpeg_stream_end  # imported here: this function is all it needs

    if not data:
        raise ImageError("empty file")
    head, tail = data[:8], data[-64:].rstrip(b"\x00")
    if (head[:3] == b"\xff\xd8\xff" and not tail.endswith(b"\xff\xd9")
            and jpeg_stream_end(data) is None):
        raise ImageError("truncated JPEG (no end-of-image marker)")
    if head == b"\x89PNG\r\n\x1a\n" and b"IEND" not in tail:
        raise ImageError("truncated PNG (no IEND chunk)")


def check_input_size(size: tuple[int, int] | None, max_pixels: float) -> tuple[int, int]:
    """Refuse an image whose header is unreadable or claims more than ``max_pixels`` pixels."""
    if size is None:
        raise ImageError(
            "not an image gsrwt can decode (no JPEG, PNG, TIFF, BMP or WebP header)"
        )
    width, height = size
    if width * height > max_pixels:
        raise ImageError(
            f"its header says {width}x{height} = {width * height / 1e6:.1f} megapixels, above "
            f"the input limit of {max_pixels / 1e6:g} megapixels (a damaged file or a "
            "decompression bomb?)",
        )
    return size


_STDERR_CAPTURE = threading.Lock()


@contextlib.contextmanager
def _codec_messages() -> Iterator[list[str]]:
    """Collect what the C codecs (libjpeg, libpng) print on stderr instead of letting it out.

    libjpeg reports damaged data only there ("Corrupt JPEG data: ...", "Premature end of JPEG
    file") and still returns an image; collected, such messages become errors.

    File descriptor 2 belongs to the whole process, so two threads cannot each redirect it:
    a lock serializes captures (and so decodes) between the threads of one process, and
    whatever another thread writes to fd 2 during a capture lands in it too (and is dropped).
    The batch runner decodes in worker processes of one thread each, where neither happens.
    """
    messages: list[str] = []
    with _STDERR_CAPTURE, _captured_stderr(messages):
        yield messages


@contextlib.contextmanager
def _captured_stderr(messages: list[str]) -> Iterator[None]:
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            text = sink.read().decode(errors="replace")
            messages.extend(line.strip() for line in text.splitlines() if line.strip())


#: The reductions libjpeg-turbo's scaled decoding makes in the DCT, largest first (it has
#: others, such as 3/8, whose pixels straddle the input's; gsrwt uses these three only).
JPEG_REDUCTIONS = (8, 4, 2)
#: Images with a side shorter than this are never decoded reduced (a preview of them costs
#: nothing, and libjpeg's choice of factor is unambiguous above it).
_LEAST_REDUCED_SIDE = 64


def reduced_size(width: int, height: int, reduction: int) -> tuple[int, int]:
    """``(width, height)`` of an image decoded ``reduction`` times smaller in the DCT: its last
    pixel of a side ``reduction`` does not divide is a part pixel, counted whole."""
    return -(-width // reduction), -(-height // reduction)


def jpeg_reduction(data: bytes, wanted: int) -> int:
    """The largest of :data:`JPEG_REDUCTIONS` up to ``wanted`` that :func:`decode_image`
    decodes the JPEG ``data`` at, 1 for none: a JPEG libjpeg-turbo decodes here (grey or
    YCbCr, not CMYK or 12-bit) whose sides are at least 64 pixels, and whose reduced size
    libjpeg-turbo confirms (:func:`reduced_size`)."""
    import simplejpeg

    if data[:3] != b"\xff\xd8\xff":
        return 1
    try:
        height, width, colorspace, _ = simplejpeg.decode_jpeg_header(data)
    except ValueError:
        return 1
    if colorspace not in ("Gray", "YCbCr") or min(width, height) < _LEAST_REDUCED_SIDE:
        return 1
    for reduction in JPEG_REDUCTIONS:
        if reduction > wanted:
            continue
        small_width, small_height = reduced_size(width, height, reduction)
        scaled = simplejpeg.decode_jpeg_header(data, min_height=small_height,
                                               min_width=small_width)
        if scaled[:2] == (small_height, small_width):
            return reduction
    return 1


def preview_reduction(pixel_map: PixelMap, source_size: tuple[int, int]) -> int:
    """The largest of :data:`JPEG_REDUCTIONS` by which an input of ``source_size`` (width,
    height, as the map sees it) may be decoded for ``pixel_map``, 1 for none: every output
    pixel that samples the input spans at least that many input pixels
    (:meth:`~gsrwt_cli.geometry.pixelmap.PixelMap.least_shrink`, the antialiasing's measure),
    so the reduced input is nowhere magnified where the antialiased warp of the whole input
    samples a pyramid level at least as coarse."""
    shrink = pixel_map.least_shrink(source_size, step=16)
    return next((r for r in JPEG_REDUCTIONS if r <= shrink * (1 + 1e-6)), 1)


def _decode_jpeg(data: bytes, padded: bool = False, into: np.ndarray | None = None,
                 reduction: int = 1) -> np.ndarray | None:
    """A grey or colour JPEG decoded by libjpeg-turbo (simplejpeg), as OpenCV would decode
    it (grey, or BGR; BGRA with an opaque fourth channel if ``padded``), into the memory of
    ``into`` if it is padded and ``into`` is big enough; None for any other JPEG (CMYK,
    12-bit: OpenCV's job). ``reduction``: decoded that many times smaller in the DCT
    (:func:`jpeg_reduction` says which the file allows).

    libjpeg reports damaged data as warnings; simplejpeg's strict mode raises them, so a
    damaged JPEG is an error here with libjpeg's own words, with nothing to capture.
    """
    import simplejpeg  # imported here: the commands that decode nothing start faster

    try:
        height, width, colorspace, _ = simplejpeg.decode_jpeg_header(data)
    except ValueError:
        return None
    if colorspace not in ("Gray", "YCbCr"):
        return None
    width, height = reduced_size(width, height, reduction)
    space = "GRAY" if colorspace == "Gray" else "BGRA" if padded else "BGR"
    channels = {"GRAY": 1, "BGR": 3, "BGRA": 4}[space]
    if space != "BGRA" or into is not None and into.nbytes < height * width * channels:
        into = None  # only the warp's BGRA goes into the caller's memory
    minimum = {"min_height": height, "min_width": width} if reduction > 1 else {}
    try:
        image = simplejpeg.decode_jpeg(data, colorspace=space, buffer=into, strict=True,
                                       **minimum)
    except ValueError as error:
        raise ImageError(f"corrupt JPEG ({one_line(str(error), 200)})") from None
    return image[..., 0] if space == "GRAY" else image


def decode_image(data: bytes, max_pixels: float = DEFAULT_MAX_INPUT_PIXELS, *,
                 padded: bool = False, into: np.ndarray | None = None,
                 reduction: int = 1) -> np.ndarray:
    """Decode an image file's bytes as stored: 8/16-bit or float, grey, BGR or BGRA.

    The header is measured first (:func:`header_size`): an image of more than ``max_pixels``
    pixels is refused before any pixel memory is allocated. Raises :class:`ImageError` for
    data that is empty, truncated, damaged or not decodable; what the codec returns is
    checked, never trusted. EXIF orientation is not applied here (:func:`read_image` and
    :meth:`Scratch.read` apply it). JPEGs are decoded by :func:`_decode_jpeg` (``padded``: a
    colour JPEG as BGRA with an opaque fourth channel, for the warp; ``into``: memory to
    decode it into), other files by OpenCV. ``reduction``: a JPEG decoded that many times
    smaller in the DCT (:func:`reduced_size`), one :func:`jpeg_reduction` allows (else
    ``ValueError``).
    """
    if not data:
        raise ImageError("empty file")
    width, height = check_input_size(header_size(data), max_pixels)
    _check_complete(data)
    if reduction != 1:
        if jpeg_reduction(data, reduction) != reduction:
            raise ValueError(f"this image cannot be decoded {reduction} times smaller")
        width, height = reduced_size(width, height, reduction)
    image = (_decode_jpeg(data, padded, into, reduction) if data[:3] == b"\xff\xd8\xff"
             else None)
    if image is not None:
        if image.shape[:2] != (height, width):
            raise ImageError(f"its header says {width}x{height} pixels but it decodes as "
                             f"{image.shape[1]}x{image.shape[0]}")
        return image
    with _codec_messages() as messages:
        try:
            image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        except cv2.error:
            image = None
    if image is None or image.size == 0:
        reason = f" ({messages[0]})" if messages else ""
        raise ImageError(f"not an image gsrwt can decode (corrupt or unsupported){reason}")
    if image.shape[:2] != (height, width):
        raise ImageError(
            f"its header says {width}x{height} pixels but it decodes as "
            f"{image.shape[1]}x{image.shape[0]}"
        )
    damage = [m for m in messages if "Corrupt JPEG" in m or "Premature end" in m]
    if damage:
        raise ImageError(f"corrupt JPEG ({damage[0]})")
    return image


def read_image(path: str | Path, max_pixels: float = DEFAULT_MAX_INPUT_PIXELS,
               orientation: int = 1) -> np.ndarray:
    """Read and decode an image file (:func:`decode_image`); the path never reaches OpenCV.
    ``orientation``: its EXIF orientation (:func:`file_orientation`), applied
    (:func:`displayed_pixels`); 1, the default, leaves the pixels as stored."""
    return displayed_pixels(decode_image(read_file_bytes(path), max_pixels), orientation)


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
    converts = image.dtype in _CONVERTIBLE
    if alpha and channels in (1, 3):
        if not converts:
            return Working(_with_opaque_alpha(image, out))
        code = cv2.COLOR_GRAY2BGRA if channels == 1 else cv2.COLOR_BGR2BGRA
        return Working(cv2.cvtColor(image, code, dst=out))
    if channels == 3 and converts:
        return Working(cv2.cvtColor(image, cv2.COLOR_BGR2BGRA, dst=out), padded=True)
    return Working(image)


#: Sample types OpenCV's colour conversions take; others are converted by numpy.
_CONVERTIBLE = (np.dtype(np.uint8), np.dtype(np.uint16), np.dtype(np.float32))


def _with_opaque_alpha(image: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """A grey or BGR image of any sample type as BGRA with an opaque alpha channel."""
    if out is None:
        out = np.empty((*image.shape[:2], 4), image.dtype)
    out[..., :3] = image[..., None] if image.ndim == 2 else image
    out[..., 3] = _full_value(image.dtype)
    return out


def warp_working(
    source: Working,
    pixel_map: PixelMap,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    out: np.ndarray | None = None,
    antialias: bool = False,
) -> Working:
    """Resample the pixels through ``pixel_map`` (:meth:`PixelMap.warp`, one OpenCV pass).

    Output pixels with no source (outside the input, or beyond the wall's horizon) get
    ``fill`` (in the image's own units), opaque, or transparent with ``alpha``. ``out``: an
    array of the output's shape and type to write into (see :class:`Scratch`). ``antialias``:
    area-filter where the map shrinks the input (:meth:`PixelMap.warp`).
    """
    pixels = source.pixels
    channels = 1 if pixels.ndim == 2 else pixels.shape[2]
    border = [fill] * min(channels, 3)
    if channels == 4:
        border.append(0.0 if alpha else _full_value(pixels.dtype))
    fill_values = tuple(border + [0.0] * (4 - len(border)))
    warped = pixel_map.warp(pixels, INTERPOLATIONS[interpolation], fill_values, out, antialias)
    return Working(warped, source.padded)


def from_working(warped: Working) -> np.ndarray:
    """The image in its own layout again (BGRA padding dropped)."""
    if warped.padded:  # only sample types OpenCV converts are padded
        return cv2.cvtColor(warped.pixels, cv2.COLOR_BGRA2BGR)
    return warped.pixels


def warp_image(
    image: np.ndarray,
    pixel_map: PixelMap,
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    antialias: bool = False,
) -> np.ndarray:
    """Warp ``image`` (any depth; grey, BGR or BGRA) into a new array: see :func:`warp_working`.

    With ``alpha`` the result has an alpha channel (added if the image had none).
    """
    source = to_working(image, alpha)
    return from_working(warp_working(source, pixel_map, interpolation, fill, alpha,
                                     antialias=antialias))


class Scratch:
    """One worker's memory for decoding and warping an image at a time.

    A colour JPEG is decoded straight to BGRA into region 1 and warped into region 0, both
    kept from image to image. Any other colour image is decoded by OpenCV (into memory it
    allocates: it cannot decode bytes into a given array), padded to BGRA in region 1 and
    warped into region 0; those regions are released before each such decode and rebuilt
    from what the decoder frees. Fresh memory costs page faults (the warp writes about 40%
    slower into it); in a worker's own process :func:`keep_freed_memory` makes the allocator
    hand the same memory back image after image. Use :meth:`read`, then :meth:`warp`.
    """

    def __init__(self) -> None:
        self._regions: list[np.ndarray] = [np.empty(0, np.uint8), np.empty(0, np.uint8)]
        self._decoded: np.ndarray | None = None
        self._padded = False  # the decoded image is a JPEG's BGRA, fourth channel opaque
        self._icc = b""  # the JPEG's ICC profile segments, if they describe it, for its output
        self._reduced: tuple[int, tuple[float, float]] = (1, (0.0, 0.0))  # see :meth:`read`
        #: The EXIF of the image :meth:`read` read last, cleaned for its output, when asked
        #: for (:func:`~gsrwt_cli.io.metadata.photo_exif`); None if it has none.
        self.exif: PhotoExif | None = None
        #: Why that EXIF could not be read (a damaged block), else None.
        self.exif_problem: str | None = None

    def array(self, region: int, shape: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
        """An uninitialized array of ``shape`` and ``dtype`` in ``region`` (0 or 1)."""
        dtype = np.dtype(dtype)
        nbytes = int(np.prod(shape)) * dtype.itemsize
        if self._regions[region].nbytes < nbytes:
            self._regions[region] = np.empty(0, np.uint8)  # free before allocating
            self._regions[region] = np.empty(nbytes, np.uint8)
        return self._regions[region][:nbytes].view(dtype).reshape(shape)

    @property
    def reduction(self) -> int:
        """How many times smaller than stored the image :meth:`read` decoded is (1, 2, 4 or
        8: a preview's JPEG decoded reduced in the DCT)."""
        return self._reduced[0]

    def read(self, path: str | Path, max_pixels: float = DEFAULT_MAX_INPUT_PIXELS,
             orientation: int = 1, preview: PixelMap | None = None, exif: bool = False
             ) -> np.ndarray:
        """Decode an image (:func:`read_image`) for :meth:`warp`, and return it, as its EXIF
        ``orientation`` displays it (:func:`displayed_pixels`; 1: as stored). ``exif``: also
        keep its EXIF for its output (:attr:`exif`, :attr:`exif_problem`), from the bytes
        read for decoding (no read of its own).

        ``preview``: the map the image will be warped by, given when the output may be made
        from a reduced input (an output smaller than the input, antialiased): a JPEG is then
        decoded reduced in the DCT by :func:`preview_reduction` (as far as
        :func:`jpeg_reduction` allows; :attr:`reduction` says how far), at a fraction of a
        full decode's cost, and :meth:`warp` maps onto the reduced pixels. Other files, and
        maps that do not shrink every sampled pixel by 2 or more, decode whole.

        The previous image is dropped first, so a failure never leaves its pixels behind.
        """
        from ..io.jpeg_stream import (
            ICC_COLOUR_SPACES,
            icc_colour_space,
            icc_segments,
            jpeg_components,
        )
        from ..io.metadata import MetadataError, photo_exif

        self._decoded, self._padded, self._reduced = None, False, (1, (0.0, 0.0))
        self.exif, self.exif_problem = None, None
        data = read_file_bytes(path)
        if exif:
            try:
                self.exif = photo_exif(data)
            except MetadataError as error:
                self.exif_problem = str(error)
        self._icc = icc_segments(data)
        if icc_colour_space(self._icc) != ICC_COLOUR_SPACES.get(jpeg_components(data)):
            self._icc = b""  # a profile that does not describe its own JPEG describes nothing
        size = header_size(data) if data[:3] == b"\xff\xd8\xff" else None
        if size is not None and size[0] * size[1] <= max_pixels:
            reduction = 1
            if preview is not None:
                shown = (size[1], size[0]) if orientation_steps(orientation)[0] else size
                reduction = jpeg_reduction(data, preview_reduction(preview, shown))
            width, height = reduced_size(*size, reduction)
            into = self.array(1, (width * height * 4,), np.uint8)
            image = decode_image(data, max_pixels, padded=True, into=into,
                                 reduction=reduction)
            self._reduced = reduction, _reduced_offset(orientation, size, reduction)
            self._padded = image.ndim == 3 and image.shape[2] == 4
        else:
            # Both regions are given back before OpenCV decodes: its own frames reuse their
            # memory (kept in the heap by keep_freed_memory), and the regions are rebuilt from
            # the memory it frees. Holding them across the decode costs two frames more.
            self._regions = [np.empty(0, np.uint8), np.empty(0, np.uint8)]
            image = decode_image(data, max_pixels)
        if orientation != 1:  # turned into memory of its own (the regions hold stored pixels)
            image = displayed_pixels(image, orientation)
        self._decoded = image
        return image[..., :3] if self._padded else image

    def warp(
        self,
        pixel_map: PixelMap,
        interpolation: str = "linear",
        fill: float = 0.0,
        alpha: bool = False,
        antialias: bool = False,
    ) -> Working:
        """Warp the image :meth:`read` decoded (see :func:`warp_working`). ``pixel_map``: from
        the whole input as displayed, even when :meth:`read` decoded it reduced (the map is
        then turned onto the reduced pixels, :meth:`~gsrwt_cli.geometry.pixelmap.PixelMap.
        reduced`)."""
        image, padded_jpeg = self._decoded, self._padded
        self._decoded, self._padded = None, False
        if image is None:
            raise RuntimeError("Scratch.warp needs an image from Scratch.read first")
        reduction, offset = self._reduced
        if reduction > 1:
            pixel_map = pixel_map.reduced(reduction, offset)
        width, height = pixel_map.size
        channels = 1 if image.ndim == 2 else image.shape[2]
        converts = channels == 3 or (alpha and channels == 1)
        if padded_jpeg:  # its opaque fourth channel is the padding, or the alpha asked for
            source = Working(image, padded=not alpha)
        elif converts:
            padded = self.array(1, (*image.shape[:2], 4), image.dtype)
            source = to_working(image, alpha, padded)
            del image  # free the decoded pixels before the warp allocates
        else:
            source = to_working(image, alpha)
        out_shape = (height, width, *source.pixels.shape[2:])
        out = self.array(0, out_shape, source.pixels.dtype)
        return warp_working(source, pixel_map, interpolation, fill, alpha, out, antialias)

    def encode(self, warped: Working, extension: str, quality: int = 95,
               segments: bytes = b"") -> bytes:
        """:func:`encode_image` of what :meth:`warp` gave; a JPEG made from a JPEG keeps its
        colour profile (the input's ICC segments, as they were) where its colour model is
        kept: the profile's colour space is the input's and the output's (grey in, grey out;
        RGB in, RGB out). A CMYK JPEG, decoded to BGR, loses its CMYK profile. ``segments``:
        more marker segments for a JPEG's header (its EXIF and XMP), put before the profile
        in the same insertion (one copy of the encoded image, not two)."""
        from ..io.jpeg_stream import ICC_COLOUR_SPACES, icc_colour_space, with_segments

        encoded = encode_image(warped, extension, quality)
        if canonical_extension(extension) != ".jpg":
            return encoded
        channels = 3 if warped.padded else 1 if warped.pixels.ndim == 2 else (
            warped.pixels.shape[2])
        if self._icc and icc_colour_space(self._icc) == ICC_COLOUR_SPACES.get(channels):
            segments += self._icc
        return with_segments(encoded, segments)


def _reduced_offset(orientation: int, stored_size: tuple[int, int], reduction: int
                    ) -> tuple[float, float]:
    """What :meth:`~gsrwt_cli.geometry.pixelmap.PixelMap.reduced` adds to a displayed image's
    reduced pixels when the stored image was reduced and then turned: along a displayed
    axis counted from the other side (mirrored), a side ``reduction`` does not divide puts
    the reduced image's part pixel first, shifting it by what that pixel lacks."""
    swap, flip_x, flip_y = orientation_steps(orientation)
    width, height = (stored_size[1], stored_size[0]) if swap else stored_size
    small_width, small_height = reduced_size(width, height, reduction)
    return (small_width - width / reduction if flip_x else 0.0,
            small_height - height / reduction if flip_y else 0.0)


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
