"""The picture of a pose estimate (``gsrwt estimate --draw``): why the estimate is what it is.

Drawn into an 8-bit BGR copy of the image: the segments coloured by their direction
(vertical red, the wall's horizontal green, the wall's normal blue, none grey), the horizon
(the vanishing line of horizontal planes, yellow) and the outline of what the canonical
frontal view of the wall shows (``rectify --bbox frontal``, magenta), with the pose written
at the top left; or the reason there is no pose. With ``--auto document``: the document's
outline (magenta, its top-left corner marked) or the reason there is none.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from ..geometry.camera import Intrinsics, View
from ..vision.edges import colour8
from .estimate import PoseEstimate
from .rectify import plan_image

#: BGR colours of the three directions (vertical, wall horizontal, normal) and of the rest.
DIRECTION_COLOURS = ((0, 0, 255), (0, 190, 0), (255, 110, 0))
UNASSIGNED = (150, 150, 150)
HORIZON = (0, 230, 255)
OUTLINE = (255, 0, 255)


def draw_estimate(image: np.ndarray, estimate: PoseEstimate,
                  camera: Intrinsics | None) -> np.ndarray:
    """The picture (BGR, the image's size) of ``estimate`` made with ``camera`` (with size)."""
    picture = (colour8(np.asarray(image)) * 0.55).astype(np.uint8)
    height, width = picture.shape[:2]
    thickness = max(1, round(math.hypot(width, height) / 600))
    for line, label in zip(estimate.lines, estimate.labels):
        colour = DIRECTION_COLOURS[label] if label >= 0 else UNASSIGNED
        ends = np.round(line).astype(int)
        cv2.line(picture, (int(ends[0]), int(ends[1])), (int(ends[2]), int(ends[3])), colour,
                 thickness, cv2.LINE_AA)
    if estimate.ok and camera is not None and estimate.pose is not None:
        _draw_horizon(picture, estimate, camera, thickness)
        _draw_outline(picture, estimate, camera, thickness)
        pose = estimate.pose
        text = (f"pan {pose.pan:.1f} tilt {pose.tilt:.1f} roll {pose.roll:.1f} "
                f"f {estimate.focal:.0f} confidence {estimate.confidence:.2f}")
    else:
        text = estimate.error or "no pose"
    scale = max(0.4, width / 1400)
    cv2.putText(picture, text, (8, int(24 * scale + 8)), cv2.FONT_HERSHEY_SIMPLEX, scale,
                (255, 255, 255), max(1, thickness), cv2.LINE_AA)
    return picture


def _draw_horizon(picture: np.ndarray, estimate: PoseEstimate, camera: Intrinsics,
                  thickness: int) -> None:
    """The line of ideal pixels whose rays are horizontal: ``(K^-1)^T up``."""
    assert estimate.world_from_camera is not None
    focal = camera.focal
    camera_from_pixel = np.diag([1 / focal, 1 / focal, 1.0]) @ camera.image_from_pixel()
    line = camera_from_pixel.T @ estimate.world_from_camera[0]
    norm = math.hypot(line[0], line[1])
    if norm == 0:
        return
    a, b, c = line / norm
    height, width = picture.shape[:2]
    foot = np.array([-a * c, -b * c])
    along = np.array([-b, a]) * 4 * (width + height)
    p1, p2 = np.round(foot - along).astype(int), np.round(foot + along).astype(int)
    inside, q1, q2 = cv2.clipLine((0, 0, width, height), tuple(map(int, p1)),
                                  tuple(map(int, p2)))
    if inside:
        cv2.line(picture, q1, q2, HORIZON, thickness, cv2.LINE_AA)


def _draw_outline(picture: np.ndarray, estimate: PoseEstimate, camera: Intrinsics,
                  thickness: int) -> None:
    """The border of the frontal output frame, mapped back into the image."""
    height, width = picture.shape[:2]
    try:
        plan = plan_image(View(intrinsics=camera, pose=estimate.pose), width, height)
    except ValueError:
        return
    out_w, out_h = plan.size
    steps = np.linspace(0.0, 1.0, 60)
    border = np.concatenate([
        np.column_stack([steps * out_w, np.zeros_like(steps)]),
        np.column_stack([np.full_like(steps, out_w), steps * out_h]),
        np.column_stack([(1 - steps) * out_w, np.full_like(steps, out_h)]),
        np.column_stack([np.zeros_like(steps), (1 - steps) * out_h]),
    ]) - 0.5
    with np.errstate(all="ignore"):
        points = plan.pixel_map.to_input(border)
    finite = np.all(np.isfinite(points), axis=1) & np.all(np.abs(points) < 1e6, axis=1)
    if finite.sum() >= 2:
        polygon = np.round(points[finite] * 16).astype(np.int32)
        cv2.polylines(picture, [polygon], True, OUTLINE, thickness, cv2.LINE_AA, shift=4)


def draw_document(image: np.ndarray, corners: np.ndarray | None, text: str) -> np.ndarray:
    """The picture (BGR, the image's size) of ``--auto document``: the document's ``corners``
    ((4, 2), top-left first; None: none found), its top-left corner marked, and ``text``."""
    picture = (colour8(np.asarray(image)) * 0.55).astype(np.uint8)
    height, width = picture.shape[:2]
    thickness = max(1, round(math.hypot(width, height) / 600))
    if corners is not None:
        cv2.polylines(picture, [np.round(corners * 4).astype(np.int32)], True, OUTLINE,
                      thickness, cv2.LINE_AA, 2)
        x, y = np.round(corners[0]).astype(int)
        cv2.circle(picture, (int(x), int(y)), 4 * thickness, OUTLINE, thickness, cv2.LINE_AA)
    scale = max(0.4, width / 1400)
    cv2.putText(picture, text, (8, int(24 * scale + 8)), cv2.FONT_HERSHEY_SIMPLEX, scale,
                (255, 255, 255), max(1, thickness), cv2.LINE_AA)
    return picture
