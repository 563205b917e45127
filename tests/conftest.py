"""Shared test helpers: an independent pinhole camera and real runs of the ``gsrwt`` command."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

GSRWT = Path(sys.executable).with_name("gsrwt")


def rodrigues(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix about a unit ``axis`` (Rodrigues' formula)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle_rad) * cross + (1 - math.cos(angle_rad)) * cross @ cross


def camera_axes(pan_deg: float, tilt_deg: float) -> np.ndarray:
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
    return np.stack([tilt_rotation @ up, tilt_rotation @ right, tilt_rotation @ forward])


def project_wall_points(
    wall_xy: np.ndarray, distance: float, pan: float, tilt: float, focal: float,
    cx: float, cy: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels ``(col, row)`` of wall points ``(X up, Y right)`` at ``Z = distance``, and depth."""
    points = np.column_stack([wall_xy, np.full(len(wall_xy), distance)])
    in_camera = points @ camera_axes(pan, tilt).T
    depth = in_camera[:, 2]
    x = focal * in_camera[:, 0] / depth
    y = focal * in_camera[:, 1] / depth
    return np.column_stack([y + cx, cy - x]), depth


def frontal_pixels(wall_xy: np.ndarray, distance: float, focal: float, cx: float, cy: float):
    """Pixels of wall points in a camera at the same place facing the wall squarely."""
    return np.column_stack(
        [focal * wall_xy[:, 1] / distance + cx, cy - focal * wall_xy[:, 0] / distance]
    )


def run_gsrwt(*args: str, stdin: str | None = None, cwd: Path | None = None):
    """Run the installed ``gsrwt`` script in a real subprocess."""
    return subprocess.run(
        [str(GSRWT), *args], input=stdin, capture_output=True, text=True, cwd=cwd, timeout=300
    )


@pytest.fixture
def gsrwt():
    return run_gsrwt
