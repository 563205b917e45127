"""Draw a synthetic frontal view of a corridor wall with a door (test texture).

The picture is a head-on (no perspective) view of a light painted corridor wall:
a dark baseboard and floor at the bottom, a wooden door with a dark casing, a door
knob on an escutcheon plate, a peek window in the door, a light-switch plate and a
room sign ("ROOM 2.14"). Everything is drawn with numpy and cv2 drawing primitives
(text with cv2's Hershey font); no external images or fonts are used. The wall and
floor carry a faint, smooth, low-contrast noise texture drawn from a fixed seed, so
the output is identical on every run.

Scale: 1 px is about 3.6 mm, so the 3000 x 2000 px texture covers about 10.8 m x 7.2 m
of wall. The centre pixel (1499.5, 999.5) is where the camera looks at pan = tilt = 0.

Two files are written next to this script:

* ``corridor_wall.png``  -- the 8-bit BGR texture (PNG compression level 9);
* ``corridor_wall.json`` -- the true positions of the drawn features, used by tests.

Regenerate both with::

    /work/venv/bin/python sample_data/draw_texture.py
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

WIDTH = 3000
HEIGHT = 2000
SEED = 20240214
MM_PER_PX = 3.6

OUT_DIR = Path(__file__).resolve().parent
PNG_PATH = OUT_DIR / "corridor_wall.png"
JSON_PATH = OUT_DIR / "corridor_wall.json"

# --- Geometry, all in pixel-edge coordinates (pixel c spans [c, c+1)). -------------
# Boxes are (x0, y0, x1, y1) with x1 / y1 exclusive, i.e. a box covers the pixel
# columns x0 .. x1 - 1 and the pixel rows y0 .. y1 - 1.

# The camera (the texture's centre, row 999.5) is at knob height, about 1 m above the floor.
BASEBOARD_TOP = HEIGHT // 2 + 280
BASEBOARD_HEIGHT = 30

LEAF_W, LEAF_H = 250, 580
LEAF_X0 = WIDTH // 2 - 400  # so that every thesis view (320x240, f = 280) sees the door
LEAF = (LEAF_X0, BASEBOARD_TOP - LEAF_H, LEAF_X0 + LEAF_W, BASEBOARD_TOP)
CASING = 18
FRAME_OUTER = (LEAF[0] - CASING, LEAF[1] - CASING, LEAF[2] + CASING, BASEBOARD_TOP)

# Escutcheon plate (26 x 80) centred 35 px left of the leaf's right edge, 270 px above the floor.
PLATE_W, PLATE_H = 26, 80
PLATE_CX, PLATE_CY = LEAF[2] - 35, BASEBOARD_TOP - 270
PLATE = (PLATE_CX - PLATE_W // 2, PLATE_CY - PLATE_H // 2,
         PLATE_CX + PLATE_W // 2, PLATE_CY + PLATE_H // 2)
KNOB_RADIUS = 11
KNOB_BOX = (40, 100)

# Peek window: 110 x 80 overall (frame included), centred on the leaf, 450 px above the floor.
WINDOW_W, WINDOW_H = 110, 80
WINDOW_FRAME = 8
WINDOW_CX, WINDOW_CY = (LEAF[0] + LEAF[2]) // 2, BASEBOARD_TOP - 450
WINDOW = (WINDOW_CX - WINDOW_W // 2, WINDOW_CY - WINDOW_H // 2,
          WINDOW_CX + WINDOW_W // 2, WINDOW_CY + WINDOW_H // 2)
WINDOW_BOX = (120, 90)

# Light switch plate: 46 x 76, centred 150 px right of the frame's outer right edge.
SWITCH_W, SWITCH_H = 46, 76
SWITCH_CX, SWITCH_CY = FRAME_OUTER[2] + 150, BASEBOARD_TOP - 350
SWITCH = (SWITCH_CX - SWITCH_W // 2, SWITCH_CY - SWITCH_H // 2,
          SWITCH_CX + SWITCH_W // 2, SWITCH_CY + SWITCH_H // 2)

# Room sign: 200 x 70, above the switch, centred on the same column.
SIGN_W, SIGN_H = 200, 70
SIGN_CX, SIGN_CY = SWITCH_CX, BASEBOARD_TOP - 490
SIGN = (SIGN_CX - SIGN_W // 2, SIGN_CY - SIGN_H // 2,
        SIGN_CX + SIGN_W // 2, SIGN_CY + SIGN_H // 2)
SIGN_TEXT = "ROOM 2.14"

# --- Colours (BGR). ----------------------------------------------------------------
WALL_BGR = (188, 203, 214)       # light warm beige paint (grey ~205)
FLOOR_BGR = (92, 104, 116)       # grey-brown linoleum (grey ~107)
BASEBOARD_BGR = (38, 42, 48)     # dark skirting (grey ~43)
CASING_BGR = (24, 26, 30)        # dark painted casing (grey ~27)
LEAF_BGR = (78, 121, 158)        # medium-dark oak (grey ~127)
GLASS_BGR = (92, 62, 40)         # dark bluish glass (grey ~59)
WINDOW_FRAME_BGR = (226, 229, 232)
PLATE_BGR = (150, 160, 168)      # brushed metal
KNOB_BGR = (176, 190, 200)
SWITCH_BGR = (240, 242, 243)
SIGN_BORDER_BGR = (70, 52, 40)
SIGN_FACE_BGR = (238, 240, 241)
TEXT_BGR = (30, 30, 30)

Box = tuple[int, int, int, int]
Colour = tuple[int, int, int]

SHIFT = 4  # fractional bits for sub-pixel cv2 drawing
ONE = 1 << SHIFT


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], cell: int) -> np.ndarray:
    """Return a smooth random field of ``shape`` (rows, cols), normalised to max |v| = 1.

    A coarse grid of Gaussian samples (one per ``cell`` pixels) is upsampled with bicubic
    interpolation, giving low-frequency variation without per-pixel Python loops.
    """
    rows, cols = shape
    coarse = rng.standard_normal((rows // cell + 3, cols // cell + 3)).astype(np.float32)
    big = cv2.resize(coarse, ((cols // cell + 3) * cell, (rows // cell + 3) * cell),
                     interpolation=cv2.INTER_CUBIC)
    field = big[cell:cell + rows, cell:cell + cols]
    return field / float(np.abs(field).max())


def _fill(img: np.ndarray, box: Box, colour: Colour,
          noise: np.ndarray | None = None, amplitude: float = 0.0) -> None:
    """Fill the pixel-edge box ``box`` with ``colour`` plus ``amplitude`` x ``noise``."""
    x0, y0, x1, y1 = box
    patch = np.empty((y1 - y0, x1 - x0, 3), np.float32)
    patch[:] = colour
    if noise is not None and amplitude:
        patch += amplitude * noise[y0:y1, x0:x1, None]
    img[y0:y1, x0:x1] = np.clip(np.rint(patch), 0, 255).astype(np.uint8)


def _sub(v: float) -> int:
    """Convert a pixel-centre coordinate to cv2's fixed-point value for ``shift=SHIFT``."""
    return int(round(v * ONE))


