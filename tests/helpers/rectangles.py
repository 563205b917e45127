"""Rectangles on a wall seen through OpenCV's own camera (``cv2.projectPoints``): the four
corners of guided correction at known pan, tilt, roll, focal length and aspect ratio.

Independent of the package: the camera's axes are built from the words
(:func:`tests.helpers.camera.camera_axes`), and OpenCV's camera frame is the thesis's with
``x`` right (thesis ``Y``), ``y`` down (thesis ``-X``), ``z`` forward, so OpenCV's
``camera_from_world`` has rows ``right, -up, forward``; the world points are the thesis's
(``X`` up, ``Y`` right, ``Z`` into the wall) and the camera sits at the origin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.optimize import least_squares

from tests.helpers.camera import camera_axes

#: OpenCV's frame to the thesis's, for camera and wall alike: ``X = -y, Y = x, Z = z``.
C = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class RectangleShot:
    """One rectangle seen by one camera; ``corners``: pixels ``(col, row)`` of its top-left,
    top-right, bottom-right and bottom-left corners, without noise."""

    pan: float
    tilt: float
    roll: float
    focal: float
    aspect: float
    width: int
    height: int
    corners: np.ndarray
    #: The rectangle's centre (thesis world) and height, in the wall's unit (distance 10).
    centre: np.ndarray
    rect_height: float

    @property
    def cx(self) -> float:
        return (self.width - 1) / 2

    @property
    def cy(self) -> float:
        return (self.height - 1) / 2

    def world_corners(self) -> np.ndarray:
        """The corners in the thesis world (``X`` up, ``Y`` right, ``Z`` into the wall)."""
        half_height, half_width = self.rect_height / 2, self.aspect * self.rect_height / 2
        return self.centre + np.array([[half_height, -half_width, 0.0],
                                       [half_height, half_width, 0.0],
                                       [-half_height, half_width, 0.0],
                                       [-half_height, -half_width, 0.0]])

    def sides(self, noisy: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The rectangle's sides as guide segments ``x1, y1, x2, y2`` (pixels): its left and
        right sides (verticals), its top and bottom (horizontals)."""
        c = self.corners if noisy is None else noisy
        verticals = np.array([[*c[0], *c[3]], [*c[1], *c[2]]])
        horizontals = np.array([[*c[0], *c[1]], [*c[3], *c[2]]])
        return verticals, horizontals


def project(points: np.ndarray, pan: float, tilt: float, roll: float, focal: float,
            cx: float, cy: float) -> np.ndarray:
    """Pixels of thesis world points ``(N, 3)`` through ``cv2.projectPoints``."""
    up, right, forward = camera_axes(pan, tilt, roll)
    camera_from_world_cv = np.array([right, -up, forward])
    rvec = cv2.Rodrigues(camera_from_world_cv)[0]
    matrix = np.array([[focal, 0.0, cx], [0.0, focal, cy], [0.0, 0.0, 1.0]])
    pixels, _ = cv2.projectPoints(points.reshape(-1, 1, 3), rvec, np.zeros(3), matrix, None)
    return pixels.reshape(-1, 2)


def rectangle_shot(pan: float, tilt: float, roll: float, focal: float, aspect: float,
                   size: float = 0.6, offset: tuple[float, float] = (0.0, 0.0),
                   width: int = 1024, height: int = 768) -> RectangleShot:
    """A rectangle of ``aspect`` (width over height), centred where the optical axis meets
    the wall (moved by ``offset``, fractions of its height), its height ``size`` times the
    wall's height the image spans there."""
    distance = 10.0
    forward = camera_axes(pan, tilt, roll)[2]
    centre = forward * distance / forward[2]
    along_axis = float(np.linalg.norm(centre))
    rect_height = size * height * along_axis / focal
    rect_width = aspect * rect_height
    x0 = centre[0] + offset[0] * rect_height
    y0 = centre[1] + offset[1] * rect_height
    world = np.array([[x0 + rect_height / 2, y0 - rect_width / 2, distance],
                      [x0 + rect_height / 2, y0 + rect_width / 2, distance],
                      [x0 - rect_height / 2, y0 + rect_width / 2, distance],
                      [x0 - rect_height / 2, y0 - rect_width / 2, distance]])
    corners = project(world, pan, tilt, roll, focal, (width - 1) / 2, (height - 1) / 2)
    return RectangleShot(pan, tilt, roll, focal, aspect, width, height, corners,
                         np.array([x0, y0, distance]), rect_height)


