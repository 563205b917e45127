"""Camera calibration files: OpenCV ``FileStorage`` YAML/XML and ROS ``camera_info`` YAML.

:func:`load_camera` reads the intrinsics a calibration tool wrote (spec section 6) into an
:class:`~gsrwt_cli.camera.Intrinsics` with its :class:`~gsrwt_cli.camera.Lens`;
:func:`write_opencv_yaml`, :func:`write_opencv_xml` and :func:`write_ros_yaml` write them
back as those tools do.

Formats
-------
- **OpenCV** (``cv2.FileStorage``, as ``calibrateCamera``'s samples write it): a
  ``camera_matrix`` (also ``cameraMatrix``, ``Camera_Matrix``) 3x3 ``opencv-matrix``, a
  ``distortion_coefficients`` (also ``dist_coeffs``, ``Distortion_Coefficients``) matrix of
  4, 5, 8, 12 or 14 values in OpenCV's order ``k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[,
  tau_x, tau_y]]]]`` (4 or 5: ``plumb_bob``, more: ``rational_polynomial``), and
  ``image_width``, ``image_height`` (or ``cameraResolution: [w, h]`` as OpenCV's interactive
  calibration writes it). OpenCV's files do not name the lens model; an optional
  ``distortion_model`` string does (``equidistant``/``fisheye`` for ``cv2.fisheye``'s k1..k4).
  Read by OpenCV's own parser, after checks that keep it safe (size, nesting).
- **ROS** ``camera_info`` (``camera_calibration_parsers``): ``image_width``,
  ``image_height``, ``camera_matrix: {rows: 3, cols: 3, data: [...]}``,
  ``distortion_model`` (``plumb_bob``, ``rational_polynomial``, ``equidistant``, and the
  aliases ``radtan``, ``fisheye``) and ``distortion_coefficients: {rows: 1, cols: N, data:
  [...]}``; read by :func:`~gsrwt_cli.safe_yaml.load_yaml`. ``rectification_matrix`` and
  ``projection_matrix`` (stereo rectification) are not the raw camera and are ignored.

Convention
----------
``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`` in OpenCV's pixel convention (``(col, row)``,
pixel centres at integers), the convention of both formats; the skew ``K[0, 1]`` is kept.
All-zero distortion is a pinhole (``lens`` None), as :class:`Intrinsics` makes it.

Every problem is a :class:`CalibrationError` naming the file and the key.

Over 400 lines: two formats, each read and written, with an error naming the key for every
way a file can be wrong.
"""

from __future__ import annotations

import math
import numbers
import re
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from .camera import LENS_MODELS, Intrinsics, Lens, ViewError
from .messages import one_line, quote
from .safe_yaml import YamlInputError, load_yaml
from .storage import open_input

#: Calibration files larger than this are refused unread (a real one is a few kilobytes;
#: OpenCV's sample with per-view extrinsics is 5 KB).
MAX_FILE_BYTES = 1 << 20
#: Deepest nesting of brackets or XML elements handed to OpenCV's parser (a calibration file
#: needs 2). OpenCV's parsers recurse without a bound and crash the process (a segmentation
#: fault, not an exception) on about 100 000 nested ``[`` or elements.
MAX_NESTING = 64
#: Deepest indentation, in columns, of a line handed to OpenCV's YAML parser (block nesting).
MAX_INDENT = 256
#: The principal point may lie outside the image (a crop), but not more than this many image
#: sides beyond it: further, the matrix does not describe an image of that size.
MAX_PRINCIPAL_POINT_SIDES = 1.0
#: Distortion vector lengths each model accepts (OpenCV takes 4, 5, 8, 12 or 14 values;
#: ``cv2.fisheye`` exactly 4); an empty vector means no distortion.
LENGTHS = {
    "plumb_bob": (4, 5),
    "rational_polynomial": (8, 12, 14),
    "equidistant": (4,),
}

# The keys each format's writers use, with the spellings OpenCV's own tools and samples use.
_CAMERA_MATRIX_KEYS = ("camera_matrix", "cameraMatrix", "Camera_Matrix")
_DISTORTION_KEYS = ("distortion_coefficients", "dist_coeffs", "Distortion_Coefficients")
_WIDTH_KEYS = ("image_width", "image_Width")
_HEIGHT_KEYS = ("image_height", "image_Height")
_RESOLUTION_KEY = "cameraResolution"
_MODEL_KEY = "distortion_model"

