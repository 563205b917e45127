"""Camera calibration files: OpenCV ``FileStorage`` YAML/XML and ROS ``camera_info`` YAML.

:func:`load_camera` reads the intrinsics a calibration tool wrote into an
:class:`~gsrwt_cli.geometry.camera.Intrinsics` with its :class:`~gsrwt_cli.geometry.camera.Lens`;
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
  Read in Python (YAML by :mod:`~gsrwt_cli.io.safe_yaml`, XML by ``xml.etree`` without DOCTYPEs,
  JSON by
  ``json``), never by OpenCV's parser, which trusts the file: a matrix with negative
  ``sizes`` crashed the process. Every node is checked before it is used (sizes whole numbers
  from 0, ``dt`` one channel, data as long as the sizes say, values of the type).
- **ROS** ``camera_info`` (``camera_calibration_parsers``): ``image_width``,
  ``image_height``, ``camera_matrix: {rows: 3, cols: 3, data: [...]}``,
  ``distortion_model`` (``plumb_bob``, ``rational_polynomial``, ``equidistant``, and the
  aliases ``radtan``, ``fisheye``) and ``distortion_coefficients: {rows: 1, cols: N, data:
  [...]}``; read by :func:`~gsrwt_cli.io.safe_yaml.load_yaml`. ``rectification_matrix`` and
  ``projection_matrix`` (stereo rectification) are not the raw camera and are ignored.

Convention
----------
``K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`` in OpenCV's pixel convention (``(col, row)``,
pixel centres at integers), the convention of both formats; the skew ``K[0, 1]`` is kept.
All-zero distortion is a pinhole (``lens`` None), as :class:`Intrinsics` makes it.

Every problem is a :class:`CalibrationError` naming the file and the key; what it quotes of
the file is a short escaped token (:func:`~gsrwt_cli.base.messages.token`), since a sidecar may name
any file (``/etc/passwd``). A local file must be a regular file: a FIFO or a device is refused
unread.

Over 400 lines: two formats, each read and written, with an error naming the key for every
way a file can be wrong.
"""

from __future__ import annotations

import json
import math
import numbers
import os
import re
import stat
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from ..base.messages import one_line, quote, token
from ..geometry.camera import Intrinsics, ViewError
from ..geometry.lens import LENS_ALIASES, LENS_MODELS, Lens
from ..io.storage import location, open_input

#: Calibration files larger than this are refused unread (a real one is a few kilobytes;
#: OpenCV's sample with per-view extrinsics is 5 KB).
MAX_FILE_BYTES = 1 << 20
#: Deepest nesting of brackets or XML elements read (a calibration file needs 2; the readers
#: recurse).
MAX_NESTING = 64
#: Deepest indentation, in columns, of a line read (YAML block nesting).
MAX_INDENT = 256
#: Largest ``rows``, ``cols`` or ``sizes`` entry read (a calibration matrix has 3 or 14).
MAX_DIMENSION = 1_000_000
#: OpenCV's element types (``dt``) of one channel, as numpy types: what a matrix may hold.
_ELEMENT_TYPES = {"u": np.uint8, "c": np.int8, "w": np.uint16, "s": np.int16, "i": np.int32,
                  "f": np.float32, "d": np.float64, "h": np.float16}
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
_XML_DECLARATION = re.compile(r"<!(?!--|\[CDATA\[)")
_XML_TOKEN = re.compile(r'"[^"]*"|\S+')
_YAML_HEADER = re.compile(r"\A%YAML[: ][^\r\n]*")
_INTEGER = re.compile(r"[-+]?[0-9]+")
_REAL = re.compile(r"[-+]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|\.(?:nan|inf))",
                   re.IGNORECASE)
#: A quoted part of a parser's message (PyYAML's, expat's): the file's content.
_QUOTED = re.compile(r"'[^'\n]*'|\"[^\"\n]*\"")


class CalibrationError(ValueError):
    """A calibration file that cannot be used: ``path``, the ``key`` at fault (or None for the
    file as a whole) and the ``reason``, as in ``camera.yaml: key 'camera_matrix': expected
    3x3 numbers, got 2x3``."""

    def __init__(self, path: str | Path, key: str | None, reason: str) -> None:
        self.path, self.key, self.reason = str(path), key, reason
        where = one_line(self.path, 200)
        if key is not None:  # the keys read are at most 29 characters; others come from the file
            where = f"{where}: key {quote(key, 40)}"
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
    data = _read_bytes(path)
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