def random_shots(count: int, seed: int, min_angle: float = 0.0, max_pan: float = 40.0,
                 max_tilt: float = 30.0, max_roll: float = 15.0,
                 sizes: tuple[float, float] = (0.4, 0.7)) -> list[RectangleShot]:
    """``count`` rectangles at random poses (``|pan|``, ``|tilt|`` at least ``min_angle``),
    focal lengths 600-1600 px and aspect ratios 0.5-2, heights ``sizes`` of the image's
    (:func:`rectangle_shot`), wholly inside a 1024x768 image."""
    rng = np.random.default_rng(seed)
    shots: list[RectangleShot] = []
    while len(shots) < count:
        pan = float(rng.choice([-1, 1]) * rng.uniform(min_angle, max_pan))
        tilt = float(rng.choice([-1, 1]) * rng.uniform(min_angle, max_tilt))
        roll = float(rng.uniform(-max_roll, max_roll))
        focal = float(rng.uniform(600, 1600))
        aspect = float(math.exp(rng.uniform(math.log(0.5), math.log(2.0))))
        shot = rectangle_shot(pan, tilt, roll, focal, aspect, size=float(rng.uniform(*sizes)),
                              offset=(float(rng.uniform(-0.2, 0.2)),
                                      float(rng.uniform(-0.2, 0.2))))
        inside = np.all((shot.corners >= 0) & (shot.corners <= [shot.width - 1,
                                                                   shot.height - 1]))
        if inside:
            shots.append(shot)
    return shots


def least_squares_pose(shot: RectangleShot, noisy: np.ndarray, mode: str) -> tuple[float, ...]:
    """The yardstick: pan, tilt, roll, focal, aspect of the exact least-squares fit of
    ``noisy`` corners by scipy over ``cv2.projectPoints`` (a rectangle of height 1 in
    OpenCV's wall frame: x right, y down), started at the truth; ``mode`` says which of focal
    and aspect are fixed at the truth (``focal given``, ``aspect given``) or free."""
    up, right, forward = camera_axes(shot.pan, shot.tilt, shot.roll)
    camera_from_wall = np.array([right, -up, forward]) @ C
    tvec = np.array([right, -up, forward]) @ shot.centre / shot.rect_height
    start = [*cv2.Rodrigues(camera_from_wall)[0].ravel(), *tvec]
    if mode != "focal given":
        start.append(math.log(shot.focal))
    if mode != "aspect given":
        start.append(math.log(shot.aspect))

    def model(p: np.ndarray) -> tuple[np.ndarray, float, float]:
        index = 6
        focal = shot.focal
        if mode != "focal given":
            focal, index = math.exp(p[index]), index + 1
        aspect = shot.aspect if mode == "aspect given" else math.exp(p[index])
        half = aspect / 2
        wall = np.array([[-half, -0.5, 0], [half, -0.5, 0], [half, 0.5, 0], [-half, 0.5, 0]])
        matrix = np.array([[focal, 0, shot.cx], [0, focal, shot.cy], [0, 0, 1.0]])
        pixels = cv2.projectPoints(wall.reshape(-1, 1, 3), p[:3], p[3:6], matrix, None)[0]
        return pixels.reshape(-1, 2), focal, aspect

    fit = least_squares(lambda p: (model(p)[0] - noisy).ravel(), np.array(start),
                        method="lm", xtol=1e-14, ftol=1e-14)
    _, focal, aspect = model(fit.x)
    rotation = cv2.Rodrigues(fit.x[:3])[0]
    world_from_camera = C @ rotation.T @ C.T
    tilt = math.degrees(math.asin(world_from_camera[0, 2]))
    pan = math.degrees(math.atan2(-world_from_camera[1, 2], world_from_camera[2, 2]))
    roll = math.degrees(math.atan2(-world_from_camera[0, 1], world_from_camera[0, 0]))
    return pan, tilt, roll, focal, aspect