_OPENCV_SIGNS = re.compile(
    rb"\A\s*(%YAML:|<\?xml|<opencv_storage>)|!!opencv-(nd-)?matrix|\"opencv-(nd-)?matrix\""
)
_XML_TAG = re.compile(r"<(/?)[A-Za-z_][^\s/>]*[^>]*?(/?)>")
_CV_WHERE = re.compile(r"^\((\d+)\): (.*)$", re.DOTALL)


class CalibrationError(ValueError):
    """A calibration file that cannot be used: ``path``, the ``key`` at fault (or None for the
    file as a whole) and the ``reason``, as in ``camera.yaml: key 'camera_matrix': expected
    3x3 numbers, got 2x3``."""

    def __init__(self, path: str | Path, key: str | None, reason: str) -> None:
        self.path, self.key, self.reason = str(path), key, reason
        where = one_line(self.path, 200)
        if key is not None:
            where = f"{where}: key {quote(key)}"
        super().__init__(f"{where}: {reason}")


# --------------------------------------------------------------------------------------------
# Reading


def load_camera(path: str | Path) -> Intrinsics:
    """The intrinsics (and lens) in the calibration file ``path``, OpenCV or ROS format.

    The format is told by the content: OpenCV's YAML header (``%YAML:1.0``), XML, or an
    ``opencv-matrix`` make it OpenCV's; any other YAML is read as ROS ``camera_info``.
    Raises :class:`CalibrationError` naming the file and the key.
    """
    text = _read_text(path)
    if _OPENCV_SIGNS.search(text.encode("utf-8", "surrogatepass")):
        fields = _read_opencv(path, text)
    else:
        fields = _read_ros(path, text)
    return _intrinsics(path, **fields)


def _read_text(path: str | Path) -> str:
    try:
        with open_input(path) as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except IsADirectoryError:
        raise CalibrationError(path, None, "is a directory, not a calibration file") from None
    except OSError as error:
        raise CalibrationError(path, None, f"cannot read ({error.strerror or error})") from None
    if len(data) > MAX_FILE_BYTES:
        raise CalibrationError(
            path, None, f"larger than {MAX_FILE_BYTES} bytes: not a calibration file"
        )
    if not data.strip():
        raise CalibrationError(path, None, "empty file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise CalibrationError(
            path, None, f"not UTF-8 text (byte {error.start}): not a calibration file"
        ) from None
    if "\x00" in text:
        raise CalibrationError(path, None, "contains NUL characters: not a calibration file")
    return text.removeprefix("\ufeff")


def _check_nesting(path: str | Path, text: str) -> None:
    """Refuse text nested deeper than OpenCV's recursive parsers should see.

    Counts every bracket and every XML element, inside strings and comments too: an
    over-estimate, which only refuses files no calibration tool writes.
    """
    depth = deepest = 0
    if text.lstrip().startswith("<"):
        for match in _XML_TAG.finditer(text):
            closing, empty = match.group(1), match.group(2)
            depth += -1 if closing else 0 if empty else 1
            deepest = max(deepest, depth)
    else:
        for char in re.findall(r"[\[\]{}]", text):
            depth += 1 if char in "[{" else -1
            deepest = max(deepest, depth)
        indent = max((len(line) - len(line.lstrip(" ")) for line in text.splitlines()), default=0)
        if indent > MAX_INDENT:
            raise CalibrationError(
                path, None, f"a line is indented {indent} columns (at most {MAX_INDENT})"
            )
    if deepest > MAX_NESTING:
        raise CalibrationError(path, None, f"nested deeper than {MAX_NESTING} levels")


def _cv_reason(error: BaseException) -> str:
    """OpenCV's parse error as ``line N: problem`` (in-memory storages have no file name)."""
    cause = error.__cause__ if isinstance(error, SystemError) else error
    if isinstance(cause, cv2.error):
        where = _CV_WHERE.match(str(getattr(cause, "func", "")).strip())
        if where:
            return f"line {where.group(1)}: {one_line(where.group(2), 160)}"
        return one_line(str(getattr(cause, "err", "")) or str(cause).strip(), 160)
    return one_line(str(error), 160)


