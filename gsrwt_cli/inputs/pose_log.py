"""Timestamped pose files (``gsrwt rectify VIDEO --poses FILE``): a pose per moment, read
into a :class:`~gsrwt_cli.geometry.timeline.Timeline`.

Formats (angles in degrees, lengths in pixels, ``time`` in seconds):

- CSV (``.csv``, ``.txt``; ``.tsv`` tab-separated) with a header row: ``time`` and the pose as
  a sidecar gives it, ``pan,tilt`` (``roll`` optional) or a quaternion ``qw,qx,qy,qz``
  (``camera_from_wall`` in OpenCV's frames, scalar first: docs/POSES.md); optionally
  ``focal``, ``fx``, ``fy``, ``cx``, ``cy``, ``distance``, interpolated linearly like the
  pose. Empty cells count as absent; other columns are ignored.
- YAML (``.yaml``, ``.yml``): a list of records with the same keys; an item
  ``{defaults: {...}}`` gives values every moment takes (``focal: 800``, say).

Read with the sidecars' readers (UTF-8 text, :mod:`~gsrwt_cli.io.safe_yaml`'s bounded YAML).
Problems raise :class:`PoseLogError` naming the file, the line (CSV) or record (YAML), the
field and why; two samples at the same time name both lines.
"""

from __future__ import annotations

import csv
import hashlib
import io
import numbers as number_types
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..base.messages import one_line, quote
from ..base.numerals import parse_decimal
from ..geometry.checks import ViewError
from ..geometry.rotations import (
    Pose,
    PoseError,
    rotation_from_pose,
    rotation_from_quaternion,
    world_from_camera_from_opencv,
)
from ..geometry.timeline import DuplicateTimeError, PoseSample, Timeline
from .sidecar import SidecarError, display_path, fields_of, parse_yaml, read_sidecar_text

#: The numbers of a sample interpolated linearly between samples (the pose is slerped).
INTERPOLATED_FIELDS = ("focal", "fx", "fy", "cx", "cy", "distance")
ANGLE_FIELDS = ("pan", "tilt", "roll")
QUATERNION_FIELDS = ("qw", "qx", "qy", "qz")
#: Every field a pose file's record may give (others are ignored).
POSE_LOG_FIELDS = ("time", *ANGLE_FIELDS, *QUATERNION_FIELDS, *INTERPOLATED_FIELDS)


class PoseLogError(SidecarError):
    """The pose file cannot be used; the message names the file, where, and why."""


@dataclass(frozen=True)
class PoseLog:
    """A pose file read: its samples in the file's order, where each came from
    (``poses.csv line 4``), the values every moment takes (YAML ``defaults``), and a
    digest of the file's bytes (what made an output: :func:`~gsrwt_cli.batch.reruns.made_with`)."""

    path: Path
    samples: list[PoseSample]
    wheres: list[str]
    defaults: dict[str, float] = field(default_factory=dict)
    digest: str = ""

    def timeline(self, max_gap: float) -> Timeline:
        """The samples sorted by time, as a :class:`Timeline`; two at the same time are a
        :class:`PoseLogError` naming both."""
        try:
            return Timeline(self.samples, max_gap)
        except DuplicateTimeError as error:
            first = self.wheres[error.first].removeprefix(display_path(self.path) + " ")
            raise PoseLogError(f"{self.wheres[error.second]}: time {error.time:g} is already "
                               f"given in {first}") from None


def _number(where: str, name: str, raw: Any) -> float:
    """A cell or YAML value as a finite float (ASCII decimals, YAML numbers)."""
    if isinstance(raw, str):
        try:
            return parse_decimal(raw.strip())
        except ValueError as error:
            raise PoseLogError(f"{where}, field {quote(name)}: {error}, got {quote(raw)}"
                               ) from None
    if isinstance(raw, bool) or not isinstance(raw, number_types.Real):
        raise PoseLogError(f"{where}, field {quote(name)}: not a number: {quote(raw)}")
    try:
        value = float(raw)
    except OverflowError:
        value = float("nan")
    if value != value or value in (float("inf"), float("-inf")):
        raise PoseLogError(f"{where}, field {quote(name)}: must be finite, got {quote(raw)}")
    return value


