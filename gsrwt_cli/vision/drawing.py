"""Pictures of what was found, drawn on an 8-bit BGR frontal view: segments in red (vertical),
blue (horizontal) or green (others), each with a dot at its ends; matches as red boxes."""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

from .ght import Match, Template
from .hough import Line, orientation_allows

#: The colours (BGR) and thickness (pixels) of what is drawn.
RED = (0, 0, 255)
BLUE = (255, 64, 0)
GREEN = (0, 200, 0)
THICKNESS = 2


def line_colour(line: Line) -> tuple[int, int, int]:
    """Red for a vertical segment, blue for a horizontal one, green for the others."""
    if orientation_allows(line.theta_deg, "vertical"):
        return RED
    return BLUE if orientation_allows(line.theta_deg, "horizontal") else GREEN


def draw_lines(picture: np.ndarray, lines: Iterable[Line]) -> None:
    """Draw each segment (end points to 1/16 pixel) and a dot at each of its ends."""
    for line in lines:
        ends = np.round(np.array([[line.x1, line.y1], [line.x2, line.y2]]) * 16).astype(int)
        colour = line_colour(line)
        cv2.line(picture, tuple(ends[0]), tuple(ends[1]), colour, THICKNESS, cv2.LINE_AA, 4)
        for end in ends:
            cv2.circle(picture, tuple(end), 3 * 16, colour, -1, cv2.LINE_AA, 4)


def draw_matches(picture: np.ndarray, template: Template, matches: Iterable[Match]) -> None:
    """Draw the template's box, at each match's place and scale, into ``picture``."""
    for match in matches:
        half = np.array([template.width, template.height]) * match.scale / 2
        corner0 = np.round([match.x, match.y] - half).astype(int)
        corner1 = np.round([match.x, match.y] + half).astype(int)
        cv2.rectangle(picture, tuple(corner0), tuple(corner1), RED, THICKNESS)
