"""Test scenes for the pose estimator: textured box rooms and corridors rendered from known
poses through OpenCV's own camera (``cv2.projectPoints``, homographies from
``cv2.getPerspectiveTransform``), independent of gsrwt's camera code.

Frames: the thesis's world (X up, Y right, Z into the back wall; docs/CONVENTIONS.md) holds the
scene; OpenCV's wall frame is ``x = Y, y = -X, z = Z``, and the camera's rotation is built
here from the formula ``world_from_camera = Rx(pan) Ry(tilt) Rz(roll)``.
Used by tests/api/test_estimate*.py, tests/cli/test_estimate.py and
benchmarks/bench_estimate.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

#: OpenCV camera axes -> thesis camera axes (docs/CONVENTIONS.md), also OpenCV wall -> thesis world.
C = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def world_from_camera(pan: float, tilt: float, roll: float) -> np.ndarray:
    """docs/CONVENTIONS.md, written out again: ``Rx(pan) @ Ry(tilt) @ Rz(roll)`` (degrees)."""
    a, b, r = (math.radians(v) for v in (pan, tilt, roll))
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    return rx @ ry @ rz


@dataclass(frozen=True)
class Shot:
    """A rendered image and its truth: pose, focal length, principal point."""

    image: np.ndarray
    pan: float
    tilt: float
    roll: float
    focal: float
    cx: float
    cy: float

    @property
    def world_from_camera(self) -> np.ndarray:
        return world_from_camera(self.pan, self.tilt, self.roll)

    @property
    def vertical(self) -> np.ndarray:
        """The world's up in the camera's (thesis) frame."""
        return self.world_from_camera[0]

    @property
    def wall_normal(self) -> np.ndarray:
        return self.world_from_camera[2]


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    """Degrees between two directions (sign ignored)."""
    cosine = abs(float(np.dot(a, b))) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(1.0, cosine)))


class OpenCvCamera:
    """Projects thesis world points with ``cv2.projectPoints``."""

    def __init__(self, pan: float, tilt: float, roll: float, focal: float,
                 cx: float, cy: float, position: np.ndarray) -> None:
        w = world_from_camera(pan, tilt, roll)
        camera_from_wall = C.T @ w.T @ C  # OpenCV frames (docs/CONVENTIONS.md, inverted)
        self.rvec = cv2.Rodrigues(camera_from_wall)[0]
        self.position_cv = C.T @ position
        self.tvec = -camera_from_wall @ self.position_cv
        self.rotation = camera_from_wall
        self.matrix = np.array([[focal, 0, cx], [0, focal, cy], [0, 0, 1.0]])

    def depth(self, world: np.ndarray) -> np.ndarray:
        """z of thesis world points ``(N, 3)`` in OpenCV's camera frame."""
        return (world @ C @ self.rotation.T + self.tvec.ravel())[:, 2]

    def project(self, world: np.ndarray) -> np.ndarray:
        cv_points = (world @ C).reshape(-1, 1, 3)  # thesis world -> OpenCV wall: C^T p
        pixels, _ = cv2.projectPoints(cv_points, self.rvec, self.tvec, self.matrix, None)
        return pixels.reshape(-1, 2)


