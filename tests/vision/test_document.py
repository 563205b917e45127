"""``--auto document`` (:mod:`gsrwt_cli.vision.document`): pages rendered through OpenCV's
own camera (``cv2.projectPoints``) onto real photos are found to a fraction of a pixel, and
photos with no document, a page the frame cuts, or two pages alike are refused, saying why."""

from __future__ import annotations

import csv

import cv2
import numpy as np
import pytest

from gsrwt_cli.vision.document import DocumentError, find_document, ordered_corners
from tests.helpers.pages import REAL, render_page
from tests.helpers.rectangles import random_shots, rectangle_shot

SHOTS = random_shots(12, seed=11, min_angle=5.0, sizes=(0.45, 0.8))


def test_pages_on_a_real_photo_are_found_to_a_fraction_of_a_pixel():
    """Twelve pages at random poses on gravel (edges everywhere, up to the page's border):
    every one found, its corners within a pixel, half of them within 0.3 px."""
    errors = [np.abs(find_document(render_page(shot, "gravel.jpg")).corners
                     - shot.corners).max() for shot in SHOTS]
    assert max(errors) < 1.0
    assert np.median(errors) < 0.3


def test_the_page_is_found_on_a_cluttered_photo_of_a_wall_too():
    shot = rectangle_shot(-22.0, 12.0, -4.0, 1000.0, 210 / 297, size=0.7)
    found = find_document(render_page(shot, "home.jpg"))
    assert np.abs(found.corners - shot.corners).max() < 0.5
    assert found.support > 0.9


def test_photos_with_no_document_are_refused():
    """Every photo of tests/data/real that shows no straight man-made structure at all."""
    with open(REAL / "photos.csv", newline="") as handle:
        names = [row["image"] for row in csv.DictReader(handle) if row["structure"] == "none"]
    assert len(names) >= 12
    for name in names:
        with pytest.raises(DocumentError):
            find_document(cv2.imread(str(REAL / name), cv2.IMREAD_COLOR))


def test_a_page_the_frame_cuts_is_refused():
    shot = rectangle_shot(15.0, 10.0, 0.0, 900.0, 0.75, size=0.8, offset=(0.0, 0.55))
    assert shot.corners[:, 0].max() > shot.width - 1  # the right side runs off the image
    with pytest.raises(DocumentError, match="runs along the image's border"):
        find_document(render_page(shot))


def test_two_pages_alike_are_refused():
    left = rectangle_shot(0.0, 15.0, 0.0, 1200.0, 0.7, size=0.6, offset=(0.0, -0.42))
    right = rectangle_shot(0.0, 15.0, 0.0, 1200.0, 0.7, size=0.6, offset=(0.0, 0.42))
    with pytest.raises(DocumentError, match="no clear document: two quadrilaterals"):
        find_document(render_page(left, extra=right))


def test_a_smaller_page_beside_the_document_does_not_count():
    big = rectangle_shot(0.0, 15.0, 0.0, 1200.0, 0.7, size=0.75, offset=(0.0, -0.3))
    small = rectangle_shot(0.0, 15.0, 0.0, 1200.0, 0.7, size=0.3, offset=(0.0, 1.15))
    found = find_document(render_page(big, extra=small))
    assert np.abs(found.corners - big.corners).max() < 1.0


@pytest.mark.parametrize("turn", range(4))
@pytest.mark.parametrize("mirrored", [False, True])
def test_corners_come_clockwise_from_the_top_left_whatever_their_order(turn, mirrored):
    corners = rectangle_shot(20.0, -10.0, 25.0, 900.0, 1.4).corners
    given = np.roll(corners, turn, axis=0)
    if mirrored:
        given = given[::-1]
    assert np.array_equal(ordered_corners(given), corners)
