"""Draw docs/poses.png: the frames, the signs of pan, tilt and roll, and roll's image.

Run from the repository: ``python docs/make_poses_figure.py``. The last panel is not drawn by
hand: it projects a wall pattern through OpenCV's own camera (``cv2.projectPoints``) with the
rvecs that :mod:`gsrwt_cli.geometry.rotations` gives for roll 0 and roll +20 degrees.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from gsrwt_cli.geometry.rotations import rvec_from_pose

PANEL_W, PANEL_H = 480, 400
INK, GREY, RED, GREEN, BLUE = (30, 30, 30), (170, 170, 170), (40, 40, 200), (40, 150, 40), (
    200, 90, 30)
FONT = cv2.FONT_HERSHEY_SIMPLEX


def canvas() -> np.ndarray:
    return np.full((PANEL_H, PANEL_W, 3), 255, np.uint8)


def text(img, words: str, at, colour=INK, scale=0.5, thick=1) -> None:
    cv2.putText(img, words, (int(at[0]), int(at[1])), FONT, scale, colour, thick, cv2.LINE_AA)


def arrow(img, start, end, colour, label: str = "", offset=(6, 0), thick=2) -> None:
    start, end = tuple(int(v) for v in start), tuple(int(v) for v in end)
    cv2.arrowedLine(img, start, end, colour, thick, cv2.LINE_AA, tipLength=0.12)
    if label:
        text(img, label, (end[0] + offset[0], end[1] + offset[1]), colour)


def into_page(img, centre, colour, label: str) -> None:
    """An axis pointing away from the viewer: a circled cross."""
    cx, cy = centre
    cv2.circle(img, (cx, cy), 9, colour, 2, cv2.LINE_AA)
    cv2.line(img, (cx - 6, cy - 6), (cx + 6, cy + 6), colour, 2, cv2.LINE_AA)
    cv2.line(img, (cx - 6, cy + 6), (cx + 6, cy - 6), colour, 2, cv2.LINE_AA)
    text(img, label, (cx + 14, cy + 5), colour)


def panel_frames() -> np.ndarray:
    img = canvas()
    text(img, "Frames, seen from behind the camera", (12, 26), scale=0.6, thick=2)
    text(img, "(at pan = tilt = roll = 0 wall and camera agree)", (12, 48), GREY)
    cv2.rectangle(img, (20, 70), (460, 330), GREY, 1, cv2.LINE_AA)
    text(img, "the wall", (30, 90), GREY)
    # Thesis (docs/CONVENTIONS.md)
    o = (90, 250)
    arrow(img, o, (o[0], o[1] - 105), RED, "X up", (8, 8))
    arrow(img, o, (o[0] + 110, o[1]), GREEN, "Y right", (-40, 22))
    into_page(img, (o[0] - 40, o[1] + 50), BLUE, "Z into the wall")
    text(img, "thesis", (40, 118), INK, 0.55, 2)
    # OpenCV
    o = (290, 150)
    arrow(img, o, (o[0] + 110, o[1]), GREEN, "x right", (-40, -10))
    arrow(img, o, (o[0], o[1] + 110), RED, "y down", (8, 0))
    into_page(img, (o[0] + 40, o[1] + 150), BLUE, "z into the wall")
    text(img, "OpenCV", (280, 118), INK, 0.55, 2)
    text(img, "OpenCV -> thesis:  X = -y,  Y = x,  Z = z", (20, 360), INK, 0.55, 1)
    text(img, "C = [[0,-1,0],[1,0,0],[0,0,1]],  W = C R^T C^T", (20, 385), INK, 0.55, 1)
    return img


def panel_pan_tilt() -> np.ndarray:
    img = canvas()
    text(img, "Pan > 0 turns left, tilt > 0 tilts up", (12, 26), scale=0.6, thick=2)
    # Top view: the wall is a line at the top, the camera below it.
    text(img, "from above", (20, 60), GREY)
    cv2.line(img, (20, 90), (230, 90), INK, 3, cv2.LINE_AA)
    text(img, "wall", (190, 80), INK)
    cam = (125, 300)
    cv2.circle(img, cam, 7, INK, -1, cv2.LINE_AA)
    arrow(img, cam, (cam[0], 100), GREY, "Z", (6, 18), thick=1)
    pan = math.radians(30)
    arrow(img, cam, (cam[0] - 190 * math.sin(pan), cam[1] - 190 * math.cos(pan)), BLUE,
          "axis", (8, 4))
    cv2.ellipse(img, cam, (70, 70), 0, -90, -90 - 30, BLUE, 1, cv2.LINE_AA)
    text(img, "pan", (cam[0] - 48, cam[1] - 78), BLUE)
    arrow(img, (170, 330), (225, 330), GREEN, "Y right", (-60, 22))
    # Side view: the wall is a line at the right, seen from the camera's right side.
    text(img, "from its right", (260, 60), GREY)
    cv2.line(img, (450, 70), (450, 330), INK, 3, cv2.LINE_AA)
    cam = (270, 250)
    cv2.circle(img, cam, 7, INK, -1, cv2.LINE_AA)
    arrow(img, cam, (440, cam[1]), GREY, "Z", (-20, 20), thick=1)
    tilt = math.radians(25)
    arrow(img, cam, (cam[0] + 175 * math.cos(tilt), cam[1] - 175 * math.sin(tilt)), BLUE,
          "axis", (-30, -10))
    cv2.ellipse(img, cam, (80, 80), 0, 0, -25, BLUE, 1, cv2.LINE_AA)
    text(img, "tilt", (cam[0] + 86, cam[1] - 14), BLUE)
    arrow(img, (290, 330), (290, 290), RED, "X up", (6, 4))
    text(img, "W = Rx(pan) Ry(tilt) Rz(roll)", (20, 385), INK, 0.55, 1)
    return img


def panel_roll() -> np.ndarray:
    img = canvas()
    text(img, "Roll > 0: the camera's top leans right", (12, 26), scale=0.6, thick=2)
    text(img, "(seen from behind it, looking where it looks)", (12, 48), GREY)
    centre, roll = np.array([240.0, 220.0]), math.radians(20)
    up = np.array([math.sin(roll), -math.cos(roll)])  # screen: right, down
    right = np.array([math.cos(roll), math.sin(roll)])
    ghost = [centre + sx * 110 * np.array([1, 0]) + sy * 70 * np.array([0, -1])
             for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    cv2.polylines(img, [np.int32(ghost)], True, GREY, 1, cv2.LINE_AA)
    body = [centre + sx * 110 * right + sy * 70 * up
            for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    cv2.polylines(img, [np.int32(body)], True, INK, 2, cv2.LINE_AA)
    arrow(img, centre, centre + 150 * up, RED, "camera up (X)", (6, 0))
    arrow(img, centre, centre + np.array([0, -150]), GREY, "", thick=1)
    text(img, "vertical", (centre[0] - 90, centre[1] - 135), GREY)
    cv2.ellipse(img, tuple(int(v) for v in centre), (120, 120), 0, -90, -70, RED, 1,
                cv2.LINE_AA)
    text(img, "roll", (centre[0] + 18, centre[1] - 128), RED)
    arrow(img, centre, centre + 90 * right, GREEN, "right (Y)", (-20, 26))
    text(img, "W[:, 0] = (cos roll, sin roll, 0): up gains +Y", (20, 360), INK, 0.55, 1)
    text(img, "rvec of roll r alone: (0, 0, -r)", (20, 385), INK, 0.55, 1)
    return img


def panel_image() -> np.ndarray:
    """A wall arrow pointing up, through OpenCV's camera with roll 0 (grey) and +20 (ink)."""
    img = canvas()
    text(img, "...so the image shows the scene turned", (12, 26), scale=0.6, thick=2)
    text(img, "counter-clockwise (cv2.projectPoints, roll 0 / +20)", (12, 48), GREY)
    f, cx, cy, distance = 300.0, 240.0, 215.0, 3.0
    k = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1]])
    # An arrow up the wall (OpenCV wall: x right, y down) and a bar to its right.
    shaft = np.array([[0, 0.9], [0, -1.0]])
    head = np.array([[-0.3, -0.6], [0, -1.0], [0.3, -0.6]])
    bar = np.array([[0.5, 0.4], [1.2, 0.4]])
    for roll, colour, thick in ((0.0, GREY, 2), (20.0, INK, 3)):
        rvec = rvec_from_pose(0.0, 0.0, roll)
        rotation = cv2.Rodrigues(rvec)[0]
        tvec = rotation @ np.array([0.0, 0.0, distance])  # camera centre (0, 0, -distance)
        for stroke in (shaft, head, bar):
            points = np.column_stack([stroke, np.zeros(len(stroke))])
            pixels, _ = cv2.projectPoints(points, rvec, tvec, k, None)
            cv2.polylines(img, [np.int32(pixels.reshape(-1, 2))], False, colour, thick,
                          cv2.LINE_AA)
    cv2.drawMarker(img, (int(cx), int(cy)), BLUE, cv2.MARKER_CROSS, 14, 1, cv2.LINE_AA)
    text(img, "principal point", (int(cx) - 150, int(cy) + 30), BLUE)
    cv2.rectangle(img, (40, 70), (440, 350), GREY, 1)
    text(img, "wall up: (0,-1,0) OpenCV = +X thesis", (20, 385), INK, 0.55, 1)
    return img


def main() -> None:
    top = np.hstack([panel_frames(), panel_pan_tilt()])
    bottom = np.hstack([panel_roll(), panel_image()])
    figure = np.vstack([top, bottom])
    figure[:, PANEL_W - 1 : PANEL_W + 1] = 210
    figure[PANEL_H - 1 : PANEL_H + 1, :] = 210
    target = Path(__file__).with_name("poses.png")
    cv2.imwrite(str(target), figure, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print(target)


if __name__ == "__main__":
    main()
