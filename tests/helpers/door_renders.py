"""Rendered corridor walls as a real camera would take them: doors of three contrasts (a white
frame on a white wall among them), seen at pans up to 40 degrees, through optical blur, sensor
noise and JPEG, then rectified with the true view.

The camera image is rendered at twice the resolution (``gsrwt``'s forward model,
:func:`~gsrwt_cli.batch.render_jobs.render_view`) and area-averaged down, so that the far side of an
oblique wall is not aliased; then blurred (Gaussian, sigma 0.8 px), given noise (sigma 2.5 grey
levels) and JPEG-encoded at quality 75. The true door edges are mapped from the texture to the
camera image and into the frontal view through the same maps (the geometry itself is tested
elsewhere; here only the edges are). Scored with :mod:`chessboard_edges`.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from gsrwt_cli import View
from gsrwt_cli.api.rectify import rectify_image
from gsrwt_cli.batch.canonical_views import CanonicalView
from gsrwt_cli.batch.render_jobs import render_view
from gsrwt_cli.geometry.framing import render_map
from tests.helpers.chessboard_edges import Board, Edge
from tests.helpers.images import smooth_texture

WIDTH, HEIGHT, FOCAL = 640, 480, 520.0
FINE = 2  # rendered at FINE x the resolution, then averaged down
TEXTURE_SIZE = (4200, 2000)  # fine texture pixels (width, height)

#: (wall, door casing, door leaf) grey levels: a white frame on a white wall, a painted
#: frame, a dark wooden one.
DOORS = ((196, 212, 204), (190, 140, 175), (185, 70, 120))
#: Leaf width and height, casing width (frontal pixels), and the spacing of the doors.
LEAF_WIDTH, LEAF_HEIGHT, CASING, SPACING = 110, 300, 12, 210
VIEWS = ((0, -5), (15, 8), (-25, -10), (30, 5), (-40, 8), (40, -12))


def _camera(pan: float, tilt: float, fine: int = FINE) -> View:
    return View(pan, tilt, FOCAL * fine, width=WIDTH * fine, height=HEIGHT * fine)


def _door_boxes(axis: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int, int]]]:
    """Casing boxes ``(x0, y0, x1, y1)`` in fine texture pixels (pixel-edge coordinates) of
    the three doors, side by side around the texture point ``axis`` the camera looks at."""
    boxes = []
    for index, shades in enumerate(DOORS):
        centre_x = axis[0] + (index - 1) * SPACING * FINE
        bottom = axis[1] + 170 * FINE
        half = (LEAF_WIDTH / 2 + CASING) * FINE
        top = bottom - (LEAF_HEIGHT + CASING) * FINE
        boxes.append((np.array([centre_x - half, top, centre_x + half, bottom]), shades))
    return boxes


def _texture(axis: np.ndarray, seed: int) -> tuple[np.ndarray, list[tuple[int, np.ndarray]]]:
    """The wall texture and the doors' true edges: (door index, ``(2, 2)`` end points in
    texture pixel-edge coordinates); door 0 is the white frame on the white wall."""
    width, height = TEXTURE_SIZE
    grain = smooth_texture(height // 4, width // 4, seed, channels=1).astype(np.float32)
    grain = cv2.resize(grain, (width, height), interpolation=cv2.INTER_CUBIC)
    texture = np.full((height, width), 0.0, np.float32)
    edges: list[tuple[int, np.ndarray]] = []
    boxes = _door_boxes(axis)
    cols = np.arange(width)[None, :] + 0.5
    rows = np.arange(height)[:, None] + 0.5
    # Each door on its own wall shade, changing smoothly between them (no edge).
    shade = np.full(width, float(boxes[0][1][0]), np.float32)
    for box, (wall, _, _) in boxes:
        shade[int(box[0]) - 60 * FINE:int(box[2]) + 60 * FINE] = wall
    shade = cv2.GaussianBlur(shade[None, :], (0, 0), 40 * FINE)[0]
    texture += shade[None, :]
    texture += 0.04 * (grain - 128)  # a faint, smooth wall grain
    for door, (box, (_, casing, leaf)) in enumerate(boxes):
        x0, y0, x1, y1 = box
        c = CASING * FINE
        in_casing = (cols >= x0) & (cols < x1) & (rows >= y0) & (rows < y1)
        in_leaf = (cols >= x0 + c) & (cols < x1 - c) & (rows >= y0 + c) & (rows < y1)
        texture[in_casing] = casing
        texture[in_leaf] = leaf
        for x in (x0, x0 + c, x1 - c, x1):  # vertical boundaries
            edges.append((door, np.array([[x, y0 + (c if x0 < x < x1 else 0)], [x, y1]])))
        edges.append((door, np.array([[x0, y0], [x1, y0]])))  # tops of casing and leaf
        edges.append((door, np.array([[x0 + c, y0 + c], [x1 - c, y0 + c]])))
        edges.append((door, np.array([[x0, y1], [x1, y1]])))  # the bottom, above the wall
    return np.clip(texture, 0, 255).astype(np.uint8), edges


def door_view(pan: float, tilt: float, seed: int = 0, degrade: bool = True) -> Board:
    """One rendered, degraded and rectified view, with its labelled edges."""
    fine_view = _camera(pan, tilt)
    fine_map = render_map(fine_view, TEXTURE_SIZE)
    axis = fine_map.to_input(np.array([[(WIDTH * FINE - 1) / 2, (HEIGHT * FINE - 1) / 2]]))[0]
    texture, texture_edges = _texture(axis, seed)
    camera = render_view(texture, fine_view)
    camera = cv2.resize(camera, (WIDTH, HEIGHT), interpolation=cv2.INTER_AREA)
    if degrade:
        rng = np.random.default_rng(seed)
        camera = cv2.GaussianBlur(camera.astype(np.float32), (0, 0), 0.8)
        camera = np.clip(camera + rng.normal(0, 2.5, camera.shape), 0, 255).astype(np.uint8)
        _, encoded = cv2.imencode(".jpg", camera, [cv2.IMWRITE_JPEG_QUALITY, 75])
        camera = cv2.imdecode(encoded, cv2.IMREAD_GRAYSCALE)
    view = View(pan, tilt, FOCAL, width=WIDTH, height=HEIGHT)
    frontal, info = rectify_image(camera, view)
    canonical = CanonicalView(Path(f"door_p{pan}_t{tilt}.jpg"), frontal, info.pixel_map,
                              (WIDTH, HEIGHT))
    edges = []
    for door, ends in texture_edges:
        samples = np.linspace(0.0, 1.0, 200)[:, None]
        points = ends[0] + samples * (ends[1] - ends[0]) - 0.5  # pixel-edge to pixel-centre
        fine_camera = fine_map.to_output(points)
        in_camera = ((fine_camera[:, 0] >= 4 * FINE) & (fine_camera[:, 0] <= (WIDTH - 4) * FINE)
                     & (fine_camera[:, 1] >= 4 * FINE)
                     & (fine_camera[:, 1] <= (HEIGHT - 4) * FINE))
        camera_points = (fine_camera + 0.5) / FINE - 0.5
        in_frontal = info.pixel_map.to_output(camera_points)
        in_frontal_frame = ((in_frontal[:, 0] >= 3) & (in_frontal[:, 0] <= WIDTH - 4)
                            & (in_frontal[:, 1] >= 3) & (in_frontal[:, 1] <= HEIGHT - 4))
        seen = np.flatnonzero(in_camera & in_frontal_frame)
        if seen.size < 2:
            continue
        # The longest run of seen samples is the visible part of the edge.
        runs = np.split(seen, np.flatnonzero(np.diff(seen) > 1) + 1)
        run = max(runs, key=len)
        edges.append(Edge(in_frontal[run[0]], in_frontal[run[-1]], True, door))
    outline = np.array([[0, 0], [WIDTH - 1, 0], [WIDTH - 1, HEIGHT - 1], [0, HEIGHT - 1]], float)
    return Board(canonical, edges, outline, camera)


def door_views(degrade: bool = True) -> list[Board]:
    return [door_view(pan, tilt, seed, degrade) for seed, (pan, tilt) in enumerate(VIEWS)]