def _read_bytes(path: str | Path) -> bytes:
    """The first :data:`MAX_FILE_BYTES` + 1 bytes of the file ``path`` (a local path or a URL).

    A local file must be a regular file: a FIFO, a device or a socket (which a sidecar may
    name) is refused unread, before it is opened and again after (it is opened without
    blocking, so a FIFO without a writer cannot hang the batch), so nothing but a file's
    bytes is ever read.
    """
    local = location(str(path))
    if not isinstance(local, Path):
        try:
            with open_input(local) as file:
                return file.read(MAX_FILE_BYTES + 1)
        except OSError as error:
            raise CalibrationError(path, None, f"cannot read ({error.strerror or error})") from None
    try:
        _check_regular(path, os.stat(local).st_mode)
        descriptor = os.open(local, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    except OSError as error:
        raise CalibrationError(path, None, f"cannot read ({error.strerror or error})") from None
    with open(descriptor, "rb", closefd=True) as file:
        _check_regular(path, os.fstat(file.fileno()).st_mode)
        try:
            return file.read(MAX_FILE_BYTES + 1)
        except OSError as error:
            raise CalibrationError(path, None, f"cannot read ({error.strerror or error})") from None


def _check_regular(path: str | Path, mode: int) -> None:
    """Refuse a file that is not a regular file (``mode``: its ``st_mode``), naming its kind."""
    if stat.S_ISREG(mode):
        return
    if stat.S_ISDIR(mode):
        raise CalibrationError(path, None, "is a directory, not a calibration file")
    kinds = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
    kind = next((name for test, name in kinds if test(mode)), "a special file")
    raise CalibrationError(path, None, f"is {kind}, not a regular file")


def _check_nesting(path: str | Path, text: str) -> None:
    """Refuse text nested deeper than a calibration file is (the readers below recurse).

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


def _invalid(path: str | Path, line: int | None, problem: str) -> CalibrationError:
    """``not a valid OpenCV FileStorage file (line N: problem)``, every quoted part of the
    parser's ``problem`` (the file's content) cut to a short token."""
    problem = _QUOTED.sub(lambda match: token(match.group(0)[1:-1]), one_line(problem, 200))
    where = f"line {line}: " if line is not None else ""
    return CalibrationError(path, None, f"not a valid OpenCV FileStorage file ({where}{problem})")


def _read_opencv(path: str | Path, text: str) -> dict[str, Any]:
    """The raw fields of an OpenCV FileStorage file (YAML, XML or JSON).

    Read in Python, never by OpenCV's own parser: that parser trusts the file (negative
    ``sizes`` or a ``dt`` of the wrong kind crash the process), so every node is read here and
    checked before a value is used.
    """
    _check_nesting(path, text)
    start = text.lstrip()[:1]
    if start == "<":
        root = _opencv_xml(path, text)
    elif start == "{":
        root = _opencv_json(path, text)
    else:
        root = _opencv_yaml(path, text)
    if not isinstance(root, dict):
        raise CalibrationError(path, None, "expected a mapping of keys at the top level")
    keys = [key for key in root if isinstance(key, str)]
    matrix_key = _one_of(path, keys, _CAMERA_MATRIX_KEYS, required=True)
    matrix = _opencv_matrix(path, matrix_key, root[matrix_key], (3, 3))
    distortion_key = _one_of(path, keys, _DISTORTION_KEYS)
    distortion = None
    if distortion_key is not None:
        distortion = _opencv_matrix(path, distortion_key, root[distortion_key], None)
    model = None
    if _MODEL_KEY in keys:
        model = root[_MODEL_KEY]
        if not isinstance(model, str):
            raise CalibrationError(path, _MODEL_KEY, f"expected a string, got {_kind(model)}")
    width_key = _one_of(path, keys, _WIDTH_KEYS)
    height_key = _one_of(path, keys, _HEIGHT_KEYS)
    width = height = None
    size_keys = (width_key or "image_width", height_key or "image_height")
    if width_key is not None:
        width = _number(path, width_key, root[width_key])
    if height_key is not None:
        height = _number(path, height_key, root[height_key])
    if width is None and height is None and _RESOLUTION_KEY in keys:
        width, height = _opencv_size(path, _RESOLUTION_KEY, root[_RESOLUTION_KEY])
        size_keys = (_RESOLUTION_KEY, _RESOLUTION_KEY)
    return {
        "matrix": matrix, "matrix_key": matrix_key,
        "distortion": distortion, "distortion_key": distortion_key or _DISTORTION_KEYS[0],
        "model": model, "width": width, "height": height, "size_keys": size_keys,
    }


def _opencv_yaml(path: str | Path, text: str) -> Any:
    """FileStorage YAML as Python values, by the bounded loader (:mod:`~gsrwt_cli.io.safe_yaml`)."""
    from ..io.safe_yaml import YamlInputError, load_yaml  # PyYAML: only for YAML files

    text = _YAML_HEADER.sub("", text, count=1)  # "%YAML:1.0" is no YAML directive
    try:
        return load_yaml(text, opencv=True)
    except YamlInputError as error:
        if error.key is not None:
            again = f", again on line {error.line}" if error.line is not None else ""
            reason = error.problem.removeprefix(f"key {quote(error.key)} ")
            raise CalibrationError(path, error.key, f"{reason}{again}") from None
        raise _invalid(path, error.line, error.problem) from None


def _opencv_json(path: str | Path, text: str) -> Any:
    """FileStorage JSON as Python values; a key given twice is an error naming it."""
    def mapping(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        result: dict[str, Any] = {}
        for key, value in pairs:
            if key in result:
                raise CalibrationError(path, key, "given twice")
            result[key] = value
        return result

    try:
        return json.loads(text, object_pairs_hook=mapping, parse_int=_integer)
    except CalibrationError:
        raise
    except json.JSONDecodeError as error:
        raise _invalid(path, error.lineno, error.msg) from None
    except (ValueError, RecursionError) as error:
        raise _invalid(path, None, str(error)) from None


def _integer(text: str) -> int | float:
    """An integer token: as an int, or as a float (infinite, perhaps) when too long for one
    that a calibration could hold (Python refuses to convert more than 4300 digits)."""
    return int(text) if len(text) <= 20 else float(text)


def _opencv_xml(path: str | Path, text: str) -> Any:
    """FileStorage XML as Python values: an element with elements is a mapping of their tags
    (or a list, if all are ``<_>``), one of text its whitespace-separated tokens (a list of
    several; numbers as numbers, ``"quoted"`` strings without their quotes).

    A DOCTYPE is refused before the parser sees it: OpenCV writes none, and entities could
    make a small file expand.
    """
    if _XML_DECLARATION.search(text):
        raise CalibrationError(
            path, None, "has a DOCTYPE or entity declaration (OpenCV's files have none)"
        )
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        line = error.position[0] if getattr(error, "position", None) else None
        raise _invalid(path, line, str(error).split(":", 1)[0]) from None
    if root.tag != "opencv_storage":
        raise CalibrationError(path, None, "expected <opencv_storage> at the top level")
    return _xml_value(path, root, None)


def _xml_value(path: str | Path, element: ElementTree.Element, key: str | None) -> Any:
    children = list(element)
    if not children:
        tokens = [_xml_scalar(item) for item in _XML_TOKEN.findall(element.text or "")]
        return tokens[0] if len(tokens) == 1 else tokens
    if any((part or "").strip() for part in (element.text, *(child.tail for child in children))):
        raise CalibrationError(path, key, "holds both text and elements")
    if all(child.tag == "_" for child in children):
        return [_xml_value(path, child, key) for child in children]
    result: dict[str, Any] = {}
    for child in children:
        name = child.tag if key is None else f"{key}.{child.tag}"
        if child.tag in result:
            raise CalibrationError(path, name, "given twice")
        result[child.tag] = _xml_value(path, child, name)
    return result


def _xml_scalar(item: str) -> Any:
    """A token of XML text: a number, or a string (quotes removed)."""
    if item.startswith('"') and item.endswith('"') and len(item) > 1:
        return item[1:-1]
    if _INTEGER.fullmatch(item):
        return _integer(item)
    if _REAL.fullmatch(item):
        return float(item.lower().replace(".nan", "nan").replace(".inf", "inf"))
    return item


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
    path: str | Path, key: str, value: object, shape: tuple[int, int] | None
) -> np.ndarray:
    """An ``opencv-matrix`` (``rows``, ``cols``, ``dt``, ``data``) or an ``opencv-nd-matrix``
    of 1 or 2 ``sizes`` (as ``FileStorage.write`` stores a 1-D numpy array) as float64, every
    part checked: whole sizes from 0 up, a ``dt`` of one channel, as many numbers as the sizes
    say, each a value of that type. ``shape`` None: a vector (one row or column) of at most
    14 values.
    """
    if not isinstance(value, dict) or "data" not in value:
        raise CalibrationError(path, key, "expected an opencv-matrix (rows, cols, dt, data)")
    element_type = value.get("dt")
    if not isinstance(element_type, str) or (
            element_type.removeprefix("1") not in _ELEMENT_TYPES):
        raise CalibrationError(
            path, f"{key}.dt", f"expected an element type of one channel "
            f"({', '.join(_ELEMENT_TYPES)}), got {_kind(element_type)}"
        )
    if "sizes" in value:  # opencv-nd-matrix
        sizes = value["sizes"] if isinstance(value["sizes"], list) else [value["sizes"]]
        if len(sizes) not in (1, 2):
            raise CalibrationError(path, f"{key}.sizes", f"expected 1 or 2 dimensions, got "
                                   f"{len(sizes)}")
        dims = [_dimension(path, f"{key}.sizes", size) for size in sizes]
        rows, cols = (1, dims[0]) if len(dims) == 1 else dims
    elif "rows" in value and "cols" in value:
        rows = _dimension(path, f"{key}.rows", value["rows"])
        cols = _dimension(path, f"{key}.cols", value["cols"])
    else:
        raise CalibrationError(path, key, "expected an opencv-matrix with rows and cols")
    data = value["data"] if isinstance(value["data"], list) else [value["data"]]
    _check_shape(path, key, rows, cols, shape, len(data))
    matrix = np.array([_number(path, f"{key}.data", item) for item in data], dtype=np.float64)
    kind = np.dtype(_ELEMENT_TYPES[element_type.removeprefix("1")])
    if kind.kind in "iu":
        limits = np.iinfo(kind)
        wrong = ~((matrix == np.round(matrix)) & (matrix >= limits.min) & (matrix <= limits.max))
        if wrong.any():
            raise CalibrationError(
                path, f"{key}.data", f"holds {matrix[wrong][0]:g}, not a value of its dt "
                f"{token(element_type)} ({kind.name})"
            )
    return matrix.reshape(rows, cols) if shape is not None else matrix


def _dimension(path: str | Path, key: str, value: object) -> int:
    """A matrix's ``rows``, ``cols`` or one of its ``sizes``: a whole number, 0 to
    :data:`MAX_DIMENSION`."""
    if (isinstance(value, bool) or not isinstance(value, numbers.Real)
            or not 0 <= value <= MAX_DIMENSION or value != int(value)):
        raise CalibrationError(
            path, key, f"expected a whole number from 0 to {MAX_DIMENSION}, got {_kind(value)}"
        )
    return int(value)


def _check_shape(path: str | Path, key: str, rows: int, cols: int,
                 shape: tuple[int, int] | None, count: int) -> None:
    """A matrix's declared ``rows x cols`` (whole numbers from 0, as :func:`_dimension` gives
    them): ``shape`` if given, else one row or column of at most 14 numbers (a distortion
    vector), holding ``count`` values."""
    if shape is not None and (rows, cols) != shape:
        raise CalibrationError(
            path, key, f"expected {shape[0]}x{shape[1]} numbers, got {rows}x{cols}"
        )
    if shape is None and not (min(rows, cols) <= 1 and max(rows, cols) <= 14):
        raise CalibrationError(
            path, key, f"expected one row or column of at most 14 numbers, got {rows}x{cols}"
        )
    if count != rows * cols:
        raise CalibrationError(
            path, key, f"its data holds {count} values, not rows x cols = {rows * cols}"
        )


def _number(path: str | Path, key: str, value: object) -> float:
    """A number of the file as a float (perhaps not finite: the caller checks)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise CalibrationError(path, key, f"expected a number, got {_kind(value)}")
    try:
        return float(value)
    except OverflowError:
        raise CalibrationError(path, key, f"expected a finite number, got {_kind(value)}") from None