def _read_opencv(path: str | Path, text: str) -> dict[str, Any]:
    """The raw fields of an OpenCV FileStorage file (YAML, XML or JSON)."""
    _check_nesting(path, text)
    try:
        storage = cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)
    except (cv2.error, SystemError) as error:
        raise CalibrationError(
            path, None, f"not a valid OpenCV FileStorage file ({_cv_reason(error)})"
        ) from None
    try:
        root = storage.root()
        if not root.isMap():
            raise CalibrationError(path, None, "expected a mapping of keys at the top level")
        keys = list(root.keys())
        for key in keys:
            if keys.count(key) > 1:
                raise CalibrationError(path, key, "given twice")
        matrix_key = _one_of(path, keys, _CAMERA_MATRIX_KEYS, required=True)
        matrix = _opencv_matrix(path, matrix_key, root.getNode(matrix_key), (3, 3))
        distortion_key = _one_of(path, keys, _DISTORTION_KEYS)
        distortion = None
        if distortion_key is not None:
            distortion = _opencv_matrix(
                path, distortion_key, root.getNode(distortion_key), None
            )
        model = None
        if _MODEL_KEY in keys:
            model = _opencv_string(path, _MODEL_KEY, root.getNode(_MODEL_KEY))
        width_key = _one_of(path, keys, _WIDTH_KEYS)
        height_key = _one_of(path, keys, _HEIGHT_KEYS)
        width = height = None
        size_keys = (width_key or "image_width", height_key or "image_height")
        if width_key is not None:
            width = _opencv_number(path, width_key, root.getNode(width_key))
        if height_key is not None:
            height = _opencv_number(path, height_key, root.getNode(height_key))
        if width is None and height is None and _RESOLUTION_KEY in keys:
            width, height = _opencv_size(path, _RESOLUTION_KEY, root.getNode(_RESOLUTION_KEY))
            size_keys = (_RESOLUTION_KEY, _RESOLUTION_KEY)
    finally:
        storage.release()
    return {
        "matrix": matrix, "matrix_key": matrix_key,
        "distortion": distortion, "distortion_key": distortion_key or _DISTORTION_KEYS[0],
        "model": model, "width": width, "height": height, "size_keys": size_keys,
    }


def _one_of(
    path: str | Path, keys: list[str], spellings: tuple[str, ...], required: bool = False
) -> str | None:
    present = [key for key in spellings if key in keys]
    if len(present) > 1:
        raise CalibrationError(
            path, present[1], f"given besides {quote(present[0])}: give one of them"
        )
    if not present:
        if required:
            others = ", ".join(quote(key) for key in spellings[1:])
            raise CalibrationError(
                path, spellings[0], f"missing (also accepted: {others})"
            )
        return None
    return present[0]


def _opencv_matrix(
    path: str | Path, key: str, node: cv2.FileNode, shape: tuple[int, int] | None
) -> np.ndarray:
    """An ``opencv-matrix`` node (or an ``opencv-nd-matrix`` of 1 or 2 dimensions, as
    ``FileStorage.write`` stores a 1-D numpy array) as float64, its size checked before
    OpenCV allocates it. ``shape`` None: a vector (one row or column) of at most 14 values.
    """
    if not node.isMap() or node.getNode("data").isNone():
        raise CalibrationError(path, key, "expected an opencv-matrix (rows, cols, dt, data)")
    sizes = node.getNode("sizes")
    if not sizes.isNone():  # opencv-nd-matrix
        if not sizes.isSeq() or sizes.size() not in (1, 2):
            raise CalibrationError(path, key, "expected sizes of 1 or 2 dimensions")
        dims = [_opencv_number(path, f"{key}.sizes", sizes.at(i)) for i in range(sizes.size())]
        rows, cols = (1.0, dims[0]) if len(dims) == 1 else dims
    else:
        rows = _opencv_number(path, f"{key}.rows", node.getNode("rows"))
        cols = _opencv_number(path, f"{key}.cols", node.getNode("cols"))
    if rows is None or cols is None:
        raise CalibrationError(path, key, "expected an opencv-matrix with rows and cols")
    data = node.getNode("data")
    _check_shape(path, key, rows, cols, shape, data.size() if data.isSeq() else 1)
    try:
        matrix = node.mat()
    except (cv2.error, SystemError) as error:
        raise CalibrationError(path, key, f"not a readable matrix ({_cv_reason(error)})") from None
    if matrix is None:
        if rows * cols == 0:
            return np.zeros((0,), dtype=np.float64)
        raise CalibrationError(path, key, "not a readable matrix")
    matrix = np.asarray(matrix, dtype=np.float64)
    if matrix.ndim == 1 and matrix.size == rows * cols:  # a 1-D opencv-nd-matrix
        matrix = matrix.reshape(int(rows), int(cols))
    if matrix.ndim != 2 or matrix.shape != (rows, cols):  # multi-channel data, for one
        raise CalibrationError(
            path, key, f"expected {rows:g}x{cols:g} numbers of one channel, got shape "
            f"{matrix.shape}"
        )
    return matrix if shape is not None else matrix.reshape(-1)


