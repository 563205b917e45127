"""The values of one view, checked into a :class:`~gsrwt_cli.geometry.camera.View`, naming what is
wrong.

Values come from a sidecar row, a YAML record or the command line, as numbers or numeric
strings. Besides pan, tilt and the intrinsics they may give the pose as the GS-RWT's own
``delta, a, gamma``, as ``solvePnP``'s ``rvec``/``tvec`` or as a quaternion; the focal length
in millimetres with the sensor's size; a lens; and a calibration file (``camera``) whose
intrinsics the other fields override. A bad value raises :class:`RecordError` naming where
it came from, the field and why, its value quoted by :func:`~gsrwt_cli.base.messages.quote`.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

from ..base.messages import quote
from ..geometry.camera import (
    LENS_FIELDS,
    LENS_MODELS,
    VIEW_FIELDS,
    Intrinsics,
    Lens,
    Pose,
    View,
    ViewError,
)
from ..geometry.gsrwt import pan_tilt_from_gsrwt
from ..geometry.guides import GuideError
from ..geometry.orientation import displayed_intrinsics
from ..geometry.pinhole import SIMPLE_PINHOLE_FIELDS, pinhole_numbers  # noqa: F401  (named here too)
from ..geometry.rotations import PoseError, distance_from_tvec, pose_from_quaternion, pose_from_rvec
from .guides import GUIDE_FIELDS, guided_values, has_guides

GSRWT_FIELDS = ("delta", "a", "gamma")
#: A pose as OpenCV's solvePnP gives it (camera_from_wall, OpenCV frames), or a quaternion of
#: the same rotation (scalar first): instead of pan, tilt and roll (docs/POSES.md).
RVEC_FIELDS = ("rvec_x", "rvec_y", "rvec_z")
TVEC_FIELDS = ("tvec_x", "tvec_y", "tvec_z")
QUATERNION_FIELDS = ("qw", "qx", "qy", "qz")
POSE_FIELDS = RVEC_FIELDS + TVEC_FIELDS + QUATERNION_FIELDS
#: A focal length in millimetres, with the sensor's size: ``fx = focal_mm * width /
#: sensor_width_mm`` (and ``fy`` from ``sensor_height_mm``, else square pixels).
SENSOR_FIELDS = ("focal_mm", "sensor_width_mm", "sensor_height_mm")
NUMERIC_FIELDS = VIEW_FIELDS + LENS_FIELDS + POSE_FIELDS + SENSOR_FIELDS + GSRWT_FIELDS
#: Fields whose values are words, not numbers: ``camera`` names a calibration file (OpenCV
#: or ROS, relative to the sidecar) whose intrinsics the record's own fields override.
#: The guides of guided correction (``corners``, ``verticals``, ``horizontals``, ``aspect``,
#: ``fit``: :mod:`~gsrwt_cli.inputs.guides`) are texts too.
TEXT_FIELDS = ("distortion_model", "camera", *GUIDE_FIELDS)
#: Every field a sidecar record may give.
SIDECAR_FIELDS = NUMERIC_FIELDS + TEXT_FIELDS
#: How far a given gamma may stray from the one that delta and a imply (the thesis rounds to 1°).
GAMMA_TOLERANCE_DEG = 1.0


class RecordError(ValueError):
    """One record of parameters is invalid: ``where`` it came from, which ``field``, ``reason``."""

    def __init__(self, where: str, field_name: str | None, reason: str) -> None:
        self.where, self.field, self.reason = where, field_name, reason
        at = f"{where}, field '{field_name}'" if field_name else where
        super().__init__(f"{at}: {reason}")


def merge_values(own: Mapping[str, Any], *fallbacks: Mapping[str, Any]) -> dict[str, Any]:
    """``own`` values over the ``fallbacks`` (earlier ones win over later ones).

    A record that gives the pose as the GS-RWT's ``delta``/``a`` takes no pan or tilt from
    the fallbacks, and one that gives pan/tilt takes no ``delta``, ``a`` or ``gamma``; one
    that gives a pose takes no guides (``corners``, ``verticals``, ``horizontals``,
    ``aspect``), and one that gives guides takes no pan, tilt, roll, delta, a or gamma.
    """
    if not any(fallbacks):  # nothing to fall back on (a sidecar's row alone, most often)
        return dict(own)
    merged: dict[str, Any] = {}
    for fallback in reversed(fallbacks):
        merged.update(fallback)
    own_keys = {k for k, v in own.items() if v is not None and v != ""}
    if own_keys & {"delta", "a"} and not own_keys & {"pan", "tilt"}:
        merged.pop("pan", None)
        merged.pop("tilt", None)
    elif own_keys & {"pan", "tilt"}:
        for name in GSRWT_FIELDS:
            merged.pop(name, None)
    if own_keys & {"pan", "tilt", "delta", "a", *RVEC_FIELDS, *QUATERNION_FIELDS}:
        for name in GUIDE_FIELDS[:-1]:  # a pose of its own: the options' guides are not its
            merged.pop(name, None)
    elif own_keys & set(GUIDE_FIELDS):
        for name in ("pan", "tilt", "roll", *GSRWT_FIELDS):  # guides of its own: their pose
            merged.pop(name, None)
    merged.update(own)
    return merged


_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NOT_FINITE = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)


def _number(where: str, name: str, raw: Any) -> float:
    """A raw value as a finite float: a real number (numpy's too) or a decimal string.

    Strings must be plain ASCII decimals (``-12``, ``3.5``, ``1e-3``); ``nan``, ``inf`` and
    values beyond floating point (``1e400``, an integer of 400 digits) are errors.
    """
    if isinstance(raw, str):
        text = raw.strip()
        if _NOT_FINITE.fullmatch(text):
            raise RecordError(where, name, f"must be finite, got {quote(raw)}")
        if not _DECIMAL.fullmatch(text):
            raise RecordError(where, name, f"not a number: {quote(raw)}")
        value = float(text)
    elif isinstance(raw, bool) or not isinstance(raw, numbers.Real):
        raise RecordError(where, name, f"not a number: {quote(raw)}")
    else:
        try:
            value = float(raw)
        except OverflowError:  # an integer or a fraction beyond floating point
            raise RecordError(where, name, f"out of range, got {quote(raw)}") from None
        if not math.isfinite(value):
            raise RecordError(where, name, f"must be finite, got {quote(raw)}")
    if not math.isfinite(value):  # a decimal string beyond floating point
        raise RecordError(where, name, f"out of range, got {quote(raw)}")
    return value


def simple_pinhole_numbers(values: Mapping[str, Any], where: str) -> tuple[float, ...] | None:
    """:func:`~gsrwt_cli.geometry.pinhole.pinhole_numbers` of a record, any value that is a number
    read as :func:`view_from_values` reads it (numpy's scalars too)."""
    return pinhole_numbers(values, where, _number)


def view_from_values(values: Mapping[str, Any], where: str, orientation: int = 1) -> View:
    """Build a :class:`View` from raw values (numbers or numeric strings), naming what is wrong.

    ``orientation``: the photo's EXIF orientation when it is applied (1: as stored). The
    values describe the photo as displayed; a calibration file (``camera``) describes the
    sensor, so its intrinsics are turned to the displayed photo
    (:func:`~gsrwt_cli.geometry.orientation.displayed_intrinsics`) before the values' own
    fields go over them.

    When ``delta`` and ``a`` are given instead of pan and tilt, the pose comes from the GS-RWT
    parameters (:func:`~gsrwt_cli.geometry.gsrwt.pan_tilt_from_gsrwt`); a given ``gamma`` must
    agree with them within :data:`GAMMA_TOLERANCE_DEG`. Values with guides (``corners``,
    ``verticals``, ``horizontals``) get the pose they show (:func:`guided_view_values`).
    Raises only :class:`RecordError`.
    """
    if guides_give_pose(values):
        values = guided_view_values(values, where, orientation)[0]
    numbers_given = {
        name: _number(where, name, values[name])
        for name in NUMERIC_FIELDS
        if values.get(name) is not None and values.get(name) != ""
    }
    given = set(numbers_given)
    if given & {"pan", "tilt"} and given & {"delta", "a"}:
        raise RecordError(where, None, "give pan and tilt, or delta and a, not both")
    if given & {"delta", "a"}:
        for name in ("delta", "a", "focal"):
            if name not in numbers_given:
                reason = f"missing field '{name}' (needed with delta, a, gamma)"
                raise RecordError(where, None, reason)
        try:
            pan, tilt = pan_tilt_from_gsrwt(
                numbers_given["delta"], numbers_given["a"], numbers_given["focal"]
            )
        except ValueError as error:
            raise RecordError(where, str(error).split(" ", 1)[0], str(error)) from None
        numbers_given["pan"], numbers_given["tilt"] = pan, tilt
    _pose_from_rotation_fields(where, numbers_given)
    for name in ("pan", "tilt"):
        if name not in numbers_given:
            raise RecordError(where, None, f"missing field '{name}'")
    _focal_from_millimetres(where, numbers_given)
    given = set(numbers_given)
    camera = values.get("camera")
    if "focal" not in numbers_given and not {"fx", "fy"} <= given and not camera:
        raise RecordError(where, None, "missing field 'focal'")
    try:
        lens = _lens_from_values(values, numbers_given)
        if camera:
            from .calibration import CalibrationError  # OpenCV's FileStorage: when needed

            try:
                base = load_camera_file(str(camera))
            except CalibrationError as error:
                raise RecordError(where, "camera", str(error)) from None
            base = displayed_intrinsics(base, orientation)
            view = _view_with_camera(base, numbers_given, lens, values)
        else:
            view = View(**{name: numbers_given[name] for name in VIEW_FIELDS
                           if name in numbers_given}, lens=lens)
    except ViewError as error:
        raise RecordError(where, error.field, str(error)) from None
    if "gamma" in numbers_given:
        implied = view.parameters.gamma_deg
        if abs(numbers_given["gamma"] - implied) > GAMMA_TOLERANCE_DEG:
            raise RecordError(
                where,
                "gamma",
                f"{numbers_given['gamma']:g} disagrees with delta and a, which imply "
                f"gamma = {implied:.2f}",
            )
    return view


def guides_give_pose(values: Mapping[str, Any]) -> bool:
    """Whether ``values`` have their pose from guides: they have guides, and not only corners
    beside a pose (the rows ``gsrwt estimate --auto document`` writes: the pose found from the
    corners, which then only frame the output, ``--bbox corners``)."""
    if not has_guides(values):
        return False
    segments = any(values.get(kind) not in (None, "") for kind in ("verticals", "horizontals"))
    posed = any(values.get(name) not in (None, "")
                for name in ("pan", "tilt", "roll", *GSRWT_FIELDS, *RVEC_FIELDS,
                             *QUATERNION_FIELDS))
    return segments or not posed


def guided_view_values(values: Mapping[str, Any], where: str, orientation: int = 1
                       ) -> tuple[dict[str, Any], dict[str, Any]]:
    """Values whose guides show the pose, with that pose (and the focal length, when the
    guides told it) in place of the guides, and the columns the guides add (``aspect``,
    ``aspect_source``, ``focal_source``: :func:`~gsrwt_cli.inputs.guides.guided_values`).
    A pose given besides the guides is an error. ``orientation``: as for
    :func:`view_from_values` (the guides' pixels are the displayed photo's)."""
    posed = [name for name in ("pan", "tilt", "roll", *GSRWT_FIELDS, *RVEC_FIELDS,
                               *QUATERNION_FIELDS) if values.get(name) not in (None, "")]
    if posed:
        raise RecordError(where, posed[0], f"give guides or a pose ({posed[0]}), not both")

    def camera_of(plain: dict[str, Any]) -> Intrinsics | None:
        if not any(plain.get(name) not in (None, "")
                   for name in ("focal", "fx", "fy", "focal_mm", "camera")):
            return None
        return view_from_values({**plain, "pan": 0, "tilt": 0}, where, orientation).intrinsics

    def principal_point_of(plain: dict[str, Any]) -> tuple[float, float] | None:
        view = view_from_values({**plain, "pan": 0, "tilt": 0, "focal": 1.0}, where,
                                orientation)
        return (view.cx, view.cy) if view.has_principal_point else None

    try:
        return guided_values(values, camera_of, principal_point_of)
    except GuideError as error:
        raise RecordError(where, error.field, str(error)) from None


def _focal_from_millimetres(where: str, numbers: dict[str, float]) -> None:
    """Fill fx and fy from ``focal_mm`` and the sensor's size in millimetres, in place."""
    if "focal_mm" not in numbers:
        return
    if given := {"focal", "fx", "fy"} & set(numbers):
        raise RecordError(where, "focal_mm", f"give focal_mm or {sorted(given)[0]}, not both")
    for name in ("sensor_width_mm", "width"):
        if name not in numbers:
            reason = (f"missing field '{name}' (needed with focal_mm"
                      + (", or an image whose size can be read)" if name == "width" else ")"))
            raise RecordError(where, name, reason)
    for name in ("focal_mm", "sensor_width_mm", "sensor_height_mm"):
        if name in numbers and not numbers[name] > 0:
            raise RecordError(where, name, f"{name} must be positive, got {numbers[name]:g}")
    numbers["fx"] = numbers["focal_mm"] * numbers["width"] / numbers["sensor_width_mm"]
    if "sensor_height_mm" in numbers:
        if "height" not in numbers:
            raise RecordError(where, "height", "missing field 'height' (needed with "
                              "sensor_height_mm)")
        numbers["fy"] = numbers["focal_mm"] * numbers["height"] / numbers["sensor_height_mm"]
    else:
        numbers["fy"] = numbers["fx"]


def _pose_from_rotation_fields(where: str, numbers: dict[str, float]) -> None:
    """Fill pan, tilt and roll from an rvec or a quaternion, and distance from a tvec
    (its distance along the wall's normal, not ``tvec_z``), in place."""
    given = set(numbers)
    sources = [name for name, fields in (("pan/tilt", ("pan", "tilt", "roll")),
                                          ("rvec", RVEC_FIELDS), ("quaternion", QUATERNION_FIELDS))
               if given & set(fields)]
    if len(sources) > 1:
        raise RecordError(where, None, f"give one pose, not {' and '.join(sources)}")
    for fields in (RVEC_FIELDS, TVEC_FIELDS, QUATERNION_FIELDS):
        missing = [name for name in fields if name not in given]
        if given & set(fields) and missing:
            raise RecordError(where, missing[0], f"missing field '{missing[0]}' (needed with "
                              f"{', '.join(fields)})")
    if given & set(TVEC_FIELDS) and not given & set(RVEC_FIELDS):
        raise RecordError(where, "tvec_x", "a tvec needs its rvec (rvec_x, rvec_y, rvec_z)")
    try:
        if given & set(RVEC_FIELDS):
            rvec = [numbers[name] for name in RVEC_FIELDS]
            angles = pose_from_rvec(rvec)
            if given & set(TVEC_FIELDS) and "distance" not in given:
                numbers["distance"] = distance_from_tvec(
                    rvec, [numbers[name] for name in TVEC_FIELDS])
        elif given & set(QUATERNION_FIELDS):
            angles = pose_from_quaternion(*(numbers[name] for name in QUATERNION_FIELDS))
        else:
            return
    except PoseError as error:
        field = "rvec_x" if given & set(RVEC_FIELDS) else "qw"
        raise RecordError(where, field, str(error)) from None
    numbers["pan"], numbers["tilt"], numbers["roll"] = angles.pan, angles.tilt, angles.roll


@lru_cache(maxsize=64)
def load_camera_file(path: str) -> Intrinsics:
    """A calibration file's intrinsics (:func:`~gsrwt_cli.inputs.calibration.load_camera`), read
    once
    per process; raises :class:`~gsrwt_cli.inputs.calibration.CalibrationError`."""
    from .calibration import load_camera

    return load_camera(path)


def _view_with_camera(base: Intrinsics, numbers: Mapping[str, float], lens: Lens | None,
                      values: Mapping[str, Any]) -> View:
    """A view whose intrinsics come from a calibration file, with the record's own fields
    (fx, fy or focal, cx, cy, skew, a lens) over the file's."""
    fx, fy = base.fx, base.fy
    if "focal" in numbers:
        fx = fy = numbers["focal"]
    fx, fy = numbers.get("fx", fx), numbers.get("fy", fy)
    cx, cy = numbers.get("cx", base.cx), numbers.get("cy", base.cy)
    overrides_lens = lens is not None or values.get("distortion_model")
    intrinsics = Intrinsics(
        fx, fy, cx, cy, numbers.get("skew", base.skew),
        numbers.get("width", base.width), numbers.get("height", base.height),
        lens if overrides_lens else base.lens,
    )
    pose = Pose(numbers["pan"], numbers["tilt"], numbers.get("roll", 0.0))
    return View(intrinsics=intrinsics, pose=pose, distance=numbers.get("distance"))


def _lens_from_values(values: Mapping[str, Any], numbers: Mapping[str, float]) -> Lens | None:
    """The lens a record gives: ``distortion_model`` (default ``plumb_bob``, or
    ``rational_polynomial`` when a coefficient only it has is given) and coefficients."""
    coefficients = tuple((name, numbers[name]) for name in LENS_FIELDS if name in numbers)
    model = values.get("distortion_model")
    if model is None or str(model).strip() == "":
        if not coefficients:
            return None
        plumb_bob = set(LENS_MODELS["plumb_bob"])
        model = ("plumb_bob" if {name for name, _ in coefficients} <= plumb_bob
                 else "rational_polynomial")
    return Lens(str(model).strip().lower(), coefficients)
