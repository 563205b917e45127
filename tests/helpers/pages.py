"""Printed pages on real photos, rendered through OpenCV's own camera (the rectangles of
:mod:`tests.helpers.rectangles`): what ``--auto document`` must find."""

from __future__ import annotations

import cv2
import numpy as np

from tests.helpers.paths import ROOT
from tests.helpers.rectangles import RectangleShot

#: Real photos of other kinds (tests/data/real/README.md), the backgrounds.
REAL = ROOT / "tests" / "data" / "real"


def page_texture(aspect: float, height: int = 600) -> np.ndarray:
    """A printed page: off-white paper, lines of dark text, a margin."""
    width = int(round(aspect * height))
    page = np.full((height, width, 3), (236, 240, 242), np.uint8)
    rng = np.random.default_rng(3)
    for row in range(60, height - 40, 34):
        words = "".join(rng.choice(list("abcdefghij klmnopqrstuvwxyz")) for _ in range(60))
        cv2.putText(page, words, (40, row), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (40, 40, 40), 2,
                    cv2.LINE_AA)
    return page


def background(name: str, width: int, height: int) -> np.ndarray:
    photo = cv2.imread(str(REAL / name), cv2.IMREAD_COLOR)
    return cv2.resize(photo, (width, height), interpolation=cv2.INTER_CUBIC)


def render_page(shot: RectangleShot, backdrop: str = "gravel.jpg",
                extra: RectangleShot | None = None) -> np.ndarray:
    """The page (and ``extra``, a second one) on a real photo: the page's outer border (its
    texture's pixel edges, at -0.5 and size - 0.5) goes to the projected corners."""
    image = background(backdrop, shot.width, shot.height).astype(np.float32)
    for one in (shot, extra) if extra is not None else (shot,):
        texture = page_texture(one.aspect)
        th, tw = texture.shape[:2]
        source = np.float32([[-0.5, -0.5], [tw - 0.5, -0.5], [tw - 0.5, th - 0.5],
                             [-0.5, th - 0.5]])
        homography = cv2.getPerspectiveTransform(source, one.corners.astype(np.float32))
        size = (one.width, one.height)
        page = cv2.warpPerspective(texture.astype(np.float32), homography, size,
                                   flags=cv2.INTER_LINEAR)
        cover = cv2.warpPerspective(np.ones((th, tw), np.float32), homography, size,
                                    flags=cv2.INTER_LINEAR)[..., None]
        # The warp blends the page with black beyond its border as it blends the cover
        # with 0: the page comes premultiplied by its cover.
        image = image * (1 - cover) + page.astype(np.float32)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)
