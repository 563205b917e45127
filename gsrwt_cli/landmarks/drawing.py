"""Pictures of what was found: lines and matches drawn in red on an 8-bit BGR frontal view."""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

from .ght import Match, Template
from .hough import Line

#: The colour (BGR) and thickness (pixels) of what is drawn.
RED = (0, 0, 255)
THICKNESS = 2


def draw_lines(picture: np.ndarray, lines: Iterable[Line]) -> None:
    """Draw each line's segment, end points rounded to the nearest pixel, into ``picture``."""
    for line in lines:
        ends = np.round([[line.x1, line.y1], [line.x2, line.y2]]).astype(int)
        cv2.line(picture, tuple(ends[0]), tuple(ends[1]), RED, THICKNESS, cv2.LINE_AA)


def draw_matches(picture: np.ndarray, template: Template, matches: Iterable[Match]) -> None:
    """Draw the template's box, at each match's place and scale, into ``picture``."""
    for match in matches:
        half = np.array([template.width, template.height]) * match.scale / 2
        corner0 = np.round([match.x, match.y] - half).astype(int)
        corner1 = np.round([match.x, match.y] + half).astype(int)
        cv2.rectangle(picture, tuple(corner0), tuple(corner1), RED, THICKNESS)