def _wall_texture(rng: np.random.Generator, width: int, height: int, kind: str) -> np.ndarray:
    """A BGR texture ``height x width`` (1 px per scene unit) with Manhattan edges and clutter."""
    base = rng.integers(120, 210, size=3)
    grain = rng.integers(0, 12, size=(height, width, 1), dtype=np.uint8)
    texture = np.ascontiguousarray((base.astype(np.uint8) + grain).astype(np.uint8))
    if kind == "floor":
        step = int(rng.integers(40, 70))
        for x in range(0, width, step):
            cv2.line(texture, (x, 0), (x, height), (60, 60, 60), 2)
        for y in range(0, height, step):
            cv2.line(texture, (0, y), (width, y), (60, 60, 60), 2)
        return texture
    if kind == "ceiling":
        for _ in range(6):
            x, y = int(rng.integers(0, width - 80)), int(rng.integers(0, height - 80))
            cv2.rectangle(texture, (x, y), (x + 70, y + 70), (245, 245, 245), -1)
        return texture
    # skirting board and a picture rail
    cv2.rectangle(texture, (0, height - 12), (width, height), (40, 40, 40), -1)
    cv2.line(texture, (0, 40), (width, 40), (80, 80, 80), 2)
    for _ in range(int(rng.integers(2, 4))):  # doors: frame, leaf, knob
        x = int(rng.integers(10, width - 110))
        cv2.rectangle(texture, (x, height - 12 - 200), (x + 95, height - 12), (50, 70, 90), -1)
        cv2.rectangle(texture, (x + 8, height - 200), (x + 87, height - 12), (90, 120, 150), -1)
        cv2.circle(texture, (x + 75, height - 110), 4, (30, 30, 30), -1)
    for _ in range(int(rng.integers(2, 5))):  # windows with bars
        x, y = int(rng.integers(0, width - 90)), int(rng.integers(50, max(51, height - 150)))
        cv2.rectangle(texture, (x, y), (x + 80, y + 90), (230, 200, 170), -1)
        cv2.rectangle(texture, (x, y), (x + 80, y + 90), (20, 20, 20), 3)
        cv2.line(texture, (x + 40, y), (x + 40, y + 90), (20, 20, 20), 2)
        cv2.line(texture, (x, y + 45), (x + 80, y + 45), (20, 20, 20), 2)
    for _ in range(int(rng.integers(4, 9))):  # clutter: posters, shelves, stray strokes
        x, y = int(rng.integers(0, width - 40)), int(rng.integers(0, height - 40))
        w, h = int(rng.integers(10, 60)), int(rng.integers(10, 60))
        colour = tuple(int(v) for v in rng.integers(0, 255, size=3))
        if rng.random() < 0.6:
            cv2.rectangle(texture, (x, y), (x + w, y + h), colour, -1)
        else:
            cv2.line(texture, (x, y), (x + w, y + h * int(rng.choice([-1, 1]))), colour, 2)
    for _ in range(3):
        centre = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        cv2.circle(texture, centre, int(rng.integers(5, 25)), (20, 90, 20), 2)
    return texture


def _clip_near(polygon: np.ndarray, depths: np.ndarray, near: float) -> np.ndarray:
    """The part of a 3D polygon with OpenCV camera depth above ``near`` (Sutherland-Hodgman)."""
    out = []
    count = len(polygon)
    for i in range(count):
        a, b = polygon[i], polygon[(i + 1) % count]
        da, db = depths[i], depths[(i + 1) % count]
        if da >= near:
            out.append(a)
        if (da >= near) != (db >= near):
            t = (near - da) / (db - da)
            out.append(a + t * (b - a))
    return np.array(out)