def sample_from_values(values: Mapping[str, Any], where: str) -> PoseSample:
    """One sample from a record's raw values: ``time``, the pose (pan/tilt/roll or a
    quaternion) and the numbers of :data:`INTERPOLATED_FIELDS`."""
    given = {name: value for name, value in values.items()
             if name in POSE_LOG_FIELDS and value is not None and value != ""}
    if "time" not in given:
        raise PoseLogError(f"{where}: missing field 'time'")
    numbers = {name: _number(where, name, value) for name, value in given.items()}
    angles = [name for name in ANGLE_FIELDS if name in numbers]
    quaternion = [name for name in QUATERNION_FIELDS if name in numbers]
    if angles and quaternion:
        raise PoseLogError(f"{where}: give one pose, not pan/tilt and a quaternion")
    try:
        if quaternion:
            missing = [name for name in QUATERNION_FIELDS if name not in numbers]
            if missing:
                raise PoseLogError(f"{where}: missing field {quote(missing[0])} (needed with "
                                   "qw, qx, qy, qz)")
            rotation = world_from_camera_from_opencv(
                rotation_from_quaternion(*(numbers[name] for name in QUATERNION_FIELDS)))
        else:
            missing = [name for name in ("pan", "tilt") if name not in numbers]
            if missing:
                raise PoseLogError(f"{where}: missing field {quote(missing[0])} (a pose is "
                                   "pan and tilt, or qw, qx, qy, qz)")
            pose = Pose(numbers["pan"], numbers["tilt"], numbers.get("roll", 0.0))
            rotation = rotation_from_pose(pose.pan, pose.tilt, pose.roll)
    except ViewError as error:
        raise PoseLogError(f"{where}, field {quote(error.field)}: {error}") from None
    except PoseError as error:
        raise PoseLogError(f"{where}, field 'qw': {one_line(str(error), 300)}") from None
    others = {name: numbers[name] for name in INTERPOLATED_FIELDS if name in numbers}
    return PoseSample(numbers["time"], rotation, others)


def load_pose_log(path: str | Path) -> PoseLog:
    """Read a CSV, TSV or YAML pose file; raises :class:`PoseLogError` (a
    :class:`~gsrwt_cli.inputs.sidecar.SidecarError`) naming the file."""
    path = Path(path)
    suffix = path.suffix.lower()
    name = display_path(path)
    if suffix not in (".csv", ".tsv", ".txt", ".yaml", ".yml"):
        if not path.exists():
            raise PoseLogError(f"{name}: no such file")
        if path.is_dir():
            raise PoseLogError(f"{name}: is a directory, not a pose file")
        raise PoseLogError(f"{name}: unknown pose file type {quote(suffix)} (use .csv, .tsv "
                           "or .yaml)")
    text = read_sidecar_text(path)
    digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:16]
    if suffix in (".yaml", ".yml"):
        samples, wheres, defaults = _yaml_samples(path, parse_yaml(path, text))
    else:
        samples, wheres = _csv_samples(path, text, "\t" if suffix == ".tsv" else ",")
        defaults = {}
    if not samples:
        raise PoseLogError(f"{name}: no poses (expected rows of time and a pose)")
    return PoseLog(path, samples, wheres, defaults, digest)


def _csv_samples(path: Path, text: str, delimiter: str) -> tuple[list[PoseSample], list[str]]:
    name = display_path(path)
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    samples: list[PoseSample] = []
    wheres: list[str] = []
    try:
        header = next(reader, None)
        if header is None or not any(cell.strip() for cell in header):
            raise PoseLogError(f"{name}: empty file, expected a header row with 'time'")
        columns = [cell.strip().lower() for cell in header]
        if "time" not in columns:
            raise PoseLogError(f"{name} line 1: missing column 'time' (header is "
                               f"{quote(','.join(columns))})")
        for column in set(columns):
            if column and columns.count(column) > 1:
                raise PoseLogError(f"{name} line 1: column {quote(column)} given twice")
        start = reader.line_num + 1
        for cells in reader:
            where = f"{name} line {start}"
            start = reader.line_num + 1
            if not any(cell.strip() for cell in cells):
                continue
            if len(cells) > len(columns):
                raise PoseLogError(f"{where}: {len(cells)} cells but the header has "
                                   f"{len(columns)}")
            values = {column: cell.strip() for column, cell in zip(columns, cells)}
            samples.append(sample_from_values(values, where))
            wheres.append(where)
    except csv.Error as error:
        raise PoseLogError(f"{name} line {reader.line_num}: {one_line(str(error), 200)}"
                           ) from None
    return samples, wheres


def _yaml_samples(path: Path, data: Any) -> tuple[list[PoseSample], list[str], dict[str, float]]:
    name = display_path(path)
    if not isinstance(data, list):
        raise PoseLogError(f"{name}: expected a list of records (time and a pose)")
    defaults: dict[str, float] = {}
    samples: list[PoseSample] = []
    wheres: list[str] = []
    for index, item in enumerate(data, start=1):
        where = f"{name} record {index}"
        if isinstance(item, dict) and set(item) == {"defaults"}:
            given = fields_of(f"{where} (defaults)", item["defaults"])
            for key, value in given.items():
                if key not in INTERPOLATED_FIELDS:
                    raise PoseLogError(f"{where} (defaults): unknown field {quote(key)} (use "
                                       f"{', '.join(INTERPOLATED_FIELDS)})")
                defaults[key] = _number(f"{where} (defaults)", key, value)
            continue
        samples.append(sample_from_values(fields_of(where, item), where))
        wheres.append(where)
    return samples, wheres, defaults
