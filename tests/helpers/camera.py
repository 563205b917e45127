"""An independent pinhole camera, built from words, not from the package.

The camera's axes come from the sentences of docs/CONVENTIONS.md (pan > 0 turns it left, tilt
> 0 up, roll > 0 leans its top to the right), each turn by Rodrigues' formula about an axis
the words name; :func:`render_view` casts its rays at a textured wall and
:func:`expected_rectified` is the frontal view the thesis defines (Fig. 5.7). Tests compare
the package's transform, renders and rectifications with these.
"""

from __future__ import annotations

import math

import cv2
import numpy as np


def rodrigues(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix about a unit ``axis`` (Rodrigues' formula)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle_rad) * cross + (1 - math.cos(angle_rad)) * cross @ cross


def camera_axes(pan_deg: float, tilt_deg: float, roll_deg: float = 0.0) -> np.ndarray:
    """Rows: the camera's up, right and forward axes in the wall's frame, built from the words.

    Independent of the package: start facing the wall (X up, Y right, Z forward), turn about
    the vertical axis so that forward moves to the left (pan > 0), then about the camera's own
    right axis so that forward moves up (tilt > 0).
    """
    up, right, forward = np.eye(3)
    pan_sense = -1.0 if (rodrigues(up, 0.1) @ forward)[1] > 0 else 1.0  # pan > 0: left, -Y
    pan_rotation = rodrigues(up, pan_sense * math.radians(pan_deg))
    up, right, forward = pan_rotation @ up, pan_rotation @ right, pan_rotation @ forward
    tilt_sense = -1.0 if (rodrigues(right, 0.1) @ forward)[0] < 0 else 1.0  # tilt > 0: up, +X
    tilt_rotation = rodrigues(right, tilt_sense * math.radians(tilt_deg))
    up, right, forward = tilt_rotation @ up, tilt_rotation @ right, tilt_rotation @ forward
    # Roll > 0: about the camera's own forward axis, so that its top leans to its right.
    roll_sense = 1.0 if (rodrigues(forward, 0.1) @ up) @ right > 0 else -1.0
    roll_rotation = rodrigues(forward, roll_sense * math.radians(roll_deg))
    return np.stack([roll_rotation @ up, roll_rotation @ right, forward])


def project_wall_points(
    wall_xy: np.ndarray, distance: float, pan: float, tilt: float, focal: float,
    cx: float, cy: float, roll: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels ``(col, row)`` of wall points ``(X up, Y right)`` at ``Z = distance``, and depth."""
    points = np.column_stack([wall_xy, np.full(len(wall_xy), distance)])
    in_camera = points @ camera_axes(pan, tilt, roll).T
    depth = in_camera[:, 2]
    x = focal * in_camera[:, 0] / depth
    y = focal * in_camera[:, 1] / depth
    return np.column_stack([y + cx, cy - x]), depth


def frontal_pixels(wall_xy: np.ndarray, distance: float, focal: float, cx: float, cy: float):
    """Pixels of wall points in a camera at the same place facing the wall squarely."""
    return np.column_stack(
        [focal * wall_xy[:, 1] / distance + cx, cy - focal * wall_xy[:, 0] / distance]
    )


def render_view(texture, pan, tilt, focal, width, height, cx, cy, distance=10.0, centre=None,
                roll=0.0):
    """What a pinhole camera sees of a wall covered by ``texture`` (independent of gsrwt).

    Casts the ray of every camera pixel with :func:`camera_axes`, meets the wall ``Z =
    distance`` and samples the texture there (bilinear). ``centre``: the wall point under the
    texture's centre (default: where the optical axis meets the wall). Returns the image and
    a mask of pixels that saw the texture.
    """
    axes = camera_axes(pan, tilt, roll)
    if centre is None:
        centre = distance * axes[2][:2] / axes[2][2]
    cols, rows = np.meshgrid(np.arange(width, dtype=float), np.arange(height, dtype=float))
    x, y = cy - rows, cols - cx
    rays = x[..., None] * axes[0] + y[..., None] * axes[1] + focal * axes[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = distance / rays[..., 2]
        wall_x, wall_y = t * rays[..., 0], t * rays[..., 1]
    th, tw = texture.shape[:2]
    unit = distance / focal
    tex_col = (wall_y - centre[1]) / unit + (tw - 1) / 2
    tex_row = (th - 1) / 2 - (wall_x - centre[0]) / unit
    valid = (rays[..., 2] > 0) & (tex_col >= 0) & (tex_col <= tw - 1) & (tex_row >= 0)
    valid &= tex_row <= th - 1
    map_x = np.where(valid, tex_col, -10).astype(np.float32)
    map_y = np.where(valid, tex_row, -10).astype(np.float32)
    image = cv2.remap(texture, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    return image, valid, centre


def expected_rectified(texture, pan, tilt, focal, width, height, cx, cy, distance, centre,
                       margin=2, roll=0.0):
    """The frontal view gsrwt should produce (default frame) and the mask the camera saw.

    Output pixel ``(col, row)`` shows the wall point ``A + ((cy - row), (col - cx)) Zc/f`` with
    ``A`` where the optical axis meets the wall (Fig. 5.7); it counts when its projection
    lands at least ``margin`` pixels inside the camera image and on the texture.
    """
    axes = camera_axes(pan, tilt)
    axis_point = distance * axes[2][:2] / axes[2][2]
    unit = distance / focal
    cols, rows = np.meshgrid(np.arange(width, dtype=float), np.arange(height, dtype=float))
    wall = np.stack([axis_point[0] + (cy - rows) * unit, axis_point[1] + (cols - cx) * unit], -1)
    pixels, depth = project_wall_points(wall.reshape(-1, 2), distance, pan, tilt, focal, cx, cy,
                                        roll)
    pixels = pixels.reshape(height, width, 2)
    seen = (depth.reshape(height, width) > 0) & (pixels[..., 0] >= margin)
    seen &= (pixels[..., 0] <= width - 1 - margin) & (pixels[..., 1] >= margin)
    seen &= pixels[..., 1] <= height - 1 - margin
    th, tw = texture.shape[:2]
    tex_col = (wall[..., 1] - centre[1]) / unit + (tw - 1) / 2
    tex_row = (th - 1) / 2 - (wall[..., 0] - centre[0]) / unit
    seen &= (tex_col >= margin) & (tex_col <= tw - 1 - margin) & (tex_row >= margin)
    seen &= tex_row <= th - 1 - margin
    expected = cv2.remap(texture, tex_col.astype(np.float32), tex_row.astype(np.float32),
                         cv2.INTER_LINEAR)
    return expected, seen