def _opencv_size(path: str | Path, key: str, value: object) -> tuple[float, float]:
    """``cameraResolution``: a cv::Size, written as the sequence ``[width, height]``."""
    if not isinstance(value, list) or len(value) != 2:
        raise CalibrationError(path, key, "expected [width, height]")
    return _number(path, key, value[0]), _number(path, key, value[1])


def _read_ros(path: str | Path, text: str) -> dict[str, Any]:
    """The raw fields of a ROS ``camera_info`` YAML file."""
    from ..io.safe_yaml import YamlInputError, load_yaml

    try:
        document = load_yaml(text)
    except YamlInputError as error:
        problem = _QUOTED.sub(lambda match: token(match.group(0)[1:-1]), str(error))
        raise CalibrationError(path, error.key, f"not valid YAML ({problem})") from None
    if not isinstance(document, dict):
        got = (f"a string of {len(document)} characters" if isinstance(document, str)
               else _kind(document))  # a whole file's text is never quoted
        raise CalibrationError(
            path, None, f"expected a mapping (OpenCV FileStorage or ROS camera_info YAML), got "
            f"{got}"
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
        raise CalibrationError(path, _MODEL_KEY, f"expected a string, got {_kind(model)}")
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
    """What a value of the file is, for a message: its kind, or a short token of it."""
    if value is None:
        return "nothing"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return token(value)


def _ros_number(path: str | Path, key: str, value: object) -> float | None:
    return None if value is None else _number(path, key, value)


def _ros_matrix(
    path: str | Path, key: str, value: object, shape: tuple[int, int] | None
) -> np.ndarray:
    """``{rows, cols, data}`` as float64; ``shape`` None: a vector of at most 14 values."""
    if not isinstance(value, dict) or not {"rows", "cols", "data"} <= set(value):
        raise CalibrationError(path, key, f"expected a mapping with rows, cols and data, got "
                               f"{_kind(value)}")
    if value["rows"] is None or value["cols"] is None:
        raise CalibrationError(path, key, "expected numbers for rows and cols")
    rows = _dimension(path, f"{key}.rows", value["rows"])
    cols = _dimension(path, f"{key}.cols", value["cols"])
    data = value["data"]
    if not isinstance(data, list):
        raise CalibrationError(path, f"{key}.data", f"expected a list of numbers, got "
                               f"{_kind(data)}")
    _check_shape(path, key, rows, cols, shape, len(data))
    numbers_ = [_number(path, f"{key}.data", item) for item in data]
    matrix = np.array(numbers_, dtype=np.float64)
    return matrix.reshape(shape) if shape is not None else matrix


def intrinsics_from_camera_info(
    source: str, matrix: object, distortion: object, model: str | None,
    width: float | None, height: float | None,
) -> Intrinsics:
    """The :class:`Intrinsics` of a ``sensor_msgs/CameraInfo`` message's fields, checked as a
    ROS ``camera_info`` file's are (the same lens models and coefficient counts).

    ``source`` names the message in errors (``walk.bag /camera/camera_info``); ``matrix``:
    its ``K`` (9 numbers, row major), ``distortion``: its ``D``, ``model``: its
    ``distortion_model`` (empty: none), ``width``/``height``: its size (0: unknown). Raises
    :class:`CalibrationError` naming the field (``K``, ``D``, ``distortion_model``).
    """
    values = np.asarray(matrix, dtype=np.float64).ravel()
    if values.size != 9:
        raise CalibrationError(source, "K", f"expected 9 numbers, got {values.size}")
    coefficients = np.asarray(distortion, dtype=np.float64).ravel()
    if coefficients.size > 14:
        raise CalibrationError(
            source, "D", f"expected at most 14 numbers, got {coefficients.size}"
        )
    if not values.any():
        raise CalibrationError(source, "K", "all zeros: an uncalibrated camera")
    return _intrinsics(
        source, matrix=values.reshape(3, 3), matrix_key="K", distortion=coefficients,
        distortion_key="D", model=model or None, width=width or None, height=height or None,
        size_keys=("width", "height"),
    )


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
        model = LENS_ALIASES.get(model, model)
        if model not in LENS_MODELS:
            raise CalibrationError(path, _MODEL_KEY, f"unknown lens model {token(model)}; use "
                                   f"one of {', '.join(LENS_MODELS)}")
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
    import cv2  # OpenCV only to write its format

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
    import yaml

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
