"""Reruns: what made each output, and whether the last table's row of an output still holds.

A ``gsrwt rectify`` row records in ``made_with`` everything that shapes its output file
beyond the image itself: the values the image was given (pose, focal length, principal
point, lens, a calibration file's content) and the run's frame, scale, sampling and encoding
options, as ``name=value`` words (:func:`made_with`). Values are compared as the words the
user's own values print as (parsed, never computed), so the same request is the same words
on every machine.

A rerun keeps an existing output only when the previous table's row of it is a record
(:func:`valid_record`: every cell as the table writer writes it, and the file it names a
regular file of its size) made with what this run asks for (:func:`differences`).
"""

from __future__ import annotations

import math
import numbers
import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote as percent_encoded

from ..base.messages import shorten
from ..imaging.images import image_file_size
from ..inputs.records import SIDECAR_FIELDS, load_camera_file
from ..tables.columns import PARAMS_COLUMNS
from ..tables.shards import RECTIFY_TABLE

if TYPE_CHECKING:
    from ..geometry.lens import Lens
    from ..io.storage import Location
    from .settings import Settings

#: Formats whose ``--quality`` changes the file.
LOSSY = (".jpg", ".webp")
#: Longest ``made_with`` and ``error`` cells a table writer writes (the error is bounded by
#: the batch's one-line wording, 500 characters, and a few more for an ellipsis).
MADE_WITH_LIMIT = 4000
ERROR_LIMIT = 540
#: Longest numeric and text cells of a record (a float printed to 6 decimals has at most
#: 316 characters; image and output names are paths).
NUMBER_LIMIT = 400
NAME_LIMIT = 8192
#: Largest output side gsrwt writes (``--max-size`` is bounded so).
SIDE_LIMIT = 1 << 30

_NUMBER_TEXT = re.compile(r"-?[0-9]+(?:\.[0-9]+)?")
_INTEGER_TEXT = re.compile(r"[1-9][0-9]{0,9}")
_GENERAL_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_WORD = re.compile(r"[a-z0-9_.]+=[^\s=]*")
_NUMBER_COLUMNS = tuple(c for c in PARAMS_COLUMNS if c not in ("image", "horizon_in_image"))
#: Statuses of a row that records its output (an error row may keep the record of an output
#: it did not redo); ``interrupted`` rows never do.
_RECORD_STATUSES = ("ok", "skipped", "error")


# --------------------------------------------------------------------------------------------
# What made an output
# --------------------------------------------------------------------------------------------


def _number(value: float) -> str:
    return format(value, ".15g")


