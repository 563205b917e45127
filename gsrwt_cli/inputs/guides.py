"""Guides as options and sidecar columns give them (``corners``, ``verticals``,
``horizontals``, ``aspect``, ``fit``), read into the pose they show
(:mod:`gsrwt_cli.geometry.guides`).

Texts: ``corners`` is four pixels ``"x1,y1 x2,y2 x3,y3 x4,y4"`` (top-left, top-right,
bottom-right, bottom-left of a rectangle upright on the wall, as the photo is displayed);
``verticals`` and ``horizontals`` are segments ``"x1,y1,x2,y2;x1,y1,x2,y2;..."``;
``aspect`` is ``W:H`` or one number (width over height); ``fit`` one of
:data:`~gsrwt_cli.geometry.guides.FIT_MODES`. A bad value raises
:class:`~gsrwt_cli.geometry.guides.GuideError` naming the field.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..base.messages import quote
from ..geometry.camera import Intrinsics
from ..geometry.guides import (
    FIT_MODES,
    GuidedPose,
    GuideError,
    check_corners,
    check_segments,
    fitted_pose,
    pose_from_corners,
    pose_from_segments,
)
from ..geometry.rotations import rotation_from_pose

#: The fields that show a pose by hand; ``aspect`` and ``fit`` qualify them.
GUIDE_GIVERS = ("corners", "verticals", "horizontals")
GUIDE_FIELDS = (*GUIDE_GIVERS, "aspect", "fit")
#: Where an estimate's aspect ratio came from (the ``aspect_source`` column).
ASPECT_SOURCES = ("given", "estimated")

_NUMBER = r"\s*[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?\s*"
_POINT = re.compile(rf"({_NUMBER}),({_NUMBER})")


def _given(value: Any) -> bool:
    return value is not None and str(value).strip() != ""


def has_guides(values: Mapping[str, Any]) -> bool:
    """Whether ``values`` show the pose with guides."""
    return any(_given(values.get(name)) for name in GUIDE_GIVERS)


def parse_corners(text: str) -> np.ndarray:
    """``"x1,y1 x2,y2 x3,y3 x4,y4"`` as a checked ``(4, 2)`` array (:func:`~gsrwt_cli.
    geometry.guides.check_corners`)."""
    points = []
    for token in str(text).split():
        match = _POINT.fullmatch(token)
        if match is None:
            raise GuideError("corners", f"{quote(token)} is not a point x,y (corners are "
                                        "\"x1,y1 x2,y2 x3,y3 x4,y4\")")
        points.append((float(match.group(1)), float(match.group(2))))
    if len(points) != 4:
        raise GuideError("corners", f"need 4 corners \"x1,y1 x2,y2 x3,y3 x4,y4\" (top-left, "
                                    f"top-right, bottom-right, bottom-left), got {len(points)}")
    return check_corners(np.array(points))


def parse_segments(text: str, kind: str) -> np.ndarray:
    """``"x1,y1,x2,y2;x1,y1,x2,y2;..."`` as a checked ``(N, 4)`` array; ``kind`` is
    ``verticals`` or ``horizontals``."""
    segments = []
    for part in str(text).split(";"):
        if not part.strip():
            continue
        numbers = part.split(",")
        try:
            values = [float(n) for n in numbers if re.fullmatch(_NUMBER, n)]
        except ValueError:
            values = []
        if len(numbers) != 4 or len(values) != 4:
            raise GuideError(kind, f"{quote(part.strip())} is not a segment x1,y1,x2,y2 "
                                   f"({kind} are \"x1,y1,x2,y2;x1,y1,x2,y2;...\")")
        segments.append(values)
    return check_segments(np.array(segments).reshape(-1, 4), kind)


def parse_aspect(value: Any) -> float:
    """``W:H`` or one number, width over height, as a positive finite number."""
    text = str(value).strip()
    parts = text.split(":")
    try:
        if len(parts) > 2 or not all(re.fullmatch(_NUMBER, p) for p in parts):
            raise ValueError
        aspect = float(parts[0]) / float(parts[1]) if len(parts) == 2 else float(parts[0])
    except (ValueError, ZeroDivisionError):
        aspect = math.nan
    if not (math.isfinite(aspect) and aspect > 0):
        raise GuideError("aspect", f"the aspect ratio is W:H or one positive number (width "
                                   f"over height), got {quote(value)}")
    return aspect


def parse_fit(value: Any) -> str:
    fit = "both" if not _given(value) else str(value).strip().lower()
    if fit not in FIT_MODES:
        raise GuideError("fit", f"fit must be one of {', '.join(FIT_MODES)}, got {quote(value)}")
    return fit


def fit_pose(pan: float, tilt: float, roll: float, fit: Any) -> tuple[float, float, float]:
    """A pose (an estimate's, say) after a ``fit`` mode (:func:`~gsrwt_cli.geometry.guides.
    fitted_pose`)."""
    pose = fitted_pose(rotation_from_pose(pan, tilt, roll), parse_fit(fit))
    return pose.pan, pose.tilt, pose.roll


def guided_pose(values: Mapping[str, Any], camera: Intrinsics | None,
                principal_point: tuple[float, float] | None) -> GuidedPose:
    """The pose the guides of ``values`` show, with ``camera`` (its focal length and lens)
    when one is known, else at ``principal_point`` with the focal length told by the guides.
    Corners win over segments when both are given."""
    fit = parse_fit(values.get("fit"))
    aspect = parse_aspect(values["aspect"]) if _given(values.get("aspect")) else None

    def image_points(pixels: np.ndarray) -> np.ndarray:
        if camera is not None:
            return camera.rays_from_pixels(pixels)[:, :2] * camera.focal
        if principal_point is None:
            raise GuideError("cx", "without a focal length the guides need the principal "
                                   "point: give --cx and --cy, or --width and --height")
        cx, cy = principal_point
        return np.column_stack([cy - pixels[:, 1], pixels[:, 0] - cx])

    focal = None if camera is None else camera.focal
    if _given(values.get("corners")):
        corners = image_points(parse_corners(values["corners"]))
        if not np.all(np.isfinite(corners)):
            raise GuideError("corners", "a corner is beyond what the lens model sees")
        return pose_from_corners(corners, focal, aspect, fit)
    if aspect is not None:
        raise GuideError("aspect", "an aspect ratio goes with --corners")
    segments = {}
    for kind in ("verticals", "horizontals"):
        if _given(values.get(kind)):
            lines = parse_segments(values[kind], kind)
            ends = image_points(lines.reshape(-1, 2)).reshape(-1, 4)
            if not np.all(np.isfinite(ends)):
                raise GuideError(kind, "a segment end is beyond what the lens model sees")
            segments[kind] = ends
    return pose_from_segments(segments.get("verticals"), segments.get("horizontals"), focal,
                              fit)


def guided_values(values: Mapping[str, Any],
                  camera_of: Callable[[dict[str, Any]], Intrinsics | None],
                  principal_point_of: Callable[[dict[str, Any]], tuple[float, float] | None],
                  ) -> tuple[dict[str, Any], dict[str, Any]]:
    """``values`` with the pose their guides show (pan, tilt, roll; the focal length too
    when the guides told it) and the guide fields left out, and the columns they add:
    ``aspect``, ``aspect_source`` (with corners) and ``focal_source`` (``estimated``, when
    the guides told the focal length).

    ``camera_of``: the intrinsics the values give (None without a focal length);
    ``principal_point_of``: their principal point when they give no focal length.
    """
    plain = {name: value for name, value in values.items() if name not in GUIDE_FIELDS}
    camera = camera_of(plain)
    found = guided_pose(values, camera, None if camera is not None else principal_point_of(plain))
    plain.update(pan=found.pose.pan, tilt=found.pose.tilt, roll=found.pose.roll)
    columns: dict[str, Any] = {}
    if found.focal_estimated:
        plain["focal"] = found.focal
        columns["focal_source"] = "estimated"
    if found.aspect is not None:
        columns["aspect"] = found.aspect
        columns["aspect_source"] = "estimated" if found.aspect_estimated else "given"
    return plain, columns