def render_room(pan: float, tilt: float, roll: float = 0.0, *, focal: float = 500.0,
                size: tuple[int, int] = (640, 480), room: tuple[float, float, float] = (
                    280.0, 400.0, 600.0), seed: int = 0, blur: float = 0.6,
                noise: float = 3.0, jpeg: int | None = 85, supersample: int = 2) -> Shot:
    """A box room (height, width, depth in scene units; back wall at Z = depth) seen from
    near its open front at the given pose, as an 8-bit BGR image with its truth.

    Rendered at ``supersample`` times the size and shrunk (area filter) so that edges are
    antialiased, then blurred (Gaussian ``blur`` px), noised (``noise`` grey levels) and
    JPEG-compressed at quality ``jpeg``.
    """
    rng = np.random.default_rng(seed)
    width, height = size
    cx, cy = (width - 1) / 2.0, (height - 1) / 2.0
    s = supersample
    room_h, room_w, depth = room
    position = np.array([room_h * rng.uniform(0.4, 0.6), room_w * rng.uniform(-0.15, 0.15),
                         rng.uniform(-60.0, 0.0)])
    camera = OpenCvCamera(pan, tilt, roll, focal * s, (cx + 0.5) * s - 0.5,
                          (cy + 0.5) * s - 0.5, position)
    half_w = room_w / 2
    # faces: corners (thesis world, in texture order: top-left, top-right, bottom-right,
    # bottom-left as the texture is drawn) and the texture's size
    z0 = 0.0
    faces = {
        "back": (np.array([[room_h, -half_w, depth], [room_h, half_w, depth],
                           [0, half_w, depth], [0, -half_w, depth]]), (room_w, room_h), "wall"),
        "left": (np.array([[room_h, -half_w, z0], [room_h, -half_w, depth],
                           [0, -half_w, depth], [0, -half_w, z0]]), (depth, room_h), "wall"),
        "right": (np.array([[room_h, half_w, depth], [room_h, half_w, z0],
                            [0, half_w, z0], [0, half_w, depth]]), (depth, room_h), "wall"),
        "floor": (np.array([[0, -half_w, depth], [0, half_w, depth],
                            [0, half_w, z0], [0, -half_w, z0]]), (room_w, depth), "floor"),
        "ceiling": (np.array([[room_h, -half_w, z0], [room_h, half_w, z0],
                              [room_h, half_w, depth], [room_h, -half_w, depth]]),
                    (room_w, depth), "ceiling"),
    }
    big = (width * s, height * s)
    canvas = np.full((big[1], big[0], 3), 90, np.uint8)
    for corners, (tw, th), kind in faces.values():
        tw, th = int(tw), int(th)
        texture = _wall_texture(rng, tw, th, kind)
        depths = camera.depth(corners)
        visible = _clip_near(corners, depths, 1.0)
        if len(visible) < 3:
            continue
        # texture pixel (u, v) <-> world point on the face, by the corners' bilinear frame
        origin, u_axis, v_axis = corners[0], corners[1] - corners[0], corners[3] - corners[0]
        image_points = camera.project(visible)
        coeffs = np.linalg.lstsq(np.column_stack([u_axis, v_axis]),
                                 (visible - origin).T, rcond=None)[0].T
        texture_points = coeffs * np.array([tw, th])
        pick = [0, 1, 2, 3] if len(visible) >= 4 else [0, 1, 2, 2]
        if len(visible) < 4:
            continue
        homography = cv2.getPerspectiveTransform(
            texture_points[pick].astype(np.float32), image_points[pick].astype(np.float32))
        warped = cv2.warpPerspective(texture, homography, big, flags=cv2.INTER_LINEAR,
                                     borderMode=cv2.BORDER_REPLICATE)
        mask = np.zeros((big[1], big[0]), np.uint8)
        polygon = np.round(image_points * 16).astype(np.int32)
        cv2.fillPoly(mask, [polygon], 255, lineType=cv2.LINE_8, shift=4)
        canvas[mask > 0] = warped[mask > 0]
    image = cv2.resize(canvas, size, interpolation=cv2.INTER_AREA) if s > 1 else canvas
    if blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), blur)
    if noise > 0:
        image = np.clip(image + rng.normal(0, noise, image.shape), 0, 255).astype(np.uint8)
    if jpeg is not None:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, jpeg])
        image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    return Shot(image, pan, tilt, roll, focal, cx, cy)


def random_shots(count: int, seed: int = 1, size: tuple[int, int] = (640, 480)) -> list[Shot]:
    """``count`` rooms and corridors: pans up to 40 degrees either way (some nearly frontal),
    tilts of both signs up to 20, rolls up to 10, focal lengths 0.6-1.4 widths."""
    rng = np.random.default_rng(seed)
    shots = []
    for index in range(count):
        pan = float(rng.choice([rng.uniform(-5, 5), rng.uniform(-40, 40),
                                rng.choice([-1, 1]) * rng.uniform(30, 40)]))
        tilt = float(rng.uniform(-20, 20))
        roll = float(rng.uniform(-10, 10))
        focal = float(rng.uniform(0.6, 1.4) * size[0])
        corridor = index % 3 == 2
        room = (260.0, 220.0, 1400.0) if corridor else (280.0, float(rng.uniform(350, 600)),
                                                          float(rng.uniform(400, 800)))
        shots.append(render_room(pan, tilt, roll, focal=focal, size=size, room=room,
                                 seed=seed * 1000 + index, blur=float(rng.uniform(0.3, 1.2)),
                                 noise=float(rng.uniform(1, 5)),
                                 jpeg=int(rng.integers(60, 95))))
    return shots