def _check_shape(path: str | Path, key: str, rows: float, cols: float,
                 shape: tuple[int, int] | None, count: int) -> None:
    """A matrix's declared ``rows x cols``: ``shape`` if given, else one row or column of at
    most 14 numbers (a distortion vector), holding ``count`` values."""
    if shape is not None and (rows, cols) != shape:
        raise CalibrationError(
            path, key, f"expected {shape[0]}x{shape[1]} numbers, got {rows:g}x{cols:g}"
        )
    if shape is None and not (min(rows, cols) <= 1 and max(rows, cols) <= 14):
        raise CalibrationError(
            path, key, f"expected one row or column of at most 14 numbers, got {rows:g}x{cols:g}"
        )
    if count != rows * cols:
        raise CalibrationError(
            path, key, f"its data holds {count} values, not rows x cols = {rows * cols:g}"
        )


def _opencv_number(path: str | Path, key: str, node: cv2.FileNode) -> float | None:
    if node.isNone():
        return None
    if not (node.isInt() or node.isReal()):
        raise CalibrationError(path, key, "expected a number")
    return node.real()


def _opencv_string(path: str | Path, key: str, node: cv2.FileNode) -> str:
    if not node.isString():
        raise CalibrationError(path, key, "expected a string")
    return node.string()


def _opencv_size(path: str | Path, key: str, node: cv2.FileNode) -> tuple[float, float]:
    """``cameraResolution``: a cv::Size, written as the sequence ``[width, height]``."""
    if not node.isSeq() or node.size() != 2:
        raise CalibrationError(path, key, "expected [width, height]")
    values = [_opencv_number(path, key, node.at(index)) for index in range(2)]
    return values[0], values[1]


def _read_ros(path: str | Path, text: str) -> dict[str, Any]:
    """The raw fields of a ROS ``camera_info`` YAML file."""
    try:
        document = load_yaml(text)
    except YamlInputError as error:
        raise CalibrationError(path, None, f"not valid YAML ({error})") from None
    if not isinstance(document, dict):
        raise CalibrationError(
            path, None, "expected a mapping (OpenCV FileStorage or ROS camera_info YAML), got "
            f"{_kind(document)}"
        )
    if "camera_matrix" not in document:
        raise CalibrationError(path, "camera_matrix", "missing")
    matrix = _ros_matrix(path, "camera_matrix", document["camera_matrix"], (3, 3))
    distortion = None
    if "distortion_coefficients" in document and document["distortion_coefficients"] is not None:
        distortion = _ros_matrix(
            path, "distortion_coefficients", document["distortion_coefficients"], None
        )
    model = document.get(_MODEL_KEY)
    if model is not None and not isinstance(model, str):
        raise CalibrationError(path, _MODEL_KEY, f"expected a string, got {quote(model)}")
    if distortion is not None and distortion.size and model is None:
        raise CalibrationError(
            path, _MODEL_KEY, "missing: ROS names the model of its distortion_coefficients "
            f"({', '.join(LENS_MODELS)})"
        )
    width, height = (_ros_number(path, key, document.get(key)) for key in _WIDTH_KEYS[:1] +
                     _HEIGHT_KEYS[:1])
    return {
        "matrix": matrix, "matrix_key": "camera_matrix",
        "distortion": distortion, "distortion_key": "distortion_coefficients",
        "model": model, "width": width, "height": height,
        "size_keys": ("image_width", "image_height"),
    }


def _kind(value: object) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, list):
        return "a list"
    return quote(value)


def _ros_number(path: str | Path, key: str, value: object) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise CalibrationError(path, key, f"expected a number, got {quote(value)}")
    try:
        return float(value)
    except OverflowError:
        raise CalibrationError(path, key, f"expected a finite number, got {quote(value)}") from None