def _given(value: Any) -> str:
    """A value as the user gave it, as one word: numbers (and decimal strings) printed the
    same way whatever their type, text percent-encoded and bounded."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        try:
            number = float(value)
        except OverflowError:
            number = math.nan
        if math.isfinite(number):
            return _number(number)
    text = str(value).strip()
    if _GENERAL_NUMBER.fullmatch(text) and math.isfinite(float(text)):
        return _number(float(text))
    return shorten(percent_encoded(text, safe=""), 200)


def lens_word(lens: Lens | None) -> str:
    """A lens as one word: ``none``, or its model and non-zero coefficients
    (``plumb_bob(k1:-0.2,p1:0.001)``)."""
    if lens is None or lens.is_identity:
        return "none"
    terms = ",".join(f"{name}:{_number(value)}" for name, value in lens.coefficients if value)
    return f"{lens.model}({terms})"


def _camera_words(path: str) -> list[tuple[str, str]]:
    """A calibration file by its content (two files alike make the same outputs)."""
    from ..inputs.calibration import CalibrationError

    try:
        camera = load_camera_file(path)
    except (CalibrationError, OSError, ValueError):
        return [("camera", "unreadable")]
    words = [(f"camera.{name}", "none" if value is None else _number(value)) for name, value in
             (("fx", camera.fx), ("fy", camera.fy), ("cx", camera.cx), ("cy", camera.cy),
              ("skew", camera.skew), ("width", camera.width), ("height", camera.height))]
    return [*words, ("camera.lens", lens_word(camera.lens))]


def made_with(values: Mapping[str, Any] | None, wall: str | None, settings: Settings,
              suffix: str, auto: str | None = None) -> str | None:
    """The ``made_with`` cell of an output: ``name=value`` words of the image's given
    ``values`` (None: the image has none, no cell), the ``wall`` of an estimated pose or the
    ``auto`` mode of a pose found otherwise (``document``), and the ``settings`` that change
    an output of this ``suffix``.

    Options that cannot change a written file (``--max-pixels``, ``--max-input-pixels``,
    ``--quality`` of a PNG) are left out, so that changing them never refuses a rerun.
    """
    if values is None:
        return None
    words = [(name, _given(values[name])) for name in SIDECAR_FIELDS
             if name != "camera" and values.get(name) is not None and values.get(name) != ""]
    if values.get("camera"):
        words += _camera_words(str(values["camera"]))
    if wall is not None:
        words.append(("wall", wall))
    if auto is not None:
        words.append(("auto", auto))
    framing = settings.framing
    box = framing.bbox
    words.append(("bbox", box if isinstance(box, str) else ",".join(map(_number, box))))
    if box in ("full", "crop"):
        words.append(("max_stretch", _number(framing.max_stretch)))
    if box == "crop" and framing.crop_aspect is not None:
        aspect = framing.crop_aspect
        words.append(("crop_aspect", aspect if isinstance(aspect, str) else _number(aspect)))
    if box == "corners":
        words.append(("margin", _number(framing.margin)))
    words.append(("scale", _number(framing.scale) if framing.px_per_unit is None
                  else f"{_number(framing.px_per_unit)}px/unit"))
    if framing.max_size is not None:
        words.append(("max_size", "x".join(map(str, framing.max_size))))
    if framing.max_area is not None and box != "frontal":  # the input's size: never lowered
        words.append(("max_area", _number(framing.max_area)))
    words += [("interpolation", settings.interpolation),
              ("antialias", "on" if settings.antialias else "off"),
              ("fill", _number(settings.fill)), ("alpha", "on" if settings.alpha else "off")]
    if settings.orientation != "exif":  # the default left out: tables made before it hold
        words.append(("orientation", settings.orientation))
    if not settings.metadata:  # likewise
        words.append(("metadata", "strip"))
    if settings.lens_profile == "off":  # auto and lensfun make the same files
        words.append(("lens_profile", "off"))
    if settings.lens_from_lines:  # the default left out, likewise
        words.append(("lens_from_lines", "on"))
    if suffix.lower() in LOSSY:
        words.append(("quality", str(settings.quality)))
    return " ".join(f"{name}={value}" for name, value in words)


def _words(cell: str) -> dict[str, str]:
    return dict(word.split("=", 1) for word in cell.split())


def differences(recorded: str, wanted: str, limit: int = 6) -> str | None:
    """What differs between two ``made_with`` cells (``pan 20 -> 10, focal 500 -> 700``), or
    None if nothing does; values shortened, at most ``limit`` differences named."""
    before, after = _words(recorded), _words(wanted)
    names = [*after, *(name for name in before if name not in after)]
    changed = [f"{name} {shorten(before.get(name, 'none'), 24)} -> "
               f"{shorten(after.get(name, 'none'), 24)}"
               for name in names if before.get(name) != after.get(name)]
    if not changed:
        return None
    more = f", and {len(changed) - limit} more" if len(changed) > limit else ""
    return ", ".join(changed[:limit]) + more


# --------------------------------------------------------------------------------------------
# The previous table's rows: input, checked as such
# --------------------------------------------------------------------------------------------


class InvalidRecordError(ValueError):
    """A previous row that cannot vouch for its output (the message names the column)."""


def _text(row: Mapping[str, Any], column: str) -> str | None:
    """A cell that a text table gives as a string and JSON as a value, as the text table
    would: None for an empty cell; JSON's numbers and booleans as they would print."""
    value = row.get(column)
    if value is None or value == "":
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise InvalidRecordError(f"{column} is not finite")
        return format(value, ".6f").rstrip("0").rstrip(".")
    if not isinstance(value, str):
        raise InvalidRecordError(f"{column} is a {type(value).__name__}")
    return value


def _check_number(row: Mapping[str, Any], column: str, required: bool = False) -> None:
    value = row.get(column)
    if isinstance(value, bool) or (value is not None and not isinstance(value, (str, int,
                                                                                float))):
        raise InvalidRecordError(f"{column} is not a number")
    text = _text(row, column)
    if text is None:
        if required:
            raise InvalidRecordError(f"{column} is empty")
        return
    if len(text) > NUMBER_LIMIT or not _NUMBER_TEXT.fullmatch(text):
        raise InvalidRecordError(f"{column} is not a number as the table writes one")


def _check_choice(row: Mapping[str, Any], column: str, choices: tuple[str, ...],
                  required: bool = False) -> str | None:
    value = row.get(column)
    if value is not None and not isinstance(value, str):
        raise InvalidRecordError(f"{column} is not text")
    text = _text(row, column)
    if text is None and not required:
        return None
    if text not in choices:
        raise InvalidRecordError(f"{column} is not one of {', '.join(choices)}")
    return text


