"""Landmarks on frontal wall images: Sobel edges, one-vote Hough lines, GHT door parts.

Synthetic images only, drawn with OpenCV: shapes are rendered 8x finer and averaged down
(exact area coverage), so the true sub-pixel geometry of every edge is known.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli.vision.edges import line_edges
from gsrwt_cli.vision.landmarks import build_template, edge_map, hough_lines, match_template
from tests.helpers.images import smooth_texture

#: Model bounding boxes of the thesis, read as ``(width, height)`` in pixels (Sec. 5.2.2: "40x100"
#: for the door knob, "120x90" for the peek window).
DOOR_KNOB_BOX = (40, 100)
PEEK_WINDOW_BOX = (120, 90)
SUPERSAMPLING = 8
SCALES = (0.9, 0.95, 1.0, 1.05, 1.1)


# --------------------------------------------------------------------------------------------
# Drawing
# --------------------------------------------------------------------------------------------


def segment_length(line) -> float:
    """Length of the segment that supports a line, pixels."""
    return math.hypot(line.x2 - line.x1, line.y2 - line.y1)


def paint(image: np.ndarray, shapes: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """``image`` with filled polygons ``(points (N, 2) as (x, y), grey)`` painted in order.

    Pixel ``(col, row)`` covers ``[col - 0.5, col + 0.5] x [row - 0.5, row + 0.5]``; each gets
    the area-weighted mix of the shapes and the background it shows.
    """
    image = np.asarray(image, np.float32)
    height, width = image.shape
    factor = SUPERSAMPLING
    colour = np.zeros((height * factor, width * factor), np.float32)
    cover = np.zeros_like(colour)
    for points, grey in shapes:
        fine = (np.asarray(points, float) + 0.5) * factor - 0.5  # fine-pixel coordinates
        inside = np.zeros(colour.shape, np.uint8)
        cv2.fillPoly(inside, [np.round(fine * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
        colour[inside == 1] = grey
        cover[inside == 1] = 1.0
    colour = cv2.resize(colour * cover, (width, height), interpolation=cv2.INTER_AREA)
    cover = cv2.resize(cover, (width, height), interpolation=cv2.INTER_AREA)
    return np.clip(np.rint(image * (1.0 - cover) + colour), 0, 255).astype(np.uint8)


def rectangle(half_width: float, half_height: float, cx: float = 0.0, cy: float = 0.0):
    return np.array([[cx - half_width, cy - half_height], [cx + half_width, cy - half_height],
                     [cx + half_width, cy + half_height], [cx - half_width, cy + half_height]])


def circle(radius: float, cx: float = 0.0, cy: float = 0.0, points: int = 96):
    angle = np.linspace(0, 2 * np.pi, points, endpoint=False)
    return np.column_stack([cx + radius * np.cos(angle), cy + radius * np.sin(angle)])


def rounded_rectangle(half_width: float, half_height: float, radius: float):
    corners = [(half_width - radius, half_height - radius, 0), (radius - half_width,
               half_height - radius, 90), (radius - half_width, radius - half_height, 180),
               (half_width - radius, radius - half_height, 270)]
    arcs = []
    for cx, cy, start in corners:
        angle = np.radians(np.linspace(start, start + 90, 16))
        arcs.append(np.column_stack([cx + radius * np.cos(angle), cy + radius * np.sin(angle)]))
    return np.concatenate(arcs)


#: A door knob on its plate, fits DOOR_KNOB_BOX (40x100) centred on the origin.
KNOB = [(rounded_rectangle(14, 44, 8), 70), (circle(9, 0, -12), 215), (rectangle(3, 6, 0, 20), 15)]

#: A peek window: frame, glass, a transom bar; fits PEEK_WINDOW_BOX (120x90).
WINDOW = [(rectangle(56, 41), 45), (rectangle(47, 32), 225), (rectangle(47, 2.5, 0, -12), 45)]


def place(shapes, x: float, y: float, scale: float = 1.0):
    """The shapes scaled about their origin, then centred on ``(x, y)``."""
    return [(scale * points + (x, y), grey) for points, grey in shapes]


def wall(seed: int, height: int = 480, width: int = 640) -> np.ndarray:
    """A softly textured grey wall: some texture pixels pass the edge threshold."""
    texture = smooth_texture(height, width, seed, channels=1).astype(np.float32)
    return np.clip(140 + 0.3 * (texture - 128), 0, 255).astype(np.uint8)


def cut_out(image: np.ndarray, x: float, y: float, box: tuple[int, int]) -> np.ndarray:
    """The ``box = (width, height)`` of ``image`` centred on ``(x, y)`` (must fit exactly)."""
    width, height = box
    left, top = x - (width - 1) / 2, y - (height - 1) / 2
    assert left == int(left) and top == int(top)
    return image[int(top):int(top) + height, int(left):int(left) + width].copy()


def angle_between_deg(a, b, period: float = 360.0):
    """Smallest difference between angles (degrees), for numbers or arrays."""
    return abs((a - b + period / 2) % period - period / 2)


# --------------------------------------------------------------------------------------------
# Edges
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("dark", "expected_deg"),
    [("left", 0.0), ("top", 90.0), ("right", 180.0), ("bottom", 270.0)],
)
def test_gradient_orientation_points_from_dark_to_light(dark, expected_deg):
    image = np.full((40, 50), 180, np.uint8)
    dark_half = {"left": np.s_[:, :25], "top": np.s_[:20, :], "right": np.s_[:, 25:],
                 "bottom": np.s_[20:, :]}[dark]
    image[dark_half] = 80
    edges = edge_map(image)
    assert edges.magnitude.dtype == np.float32 and edges.orientation_deg.dtype == np.float32
    # A 100-level step under the raw 3x3 Sobel mask: 1 + 2 + 1 times 100.
    assert edges.magnitude.max() == pytest.approx(400.0)
    # Two columns (rows) of edge pixels, along the 38 (48) rows (columns) off the border.
    assert edges.mask.sum() == 2 * (38 if dark in ("left", "right") else 48)
    orientations = edges.orientation_deg[edges.mask]
    assert np.all((orientations >= 0) & (orientations < 360))
    assert np.all(angle_between_deg(orientations, expected_deg) < 1e-3)


def test_edge_threshold_and_border():
    image = np.full((30, 30), 100, np.uint8)
    image[:, 15:] = 119  # a 19-level step: Sobel magnitude 76, below the thesis's 80
    assert not edge_map(image).mask.any()
    image[:, 15:] = 120  # exactly 80: an edge
    assert edge_map(image).mask.sum() == 2 * 28
    image = np.full((30, 30), 100, np.uint8)
    image[0, :] = 255  # a bright first row: strong gradient only along the border
    edges = edge_map(image)
    assert edges.magnitude[1].max() > 80 and not edges.mask[0].any()
    assert edges.mask[1].any()  # row 1 is inside: its 3x3 mask sees row 0


def test_colour_images_are_converted_to_grey():
    grey = wall(3, 120, 160)
    colour = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    np.testing.assert_array_equal(edge_map(colour).mask, edge_map(grey).mask)
    with pytest.raises(TypeError):
        edge_map(grey.astype(np.float32))


# --------------------------------------------------------------------------------------------
# Hough lines
# --------------------------------------------------------------------------------------------


def test_dark_bar_gives_two_vertical_lines_at_its_pixel_edges():
    image = np.full((200, 300), 200, np.uint8)
    image[:, 100:160] = 50  # columns 100..159: edges at x = 99.5 and x = 159.5
    lines = hough_lines(image)
    assert len(lines) == 2
    by_side = sorted(lines, key=lambda line: abs(line.rho))
    left, right = by_side
    # Left edge: light on the left, so the gradient points left (180 deg), rho = -x.
    assert angle_between_deg(left.theta_deg, 180.0) < 0.5
    assert abs(left.rho - (-99.5)) < 0.5
    assert angle_between_deg(right.theta_deg, 0.0) < 0.5
    assert abs(right.rho - 159.5) < 0.5
    for line, x in ((left, 99.5), (right, 159.5)):
        assert line.votes >= 50
        assert abs(line.x1 - x) < 0.5 and abs(line.x2 - x) < 0.5
        assert sorted([line.y1, line.y2]) == pytest.approx([1.0, 198.0], abs=1.0)
        assert segment_length(line) == pytest.approx(197.0, abs=2.0)


@pytest.mark.parametrize("edge_x", [100.3, 100.5, 100.8])
def test_sub_pixel_edge_position(edge_x):
    # Light left of edge_x, dark right of it; its pixel column is part-dark. The thresholded
    # edge is three pixels wide and lopsided: the magnitude-weighted fit finds the edge.
    image = paint(np.full((120, 200), 190), [(rectangle(200, 200, edge_x + 200, 60), 40)])
    (line,) = hough_lines(image)
    assert angle_between_deg(line.theta_deg, 180.0) < 0.1
    assert line.rho == pytest.approx(-edge_x, abs=0.1)


def test_lines_come_strongest_first_and_max_lines_keeps_the_strongest():
    image = np.full((240, 320), 60, np.uint8)
    image[20:220, 40:60] = 220  # a 200-px and a 150-px tall bar
    image[60:210, 200:230] = 220
    lines = hough_lines(image, min_votes=40)
    votes = [line.votes for line in lines]
    assert votes == sorted(votes, reverse=True)
    assert len(lines) >= 4
    strongest = hough_lines(image, min_votes=40, max_lines=2)
    assert [(line.rho, line.theta_deg) for line in strongest] == [
        (line.rho, line.theta_deg) for line in lines[:2]]
    assert sorted(abs(line.rho) for line in strongest) == pytest.approx([39.5, 59.5], abs=0.5)


def test_oblique_edge_at_30_degrees():
    direction = np.array([math.cos(math.radians(30)), math.sin(math.radians(30))])
    normal = np.array([-direction[1], direction[0]])  # 120 deg; the dark side
    point = np.array([121.3, 97.8])
    far = 1000.0
    half_plane = np.array([point - far * direction, point + far * direction,
                           point + far * direction + far * normal,
                           point - far * direction + far * normal])
    image = paint(np.full((200, 240), 190, np.float32), [(half_plane, 40)])
    lines = hough_lines(image)
    assert len(lines) == 1
    line = lines[0]
    # Light to dark along `normal`: the gradient points the other way, 300 deg.
    assert angle_between_deg(line.theta_deg, 300.0) < 1.0
    assert line.rho == pytest.approx(-float(point @ normal), abs=0.5)
    assert segment_length(line) > 200  # the edge crosses the whole image (~ 277 px)


def test_near_vertical_edge_is_one_line_across_the_0_360_seam():
    # Normal at 359 deg: its pixels vote in the bins of 358 and 0 deg, which are neighbours.
    normal_deg = 359.0
    normal = np.array([math.cos(math.radians(normal_deg)), math.sin(math.radians(normal_deg))])
    direction = np.array([-normal[1], normal[0]])
    point = np.array([80.4, 60.0])
    far = 1000.0
    dark_side = np.array([point - far * direction, point + far * direction,
                          point + far * direction - far * normal,
                          point - far * direction - far * normal])
    image = paint(np.full((120, 160), 200), [(dark_side, 50)])
    lines = hough_lines(image, min_votes=15)  # low: the 358-deg bin holds a peak of its own
    assert len(lines) == 1
    assert angle_between_deg(lines[0].theta_deg, normal_deg) < 0.5
    assert lines[0].rho == pytest.approx(float(point @ normal), abs=0.3)


def test_flat_and_gently_shaded_images_have_no_lines():
    assert hough_lines(np.full((120, 160), 128, np.uint8)) == []
    ramp = np.tile(np.linspace(0, 150, 160), (120, 1)).astype(np.uint8)  # ~1 level per px
    assert hough_lines(ramp) == []


def test_short_edges_stay_below_min_votes_and_min_length():
    image = np.full((120, 160), 200, np.uint8)
    image[40:70, 60:90] = 40  # a 30x30 square: each edge cell collects fewer than 30 votes
    assert hough_lines(image, min_votes=50, min_length=0) == []  # the thesis's 50 votes
    assert hough_lines(image) == []  # each side is 29 px from first to last pixel
    sides = hough_lines(image, min_votes=15, min_length=15)
    assert len(sides) == 4
    for line in sides:  # from the first to the last pixel row (column) of the square
        assert line.length == pytest.approx(29.0, abs=0.5) and line.votes >= 15
        assert sorted([line.y1, line.y2] if abs(line.x1 - line.x2) < 1 else
                      [line.x1, line.x2]) == pytest.approx([40, 69] if abs(line.x1 - line.x2)
                                                           < 1 else [60, 89], abs=0.5)


def test_a_line_is_cut_where_its_edge_has_a_gap():
    image = np.full((300, 200), 200, np.uint8)
    image[20:120, 80:] = 60  # x = 79.5, rows 20..119 and 150..279: a 30-row gap between
    image[150:280, 80:] = 60
    pieces = sorted((line for line in hough_lines(image, orientation="vertical")),
                    key=lambda line: min(line.y1, line.y2))
    assert len(pieces) == 2
    for line, (top, bottom) in zip(pieces, ((20, 119), (150, 279))):
        assert line.rho == pytest.approx(-79.5, abs=0.1)
        ends = sorted([line.y1, line.y2])
        # The ends are the first and last pixel rows of the edge.
        assert ends == pytest.approx([top, bottom], abs=0.5)
        assert line.length == pytest.approx(ends[1] - ends[0])
        assert line.contrast > 200  # a 140-level step: well over the threshold
    (whole,) = hough_lines(image, orientation="vertical", max_gap=40)
    assert sorted([whole.y1, whole.y2]) == pytest.approx(
        [min(pieces[0].y1, pieces[0].y2), max(pieces[1].y1, pieces[1].y2)], abs=0.5)
    (longer,) = hough_lines(image, orientation="vertical", min_length=110)
    assert longer.length == pytest.approx(pieces[1].length, abs=0.5)


def test_orientation_filters():
    image = np.full((200, 240), 200, np.uint8)
    image[40:160, 60:180] = 60  # a square: two vertical and two horizontal sides
    every = hough_lines(image)
    vertical = hough_lines(image, orientation="vertical")
    horizontal = hough_lines(image, orientation="horizontal")
    assert len(every) == 4 and len(vertical) == 2 and len(horizontal) == 2
    assert {round(abs(line.rho), 1) for line in vertical} == {59.5, 179.5}
    assert {round(abs(line.rho), 1) for line in horizontal} == {39.5, 159.5}
    with pytest.raises(ValueError):
        hough_lines(image, orientation="diagonal")


def test_hysteresis_keeps_the_faint_part_of_a_strong_edge_only():
    # An edge fading from a 40-level step (top) to a 6-level one (bottom), as a door frame
    # in falling light, and beside it an isolated 6-level step.
    step = np.linspace(40, 6, 240)[:, None]
    image = np.full((240, 220), 150.0)
    image[:, 60:] -= step
    image[:, 150:] -= 6
    grey = np.rint(image).astype(np.uint8)
    edges = line_edges(grey)
    assert edges.magnitude[230, 55:65].max() < 25  # the faint end alone is under threshold
    assert edges.mask[3:237, 58:62].any(axis=1).all()  # but kept: the same edge is strong
    assert not edges.mask[:, 140:160].any()  # the isolated faint edge is not
    (line,) = hough_lines(grey, orientation="vertical")
    assert abs(line.rho) == pytest.approx(59.5, abs=0.2) and line.length > 225


def test_magnification_lifts_a_stretched_edge_over_the_threshold():
    image = np.full((200, 200), 150, np.uint8)
    image[:, 100:] = 144  # a 6-level step: under the threshold unmagnified
    assert not line_edges(image).mask.any()
    stretched = line_edges(image, magnification=np.full(image.shape, 2.5, np.float32))
    assert stretched.mask[5:195, 98:102].any(axis=1).all()
    assert hough_lines(image, edges=stretched)


def test_no_edges_at_the_border_of_the_fill():
    image = np.full((200, 200), 180, np.uint8)
    valid = np.ones(image.shape, bool)
    valid[:, :50] = False
    image[~valid] = 0  # the fill
    image[:, 120:] = 90  # a real edge at x = 119.5
    edges = line_edges(image, valid=valid)
    assert not edges.mask[:, :53].any() and not edges.support[:, :53].any()
    (line,) = hough_lines(image, edges=edges)
    assert abs(line.rho) == pytest.approx(119.5, abs=0.1)
    assert len(hough_lines(image)) == 2  # without the mask the fill's border is a line


def test_empty_images_give_no_lines():
    assert hough_lines(np.zeros((0, 0), np.uint8)) == []
    assert hough_lines(np.zeros((0, 5, 3), np.uint8)) == []
    assert hough_lines(np.zeros((2, 2), np.uint8)) == []
    edges = edge_map(np.zeros((0, 7), np.uint8))
    assert edges.mask.shape == (0, 7) and edges.magnitude.shape == (0, 7)


def test_orientation_step_must_divide_a_full_turn():
    with pytest.raises(ValueError):
        hough_lines(np.zeros((10, 10), np.uint8), theta_step_deg=7.0)


# --------------------------------------------------------------------------------------------
# Generalized Hough Transform
# --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def knob_template():
    image = paint(wall(1), place(KNOB, 200.5, 180.5))
    return build_template(cut_out(image, 200.5, 180.5, DOOR_KNOB_BOX))


@pytest.fixture(scope="module")
def window_template():
    image = paint(wall(1), place(WINDOW, 300.5, 200.5))
    return build_template(cut_out(image, 300.5, 200.5, PEEK_WINDOW_BOX))


def test_template_holds_the_model_edge_pixels(knob_template):
    template = knob_template
    assert (template.width, template.height) == DOOR_KNOB_BOX
    assert template.edge_count == len(template.offsets) > 300
    assert np.all(np.diff(template.orientation_bins) >= 0)
    assert template.bin_count == 90  # 4-degree bins
    # Offsets point from model pixels to the box centre (19.5, 49.5): inside the box.
    assert np.all(np.abs(template.offsets[:, 0]) <= 19.5)
    assert np.all(np.abs(template.offsets[:, 1]) <= 49.5)
    # The R-table's rows (entries of one orientation bin each) hold every entry once.
    assert template.bin_starts[0] == 0 and template.bin_starts[-1] == template.edge_count
    assert np.all(np.diff(template.bin_starts) >= 0)


def test_knob_found_where_it_was_moved(knob_template):
    x, y = 421.3, 287.6
    image = paint(wall(2), place(KNOB, x, y))
    matches = match_template(image, knob_template)
    best = matches[0]
    assert best.scale == 1.0
    assert math.hypot(best.x - x, best.y - y) < 1.0
    assert best.score > 0.8 and best.votes == round(best.score * knob_template.edge_count)
    assert all(0.0 <= match.score <= 1.0 for match in matches)
    scores = [match.score for match in matches]
    assert scores == sorted(scores, reverse=True) and scores[1] < 0.5 * best.score
    assert len(matches) <= 5


def test_window_found_at_scale_1_05(window_template):
    x, y = 413.7, 262.2
    image = paint(wall(4), place(WINDOW, x, y, scale=1.05))
    best = match_template(image, window_template, scales=SCALES)[0]
    assert abs(best.scale - 1.05) <= 0.05 + 1e-9  # within one scale step
    assert math.hypot(best.x - x, best.y - y) < 2.0
    assert best.score > 0.8


@pytest.mark.parametrize("template_name", ["knob_template", "window_template"])
def test_whole_pixel_moves_are_found_to_a_fraction_of_a_pixel(template_name, request):
    # Both boxes have even sides: the reference point sits between pixels, and the votes of a
    # copy moved by whole pixels land on both sides of it.
    template = request.getfixturevalue(template_name)
    shapes, (x, y) = (KNOB, (200.5, 180.5)) if "knob" in template_name else (WINDOW, (300.5, 200.5))
    x, y = x + 137, y + 58
    best = match_template(paint(wall(7), place(shapes, x, y)), template)[0]
    assert best.scale == 1.0
    assert math.hypot(best.x - x, best.y - y) < 0.1


def test_exact_orientation_bins_also_find_the_knob(knob_template):
    x, y = 421.3, 287.6
    image = paint(wall(2), place(KNOB, x, y))
    best = match_template(image, knob_template, orientation_tolerance_bins=0)[0]
    assert best.scale == 1.0 and math.hypot(best.x - x, best.y - y) < 1.0
    assert best.score > 0.8  # the score does not depend on the voting tolerance


def test_matches_are_distinct_places(window_template):
    image = paint(wall(5),
                  place(WINDOW, 150.5, 120.5) + place(WINDOW, 470.5, 340.5))
    matches = match_template(image, window_template, max_matches=5, min_score=0.3)
    assert len(matches) >= 2
    for x, y in ((150.5, 120.5), (470.5, 340.5)):
        assert min(math.hypot(m.x - x, m.y - y) for m in matches[:2]) < 1.0
    smaller_side = min(PEEK_WINDOW_BOX)
    for i, a in enumerate(matches):
        for b in matches[i + 1:]:
            assert math.hypot(a.x - b.x, a.y - b.y) >= smaller_side / 2 - 2


@pytest.mark.parametrize("template_name", ["knob_template", "window_template"])
def test_no_match_above_half_when_the_object_is_absent(template_name, request):
    template = request.getfixturevalue(template_name)
    image = paint(wall(6), place(WINDOW if "knob" in template_name else KNOB,
                                                    320.5, 240.5))  # the other part only
    assert match_template(image, template, min_score=0.5) == []
    assert match_template(image, template)  # without the threshold there is always a best


def test_colour_image_matches_like_grey(knob_template):
    image = paint(wall(2), place(KNOB, 250.0, 240.0))
    grey_best = match_template(image, knob_template)[0]
    colour_best = match_template(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR), knob_template)[0]
    assert colour_best == grey_best


def test_no_edges_no_matches(knob_template):
    assert match_template(np.full((480, 640), 140, np.uint8), knob_template) == []
    assert match_template(np.zeros((0, 0), np.uint8), knob_template) == []
    assert match_template(wall(2), knob_template, scales=()) == []
    with pytest.raises(ValueError):
        build_template(np.full((100, 40), 140, np.uint8))
