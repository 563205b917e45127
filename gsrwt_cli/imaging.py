"""Image files and pixels: read any depth and channel layout, warp with OpenCV, write atomically."""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import dataclass, field
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

_UMASK = os.umask(0)
os.umask(_UMASK)

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


def _check_complete(data: np.ndarray) -> None:
    """Detect truncated JPEG and PNG files, which OpenCV would decode partially."""
    head = bytes(data[:8])
    tail = bytes(data[-64:]).rstrip(b"\x00")
    if head[:3] == b"\xff\xd8\xff" and not tail.endswith(b"\xff\xd9"):
        raise ImageError("truncated JPEG (no end-of-image marker)")
    if head == b"\x89PNG\r\n\x1a\n" and b"IEND" not in tail:
        raise ImageError("truncated PNG (no IEND chunk)")


def read_image(path: str | Path) -> np.ndarray:
    """Read an image file as it is stored: 8/16-bit or float, grey, colour (BGR) or BGRA.

    Raises :class:`ImageError` for a file that is empty, truncated or not decodable.
    Reads through numpy so that non-ASCII paths work; EXIF orientation is not applied
    (pan and tilt describe the sensor, not the display).
    """
    try:
        data = np.fromfile(str(path), dtype=np.uint8)
    except OSError as error:
        raise ImageError(f"cannot read ({error.strerror or error})") from None
    if data.size == 0:
        raise ImageError("empty file")
    _check_complete(data)
    image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    if image is None or image.size == 0:
        raise ImageError("not an image OpenCV can decode (corrupt or unsupported)")
    if image.ndim == 3 and image.shape[2] == 2:  # grey + alpha
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGRA)  # pragma: no cover - OpenCV expands
    return image


@dataclass
class Workspace:
    """Buffers reused from one image to the next (one per worker) to avoid page faults."""

    buffers: dict[tuple, np.ndarray] = field(default_factory=dict)

    def get(self, name: str, shape: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
        key = (name, shape, np.dtype(dtype).str)
        buffer = self.buffers.get(key)
        if buffer is None:
            self.buffers = {k: v for k, v in self.buffers.items() if k[0] != name}
            buffer = self.buffers[key] = np.empty(shape, dtype)
        return buffer


def _full_value(dtype: np.dtype) -> float:
    return float(np.iinfo(dtype).max) if np.issubdtype(dtype, np.integer) else 1.0


def warp_image(
    image: np.ndarray,
    output_from_input: Matrix,
    size: tuple[int, int],
    interpolation: str = "linear",
    fill: float = 0.0,
    alpha: bool = False,
    workspace: Workspace | None = None,
) -> np.ndarray:
    """Backward-map ``image`` through a homography in one OpenCV pass (thesis Sec. 5.1).

    ``size`` is ``(width, height)`` of the output. Output pixels with no source get ``fill``
    (in the image's own units); with ``alpha`` they become transparent instead, and an
    alpha channel is added if the image had none. Output pixels that map to the far side of
    the vanishing line (``w <= 0``, what the camera saw beyond the wall's horizon) get the
    fill as well: ``output_from_input`` must be scaled so that ``w > 0`` where the wall is
    visible, as the framing module's homographies are. Colour images are warped as four
    channels, which OpenCV does about twice as fast as three.
    """
    width, height = size
    flags = INTERPOLATIONS[interpolation]
    dtype = image.dtype
    opaque = _full_value(dtype)
    channels = 1 if image.ndim == 2 else image.shape[2]
    if alpha and channels in (1, 3):
        source = cv2.cvtColor(image, cv2.COLOR_GRAY2BGRA if channels == 1 else cv2.COLOR_BGR2BGRA)
    elif channels == 3:
        source = _buffer(workspace, "source", (*image.shape[:2], 4), dtype)
        cv2.cvtColor(image, cv2.COLOR_BGR2BGRA, dst=source)
    else:
        source = image
    work_channels = 1 if source.ndim == 2 else source.shape[2]
    # No source: the fill colour, opaque unless --alpha asks for transparency.
    border = [fill] * min(work_channels, 3) + [0.0 if alpha else opaque] * (work_channels == 4)
    warped = _buffer(workspace, "warped", (height, width, work_channels)[: source.ndim], dtype)
    cv2.warpPerspective(
        source,
        np.asarray(output_from_input, dtype=np.float64),
        (width, height),
        dst=warped,
        flags=flags,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=tuple(border + [0.0] * (4 - len(border))),
    )
    _fill_beyond_horizon(warped, output_from_input, border)
    if image.ndim == 3 and image.shape[2] == 3 and not alpha:
        result = np.empty((height, width, 3), dtype)
        return cv2.cvtColor(warped, cv2.COLOR_BGRA2BGR, dst=result)
    return warped.copy() if workspace is not None else warped


def _buffer(workspace: Workspace | None, name: str, shape: tuple[int, ...], dtype) -> np.ndarray:
    if workspace is None:
        return np.empty(shape, dtype)
    return workspace.get(name, shape, dtype)


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


def encode_image(image: np.ndarray, extension: str, quality: int = 95) -> bytes:
    """Encode pixels as a file of type ``extension``; JPEG and WebP at ``quality`` (1-100)."""
    ext = canonical_extension(extension)
    channels = 1 if image.ndim == 2 else image.shape[2]
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


def write_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that no reader ever sees a partial file.

    The bytes go to a hidden temporary file in the same directory, which is then renamed
    over ``path`` (``os.replace`` is atomic within a file system). On failure the temporary
    file is removed and ``path`` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.name}.", suffix=".part"
    )
    try:
        with os.fdopen(descriptor, "wb") as handle:
            handle.write(data)
        os.chmod(temporary, 0o666 & ~_UMASK)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
