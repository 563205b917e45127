"""Calibrate OpenCV's right-camera chessboard photos and write the files beside this script.

``python tests/data/make_right_calibration.py`` writes, from ``right*.jpg`` here:

- ``right_camera.yml``: OpenCV FileStorage YAML, as OpenCV's calibration sample writes it;
- ``right_camera.xml``: the same in FileStorage XML;
- ``right_camera_ros.yaml``: ROS ``camera_info`` YAML;
- ``right_poses.csv``: each board's pose from ``cv2.solvePnP`` with that calibration,
  ``image,rvec_x,rvec_y,rvec_z,tvec_x,tvec_y,tvec_z``.

The board has 9x6 inner corners. Its object frame is OpenCV's, as ``solvePnP`` returns it:
x along a row of corners (the order ``findChessboardCorners`` gives), y along a column, z into
the board, origin at the first corner; one unit is one square (the photos do not say how
large a square is), so ``tvec`` is in squares. ``tests/inputs/test_calibration.py`` reruns
:func:`calibrate` and compares it with the committed files.
"""

from __future__ import annotations

import csv
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
#: Inner corners per row and per column of the board in the photos.
BOARD = (9, 6)
#: The photos OpenCV ships (right10.jpg is not among them).
IMAGES = tuple(f"right{number:02d}.jpg" for number in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14))
POSE_COLUMNS = ("image", "rvec_x", "rvec_y", "rvec_z", "tvec_x", "tvec_y", "tvec_z")
_SUBPIX = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-6)


@dataclass
class Calibration:
    camera_matrix: np.ndarray  # 3x3
    distortion: np.ndarray  # 5 values, k1 k2 p1 p2 k3
    size: tuple[int, int]  # width, height
    rms: float  # calibrateCamera's reprojection error, pixels
    corners: dict[str, np.ndarray]  # image name -> (54, 2) detected corners, pixels


def board_points() -> np.ndarray:
    """The board's corners in its own frame, ``(54, 3)``, in squares, in detection order."""
    cols, rows = BOARD
    grid = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2)
    return np.column_stack([grid, np.zeros(len(grid))]).astype(np.float64)


def detect_corners(path: Path) -> np.ndarray:
    """The 9x6 inner corners of the board in ``path``, refined to subpixel, ``(54, 2)``."""
    grey = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if grey is None:
        raise RuntimeError(f"cannot read {path}")
    found, corners = cv2.findChessboardCorners(grey, BOARD)
    if not found:
        raise RuntimeError(f"no {BOARD[0]}x{BOARD[1]} board in {path}")
    # A 11x11 window (half-size 5), as OpenCV's samples/python/calibrate.py: the squares are
    # about 25 pixels, and a larger window reaches into the next corner on oblique views.
    corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1), _SUBPIX)
    return corners.reshape(-1, 2).astype(np.float64)


def calibrate(folder: Path = HERE) -> Calibration:
    """``cv2.calibrateCamera`` (plumb_bob, k1 k2 p1 p2 k3) over the photos in ``folder``."""
    corners = {name: detect_corners(folder / name) for name in IMAGES}
    height, width = cv2.imread(str(folder / IMAGES[0]), cv2.IMREAD_GRAYSCALE).shape
    objects = [board_points().astype(np.float32)] * len(corners)
    images = [points.astype(np.float32).reshape(-1, 1, 2) for points in corners.values()]
    rms, matrix, distortion, _, _ = cv2.calibrateCamera(
        objects, images, (width, height), None, None
    )
    return Calibration(matrix, distortion.reshape(-1), (width, height), float(rms), corners)


def board_pose(
    corners: np.ndarray, matrix: np.ndarray, distortion: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``solvePnP``'s ``(rvec, tvec)`` of the board: camera_from_board, OpenCV frames."""
    ok, rvec, tvec = cv2.solvePnP(board_points(), corners, matrix, distortion)
    if not ok:
        raise RuntimeError("solvePnP failed")
    return rvec.reshape(3), tvec.reshape(3)


def write_poses(path: Path, calibration: Calibration) -> None:
    with open(path, "w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file, lineterminator="\n")
        writer.writerow(POSE_COLUMNS)
        for name, corners in calibration.corners.items():
            rvec, tvec = board_pose(corners, calibration.camera_matrix, calibration.distortion)
            writer.writerow([name, *(repr(float(value)) for value in (*rvec, *tvec))])


def main() -> None:
    sys.path.insert(0, str(HERE.parent.parent))
    from gsrwt_cli.geometry.camera import Intrinsics
    from gsrwt_cli.geometry.lens import Lens
    from gsrwt_cli.inputs.calibration import write_opencv_xml, write_opencv_yaml, write_ros_yaml

    calibration = calibrate()
    matrix, width_height = calibration.camera_matrix, calibration.size
    lens = Lens("plumb_bob", tuple(zip(("k1", "k2", "p1", "p2", "k3"),
                                       (float(value) for value in calibration.distortion))))
    intrinsics = Intrinsics(
        fx=matrix[0, 0], fy=matrix[1, 1], cx=matrix[0, 2], cy=matrix[1, 2], skew=matrix[0, 1],
        width=width_height[0], height=width_height[1], lens=lens,
    )
    write_opencv_yaml(HERE / "right_camera.yml", intrinsics)
    write_opencv_xml(HERE / "right_camera.xml", intrinsics)
    write_ros_yaml(HERE / "right_camera_ros.yaml", intrinsics, camera_name="right")
    write_poses(HERE / "right_poses.csv", calibration)
    print(f"calibrated {len(calibration.corners)} photos, RMS {calibration.rms:.4f} px")
    print(matrix)
    print(calibration.distortion)


if __name__ == "__main__":
    main()