def _size(row: Mapping[str, Any]) -> tuple[int, int]:
    sides = []
    for column in ("out_width", "out_height"):
        value = row.get(column)
        if isinstance(value, int) and not isinstance(value, bool):
            value = str(value)
        if not isinstance(value, str) or not _INTEGER_TEXT.fullmatch(value) or int(
                value) > SIDE_LIMIT:
            raise InvalidRecordError(f"{column} is not a positive whole number of pixels")
        sides.append(int(value))
    return sides[0], sides[1]


def check_record(row: Mapping[str, Any], columns: tuple[str, ...]) -> dict[str, Any]:
    """``row`` of a previous table as a record of its output: every cell of ``columns`` as
    :class:`~gsrwt_cli.tables.writer.TableWriter` writes it (types, choices, lengths), the output's
    size, scale, homography and ``made_with`` given. Returns the row restricted to
    ``columns``; raises :class:`InvalidRecordError` naming the first bad column."""
    text = all(value is None or isinstance(value, str) for value in row.values())
    problem = RECTIFY_TABLE.cell_problem(row, text)
    if problem is not None:  # the kinds every reader of the table checks
        column, kind = problem
        raise InvalidRecordError(f"{column} is not {kind.expected}")
    # A record is also as the writer writes it: bounded, numbers to fixed decimals, and
    # says where its focal length came from.
    if row.get("focal_source") in (None, ""):
        raise InvalidRecordError("focal_source is empty")
    for column in ("image", "output"):
        value = row.get(column)
        if not isinstance(value, str) or not value or len(value) > NAME_LIMIT:
            raise InvalidRecordError(f"{column} is not a file name")
    for column in _NUMBER_COLUMNS:
        _check_number(row, column, required=column in ("pan_deg", "tilt_deg", "fx_px",
                                                       "fy_px"))
    _check_number(row, "confidence")
    confidence = _text(row, "confidence")
    if confidence is not None and not 0 <= float(confidence) <= 1:
        raise InvalidRecordError("confidence is not within 0-1")
    _size(row)
    _check_number(row, "scale", required=True)
    scale = _text(row, "scale")
    if scale is None or not float(scale) > 0:
        raise InvalidRecordError("scale is not positive")
    homography = row.get("homography")
    if not isinstance(homography, str) or len(homography) > 9 * 32:
        raise InvalidRecordError("homography is not 9 numbers")
    entries = homography.split(" ")
    if len(entries) != 9 or not all(_GENERAL_NUMBER.fullmatch(entry) for entry in entries):
        raise InvalidRecordError("homography is not 9 numbers")
    cell = row.get("made_with")
    if not isinstance(cell, str) or len(cell) > MADE_WITH_LIMIT or not all(
            _WORD.fullmatch(word) for word in cell.split(" ")):
        raise InvalidRecordError("made_with is not name=value words")
    status = _check_choice(row, "status", _RECORD_STATUSES, required=True)
    error = row.get("error")
    if status == "error":
        if not isinstance(error, str) or not error or len(error) > ERROR_LIMIT or any(
                char in error for char in "\r\n\x00"):
            raise InvalidRecordError("error is not one line of an error")
    elif error not in (None, ""):
        raise InvalidRecordError(f"a row with status {status} has an error")
    return {column: row.get(column) for column in columns}


def file_fits(output: Path | Location, size: tuple[int, int]) -> str | None:
    """Why the existing ``output`` is not the file a record of this ``size`` describes (not a
    regular file, another size), or None if it is."""
    if not is_regular_file(output):
        return "is not a regular file"
    found = image_file_size(output)
    if found != size:
        return "is not of the recorded size"
    return None


def is_regular_file(output: Path | Location) -> bool:
    """Whether ``output`` is a regular file itself (not a link, a directory or a FIFO)."""
    if not isinstance(output, Path):
        return output.is_file()
    try:
        return stat.S_ISREG(os.lstat(output).st_mode)
    except OSError:
        return False


def record_of(row: Mapping[str, Any] | None, output: Path | Location,
              columns: tuple[str, ...]) -> dict[str, Any] | None:
    """The previous ``row`` of ``output`` as its record, or None if it is none (invalid,
    or not describing the file that is there now)."""
    if row is None:
        return None
    try:
        record = check_record(row, columns)
    except InvalidRecordError:
        return None
    if file_fits(output, _size(record)) is not None:
        return None
    return record