def _ros_matrix(
    path: str | Path, key: str, value: object, shape: tuple[int, int] | None
) -> np.ndarray:
    """``{rows, cols, data}`` as float64; ``shape`` None: a vector of at most 14 values."""
    if not isinstance(value, dict) or not {"rows", "cols", "data"} <= set(value):
        raise CalibrationError(path, key, f"expected a mapping with rows, cols and data, got "
                               f"{_kind(value)}")
    rows = _ros_number(path, f"{key}.rows", value["rows"])
    cols = _ros_number(path, f"{key}.cols", value["cols"])
    if rows is None or cols is None:
        raise CalibrationError(path, key, "expected numbers for rows and cols")
    data = value["data"]
    if not isinstance(data, list):
        raise CalibrationError(path, f"{key}.data", f"expected a list of numbers, got "
                               f"{_kind(data)}")
    _check_shape(path, key, rows, cols, shape, len(data))
    numbers_ = [_ros_number(path, f"{key}.data", item) for item in data]
    matrix = np.array(numbers_, dtype=np.float64)
    return matrix.reshape(shape) if shape is not None else matrix


# --------------------------------------------------------------------------------------------
# Checking


def _intrinsics(
    path: str | Path, *, matrix: np.ndarray, matrix_key: str, distortion: np.ndarray | None,
    distortion_key: str, model: str | None, width: float | None, height: float | None,
    size_keys: tuple[str, str],
) -> Intrinsics:
    """The checked :class:`Intrinsics` of the raw fields, errors naming the file's keys."""
    if not np.all(np.isfinite(matrix)):
        raise CalibrationError(path, matrix_key, "holds a value that is not a finite number")
    if matrix[1, 0] != 0 or matrix[2, 0] != 0 or matrix[2, 1] != 0 or matrix[2, 2] != 1:
        raise CalibrationError(
            path, matrix_key, "expected [[fx, skew, cx], [0, fy, cy], [0, 0, 1]], got rows "
            f"2 and 3 {_row(matrix[1])} {_row(matrix[2])}"
        )
    if (width is None) != (height is None):
        missing = size_keys[1] if height is None else size_keys[0]
        raise CalibrationError(path, missing, "missing (the image size needs width and height)")
    lens = _lens(path, distortion, distortion_key, model)
    field_keys = {
        "fx": matrix_key, "fy": matrix_key, "cx": matrix_key, "cy": matrix_key,
        "skew": matrix_key, "width": size_keys[0], "height": size_keys[1],
    }
    try:
        intrinsics = Intrinsics(
            fx=float(matrix[0, 0]), fy=float(matrix[1, 1]), cx=float(matrix[0, 2]),
            cy=float(matrix[1, 2]), skew=float(matrix[0, 1]), width=width, height=height,
            lens=lens,
        )
    except ViewError as error:
        raise CalibrationError(path, field_keys.get(error.field, matrix_key), str(error)) from None
    if intrinsics.width is not None:
        for name, value, side in (("cx", intrinsics.cx, intrinsics.width),
                                  ("cy", intrinsics.cy, intrinsics.height)):
            reach = MAX_PRINCIPAL_POINT_SIDES * side
            if not -reach <= value <= side - 1 + reach:
                raise CalibrationError(
                    path, matrix_key, f"the principal point's {name} = {value:.15g} lies more "
                    f"than {MAX_PRINCIPAL_POINT_SIDES:g} image side(s) outside the "
                    f"{intrinsics.width}x{intrinsics.height} image"
                )
    return intrinsics


def _row(values: np.ndarray) -> str:
    return "[" + ", ".join(f"{value:.6g}" for value in values) + "]"


def _lens(
    path: str | Path, distortion: np.ndarray | None, key: str, model: str | None
) -> Lens | None:
    """The :class:`Lens` of a distortion vector in OpenCV's order (None: a pinhole)."""
    if model is not None:
        try:
            model = Lens(model).model  # aliases resolved, unknown names refused
        except ViewError as error:
            raise CalibrationError(path, _MODEL_KEY, str(error)) from None
    if distortion is None or distortion.size == 0:
        return None
    count = distortion.size
    if not np.all(np.isfinite(distortion)):
        raise CalibrationError(path, key, "holds a value that is not a finite number")
    if model is None:
        model = "plumb_bob" if count in LENGTHS["plumb_bob"] else "rational_polynomial"
    if count not in LENGTHS[model]:
        lengths = " or ".join(str(length) for length in LENGTHS[model])
        raise CalibrationError(
            path, key, f"the {model} model takes {lengths} coefficients, got {count}"
        )
    names = LENS_MODELS[model][:count]
    try:
        return Lens(model, tuple(zip(names, (float(value) for value in distortion))))
    except ViewError as error:
        raise CalibrationError(path, key, str(error)) from None


