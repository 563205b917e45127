"""Each left-camera chessboard photo's board pose with OpenCV's own calibration of it.

``python tests/data/make_left_poses.py`` writes ``left/left_poses.csv`` from ``left/left*.jpg``
and ``opencv4_left_intrinsics.yml`` (``left_intrinsics.yml`` of OpenCV's samples, which
OpenCV's calibration sample made from these 13 photos): ``cv2.solvePnP`` of the 9x6 inner
corners found as for the right camera (:mod:`make_right_calibration`), the same columns and
frames. ``tests/inputs/test_calibration.py`` reruns it and compares it with the committed file.
"""

from __future__ import annotations

import csv
from pathlib import Path

import cv2
import numpy as np
from make_right_calibration import POSE_COLUMNS, board_pose, detect_corners

HERE = Path(__file__).resolve().parent
#: The photos OpenCV ships (left10.jpg is not among them).
IMAGES = tuple(f"left{number:02d}.jpg" for number in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14))


def opencv_calibration(path: Path = HERE / "opencv4_left_intrinsics.yml"
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The camera matrix and the distortion (k1 k2 p1 p2 k3) OpenCV's sample wrote."""
    storage = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        return (storage.getNode("camera_matrix").mat(),
                storage.getNode("distortion_coefficients").mat().reshape(-1))
    finally:
        storage.release()


def left_poses(folder: Path = HERE / "left") -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each photo's ``(rvec, tvec)``, camera_from_board in OpenCV's frames."""
    matrix, distortion = opencv_calibration()
    return {name: board_pose(detect_corners(folder / name), matrix, distortion)
            for name in IMAGES}


def main() -> None:
    with open(HERE / "left" / "left_poses.csv", "w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file, lineterminator="\n")
        writer.writerow(POSE_COLUMNS)
        for name, (rvec, tvec) in left_poses().items():
            writer.writerow([name, *(repr(float(value)) for value in (*rvec, *tvec))])
    print(f"wrote the poses of {len(IMAGES)} photos")


if __name__ == "__main__":
    main()