def _circle(img: np.ndarray, centre_edge: tuple[float, float], radius: float,
            colour: Colour, thickness: int = -1) -> None:
    """Draw an antialiased circle whose centre is given in pixel-edge coordinates."""
    cx, cy = centre_edge[0] - 0.5, centre_edge[1] - 0.5
    cv2.circle(img, (_sub(cx), _sub(cy)), _sub(radius), colour, thickness,
               cv2.LINE_AA, SHIFT)


def _shade(colour: Colour, delta: int) -> Colour:
    """Return ``colour`` brightened (delta > 0) or darkened (delta < 0), clipped to 0..255."""
    b, g, r = (int(np.clip(c + delta, 0, 255)) for c in colour)
    return (b, g, r)


def _draw_background(img: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Paint wall, baseboard and floor with faint smooth texture; return the noise field."""
    noise = 0.7 * _smooth_noise(rng, (HEIGHT, WIDTH), 96)
    noise += 0.3 * _smooth_noise(rng, (HEIGHT, WIDTH), 16)
    _fill(img, (0, 0, WIDTH, BASEBOARD_TOP), WALL_BGR, noise, 6.0)
    _fill(img, (0, BASEBOARD_TOP, WIDTH, BASEBOARD_TOP + BASEBOARD_HEIGHT),
          BASEBOARD_BGR, noise, 2.0)
    # A thin lighter bevel on top of the baseboard.
    _fill(img, (0, BASEBOARD_TOP, WIDTH, BASEBOARD_TOP + 3), _shade(BASEBOARD_BGR, 18))
    floor_noise = np.roll(noise, 211, axis=1)
    _fill(img, (0, BASEBOARD_TOP + BASEBOARD_HEIGHT, WIDTH, HEIGHT), FLOOR_BGR,
          floor_noise, 5.0)
    return noise


def _draw_door(img: np.ndarray, rng: np.random.Generator, noise: np.ndarray) -> None:
    """Draw the casing, the wooden leaf with faint grain, the peek window and the knob."""
    fx0, fy0, fx1, fy1 = FRAME_OUTER
    lx0, ly0, lx1, ly1 = LEAF
    # Casing: left, right and top members (uniform dark paint, very faint texture).
    for box in ((fx0, fy0, lx0, fy1), (lx1, fy0, fx1, fy1), (lx0, fy0, lx1, ly0)):
        _fill(img, box, CASING_BGR, noise, 2.0)

    # Leaf: wood colour with smooth column streaks, then a few faint grain lines.
    streak = _smooth_noise(rng, (1, lx1 - lx0), 6)
    leaf_noise = 0.6 * streak + 0.4 * noise[ly0:ly1, lx0:lx1]
    patch = np.empty((ly1 - ly0, lx1 - lx0, 3), np.float32)
    patch[:] = LEAF_BGR
    patch += 4.0 * leaf_noise[:, :, None]
    img[ly0:ly1, lx0:lx1] = np.clip(np.rint(patch), 0, 255).astype(np.uint8)
    rows = np.arange(ly0 + 4, ly1 - 4, 8, dtype=np.float64)
    for _ in range(9):
        x = rng.uniform(lx0 + 14, lx1 - 14)
        amp = rng.uniform(0.8, 2.5)
        period = rng.uniform(150.0, 400.0)
        phase = rng.uniform(0.0, 2.0 * np.pi)
        delta = int(rng.choice([-9, -7, 6, 8]))
        xs = x + amp * np.sin(2.0 * np.pi * rows / period + phase)
        pts = np.stack([xs, rows], axis=1)
        pts = np.rint(pts * ONE).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(img, [pts], False, _shade(LEAF_BGR, delta), 1, cv2.LINE_AA, SHIFT)

    _draw_window(img)
    _draw_knob(img)


def _draw_window(img: np.ndarray) -> None:
    """Draw the peek window: a light frame around dark bluish glass with a soft reflection."""
    wx0, wy0, wx1, wy1 = WINDOW
    _fill(img, WINDOW, WINDOW_FRAME_BGR)
    # Thin shadow line on the inner side of the frame (top/left), inside the window box.
    gx0, gy0, gx1, gy1 = wx0 + WINDOW_FRAME, wy0 + WINDOW_FRAME, wx1 - WINDOW_FRAME, \
        wy1 - WINDOW_FRAME
    _fill(img, (gx0 - 1, gy0 - 1, gx1 + 1, gy1 + 1), _shade(WINDOW_FRAME_BGR, -60))
    _fill(img, (gx0, gy0, gx1, gy1), GLASS_BGR)
    # Soft diagonal reflection band, blended into the glass only.
    glass = img[gy0:gy1, gx0:gx1]
    overlay = glass.copy()
    h, w = glass.shape[:2]
    band = np.array([[int(0.25 * w), 0], [int(0.45 * w), 0],
                     [int(0.20 * w), h], [int(0.00 * w), h]], np.int32)
    cv2.fillPoly(overlay, [band], _shade(GLASS_BGR, 45), cv2.LINE_AA)
    img[gy0:gy1, gx0:gx1] = cv2.addWeighted(glass, 0.6, overlay, 0.4, 0.0)


def _draw_knob(img: np.ndarray) -> None:
    """Draw the escutcheon plate, the round knob (with shadow and highlight) and a keyhole."""
    px0, py0, px1, py1 = PLATE
    _fill(img, PLATE, _shade(PLATE_BGR, -55))
    _fill(img, (px0 + 1, py0 + 1, px1 - 1, py1 - 1), PLATE_BGR)
    _fill(img, (px0 + 2, py0 + 2, px0 + 4, py1 - 2), _shade(PLATE_BGR, 25))  # bevel
    centre = (float(PLATE_CX), float(PLATE_CY))
    _circle(img, (centre[0] + 1.5, centre[1] + 2.0), KNOB_RADIUS, _shade(PLATE_BGR, -70))
    _circle(img, centre, KNOB_RADIUS, _shade(KNOB_BGR, -70))
    _circle(img, centre, KNOB_RADIUS - 1.5, KNOB_BGR)
    _circle(img, (centre[0] - 3.0, centre[1] - 3.5), 3.5, _shade(KNOB_BGR, 45))
    # Keyhole below the knob.
    kx, ky = float(PLATE_CX), float(PLATE_CY + 24)
    _circle(img, (kx, ky), 2.5, (25, 25, 25))
    _fill(img, (PLATE_CX - 1, PLATE_CY + 24, PLATE_CX + 1, PLATE_CY + 31), (25, 25, 25))


def _draw_switch(img: np.ndarray) -> None:
    """Draw the light-switch plate with two rocker switches side by side."""
    sx0, sy0, sx1, sy1 = SWITCH
    _fill(img, (sx0 + 2, sy0 + 2, sx1 + 2, sy1 + 2), _shade(WALL_BGR, -45))  # drop shadow
    _fill(img, SWITCH, _shade(SWITCH_BGR, -40))
    _fill(img, (sx0 + 1, sy0 + 1, sx1 - 1, sy1 - 1), SWITCH_BGR)
    rocker_w, rocker_h = 14, 36
    for cx in (SWITCH_CX - 9, SWITCH_CX + 9):
        rx0, ry0 = cx - rocker_w // 2, SWITCH_CY - rocker_h // 2
        rx1, ry1 = rx0 + rocker_w, ry0 + rocker_h
        _fill(img, (rx0 - 1, ry0 - 1, rx1 + 1, ry1 + 1), _shade(SWITCH_BGR, -75))
        _fill(img, (rx0, ry0, rx1, ry0 + rocker_h // 2), _shade(SWITCH_BGR, 5))
        _fill(img, (rx0, ry0 + rocker_h // 2, rx1, ry1), _shade(SWITCH_BGR, -28))
    # Two small screws above and below the rockers.
    for dy in (-30, 30):
        _circle(img, (float(SWITCH_CX), float(SWITCH_CY + dy)), 2.5, _shade(SWITCH_BGR, -90))


def _draw_sign(img: np.ndarray) -> None:
    """Draw the room sign: dark border, light face and centred antialiased Hershey text."""
    gx0, gy0, gx1, gy1 = SIGN
    _fill(img, (gx0 + 2, gy0 + 2, gx1 + 2, gy1 + 2), _shade(WALL_BGR, -45))  # drop shadow
    _fill(img, SIGN, SIGN_BORDER_BGR)
    _fill(img, (gx0 + 4, gy0 + 4, gx1 - 4, gy1 - 4), SIGN_FACE_BGR)
    _fill(img, (gx0 + 7, gy0 + 7, gx1 - 7, gy1 - 7), _shade(SIGN_FACE_BGR, -70))  # inner line
    _fill(img, (gx0 + 8, gy0 + 8, gx1 - 8, gy1 - 8), SIGN_FACE_BGR)
    font = cv2.FONT_HERSHEY_DUPLEX
    thickness = 2
    (tw1, _), _ = cv2.getTextSize(SIGN_TEXT, font, 1.0, thickness)
    scale = round(150.0 / tw1, 3)
    (tw, th), _ = cv2.getTextSize(SIGN_TEXT, font, scale, thickness)
    org = (SIGN_CX - tw // 2, SIGN_CY + th // 2)
    cv2.putText(img, SIGN_TEXT, org, font, scale, TEXT_BGR, thickness, cv2.LINE_AA)


def _centre(box: Box) -> list[float]:
    """Return the centre of a pixel-edge box as [col, row] floats."""
    return [(box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0]


def _truth() -> dict:
    """Return the ground-truth feature positions (the JSON content)."""
    return {
        "width": WIDTH,
        "height": HEIGHT,
        "centre": [(WIDTH - 1) / 2.0, (HEIGHT - 1) / 2.0],
        "door": {
            "leaf": list(LEAF),
            "frame_outer": list(FRAME_OUTER),
            "vertical_boundaries": [FRAME_OUTER[0], LEAF[0], LEAF[2], FRAME_OUTER[2]],
        },
        "knob": {"centre": _centre(PLATE), "box": list(KNOB_BOX)},
        "window": {"centre": _centre(WINDOW), "box": list(WINDOW_BOX)},
        "switch": {"centre": _centre(SWITCH), "size": [SWITCH_W, SWITCH_H]},
        "sign": {"centre": _centre(SIGN), "size": [SIGN_W, SIGN_H], "text": SIGN_TEXT},
        "baseboard_top": BASEBOARD_TOP,
        "mm_per_px": MM_PER_PX,
        "convention": (
            "Image axes: x = column (rightwards), y = row (downwards), row 0 at the top. "
            "All feature positions (door, knob, window, switch, sign, baseboard_top) are "
            "pixel-edge coordinates: pixel (c, r) spans [c, c+1) x [r, r+1), so a box "
            "[x0, y0, x1, y1] covers columns x0..x1-1 and rows y0..y1-1 (x1, y1 exclusive) "
            "and an edge value is the boundary between two pixel columns/rows. Subtract 0.5 "
            "to get pixel-centre (array index) coordinates. Exception: 'centre' is the "
            "texture's centre pixel in pixel-centre coordinates, ((W-1)/2, (H-1)/2), "
            "i.e. the point (W/2, H/2) in pixel-edge coordinates. "
            "'box' (knob, window) is a [w, h] box centred on 'centre' that contains the "
            "whole feature; 'size' (switch, sign) is the exact plate size [w, h]."
        ),
    }


def draw_corridor_wall() -> tuple[np.ndarray, dict]:
    """Draw the corridor-wall texture.

    Returns:
        The HEIGHT x WIDTH 8-bit BGR image and the ground-truth dict written to
        ``corridor_wall.json``.
    """
    rng = np.random.default_rng(SEED)
    img = np.zeros((HEIGHT, WIDTH, 3), np.uint8)
    noise = _draw_background(img, rng)
    _draw_door(img, rng, noise)
    _draw_switch(img)
    _draw_sign(img)
    return img, _truth()


def main() -> None:
    """Draw the texture and write ``corridor_wall.png`` and ``corridor_wall.json``."""
    img, truth = draw_corridor_wall()
    if not cv2.imwrite(str(PNG_PATH), img, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        raise OSError(f"could not write {PNG_PATH}")
    JSON_PATH.write_text(json.dumps(truth, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {PNG_PATH} ({PNG_PATH.stat().st_size} bytes) and {JSON_PATH}")


if __name__ == "__main__":
    main()