# --------------------------------------------------------------------------------------------
# Writing


def _coefficients(intrinsics: Intrinsics) -> np.ndarray:
    if intrinsics.lens is None:
        return np.zeros(5)
    return intrinsics.lens.opencv_coefficients()


def _opencv_text(intrinsics: Intrinsics, suffix: str) -> str:
    storage = cv2.FileStorage(
        f"camera{suffix}", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY
    )
    if intrinsics.width is not None:
        storage.write("image_width", int(intrinsics.width))
        storage.write("image_height", int(intrinsics.height))
    storage.write("camera_matrix", intrinsics.matrix())
    if intrinsics.lens is not None and intrinsics.lens.is_fisheye:
        storage.write(_MODEL_KEY, intrinsics.lens.model)  # OpenCV's files cannot tell it
    storage.write("distortion_coefficients", _coefficients(intrinsics).reshape(1, -1))
    return storage.releaseAndGetString()


def write_opencv_yaml(path: str | Path, intrinsics: Intrinsics) -> None:
    """Write ``intrinsics`` as OpenCV's calibration sample does, in FileStorage YAML.

    ``image_width``, ``image_height``, ``camera_matrix``, ``distortion_coefficients`` (one
    row; 5 zeros for a pinhole) and, for the fisheye model only, ``distortion_model``.
    """
    Path(path).write_text(_opencv_text(intrinsics, ".yml"), encoding="utf-8")


def write_opencv_xml(path: str | Path, intrinsics: Intrinsics) -> None:
    """:func:`write_opencv_yaml` in FileStorage XML."""
    Path(path).write_text(_opencv_text(intrinsics, ".xml"), encoding="utf-8")


def write_ros_yaml(path: str | Path, intrinsics: Intrinsics, camera_name: str = "camera") -> None:
    """Write ``intrinsics`` as ROS's ``camera_calibration_parsers`` writes ``camera_info``.

    A pinhole is written as ``plumb_bob`` with 5 zeros; the rectification matrix is the
    identity and the projection matrix ``[K | 0]`` (a monocular camera).
    """
    if intrinsics.width is None:
        raise ValueError("a ROS camera_info file needs the image size")
    lens = intrinsics.lens
    model = "plumb_bob" if lens is None else lens.model
    coefficients = _coefficients(intrinsics)
    matrix = intrinsics.matrix()
    projection = np.hstack([matrix, np.zeros((3, 1))])

    def block(values: np.ndarray, rows: int, cols: int) -> dict[str, Any]:
        return {"rows": rows, "cols": cols, "data": [float(value) for value in values.ravel()]}

    document = {
        "image_width": int(intrinsics.width),
        "image_height": int(intrinsics.height),
        "camera_name": camera_name,
        "camera_matrix": block(matrix, 3, 3),
        "distortion_model": model,
        "distortion_coefficients": block(coefficients, 1, len(coefficients)),
        "rectification_matrix": block(np.eye(3), 3, 3),
        "projection_matrix": block(projection, 3, 4),
    }
    text = yaml.safe_dump(document, default_flow_style=None, sort_keys=False)
    Path(path).write_text(text, encoding="utf-8")


def intrinsics_close(a: Intrinsics, b: Intrinsics, tolerance: float = 1e-9) -> bool:
    """Whether two intrinsics agree to ``tolerance`` (relative, and absolute near 0)."""
    def close(x: float | None, y: float | None) -> bool:
        if x is None or y is None:
            return x is y
        return math.isclose(x, y, rel_tol=tolerance, abs_tol=tolerance)

    fields = ("fx", "fy", "cx", "cy", "skew", "width", "height")
    if not all(close(getattr(a, name), getattr(b, name)) for name in fields):
        return False
    if (a.lens is None) != (b.lens is None):
        return False
    if a.lens is None:
        return True
    names = LENS_MODELS[a.lens.model]
    return a.lens.model == b.lens.model and all(
        close(a.lens.value(name), b.lens.value(name)) for name in names
    )
