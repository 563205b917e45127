"""Issue 15: door edges found as segments on real photos, in real subprocess runs of gsrwt.

Labelled sets (``chessboard_edges``, ``door_renders``): OpenCV's 13 chessboard photos
rectified with their solvePnP poses, every square's sides known from the corners OpenCV finds
in the raw photo; the same photos at 15 % contrast with noise and JPEG; rendered doors (a
white frame on a white wall among them) at pans up to 40 degrees through blur, noise and
JPEG. The goals are issue 15's (recall of long vertical edges >= 0.75, precision >= 0.55 for
vertical and >= 0.45 for all lines); the tighter bounds are a little under what was measured
(``benchmarks/bench_landmarks.py``), so that a regression fails.
"""

from __future__ import annotations

from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from gsrwt_cli.vision.edges import line_edges
from gsrwt_cli.vision.frontal_pixels import frontal_edges, seen
from gsrwt_cli.vision.landmarks import hough_lines
from tests.helpers.chessboard_edges import (
    DATA,
    Score,
    frontal_views,
    is_vertical,
    label,
    low_contrast_photo,
    photos,
    score,
)
from tests.helpers.cli import lines_of, run_gsrwt
from tests.helpers.door_renders import door_views
from tests.helpers.paths import SAMPLE_VIEWS as SAMPLES

POSES = ["--sidecar", str(DATA / "right_poses.csv"), "--camera", str(DATA / "right_camera.yml")]


@pytest.fixture(scope="module")
def boards():
    return {view.path.name: label(view) for view in frontal_views()}


def total_score(boards, found) -> Score:
    total = Score()
    for name, board in boards.items():
        total.add(score(board, found.get(name, [])))
    return total


@pytest.fixture(scope="module")
def chessboard_lines():
    """One call of gsrwt lines over the directory of photos, at the defaults."""
    return lines_of(str(DATA), *POSES)


@pytest.mark.slow
def test_real_chessboard_photos_recall_and_precision_at_the_defaults(boards, chessboard_lines):
    assert set(chessboard_lines) == {path.name for path in photos()}
    total = total_score(boards, chessboard_lines)
    print(f"recall {total.recall:.3f} ({total.found}/{total.long_vertical}), precision "
          f"vertical {total.vertical_precision:.3f}, all {total.precision:.3f}")
    assert total.long_vertical >= 300 and total.lines >= 800
    assert total.recall >= 0.75 and total.vertical_precision >= 0.55 and total.precision >= 0.45
    assert total.recall >= 0.95  # measured 0.979
    assert total.vertical_precision >= 0.95  # measured 0.972
    assert total.precision >= 0.90  # measured 0.922


@pytest.mark.slow
def test_low_contrast_real_photos_white_on_white(boards, tmp_path):
    """The photos at 15 % contrast (black and white squares 27 grey levels apart, like a
    white frame on a white wall) with noise and JPEG 60, through the same sidecar."""
    for path in photos():
        cv2.imwrite(str(tmp_path / path.name), low_contrast_photo(path))
    found = lines_of(str(tmp_path), *POSES)
    total = total_score(boards, found)
    print(f"recall {total.recall:.3f}, precision vertical {total.vertical_precision:.3f}, "
          f"all {total.precision:.3f}")
    assert total.recall >= 0.75 and total.vertical_precision >= 0.55 and total.precision >= 0.45
    assert total.recall >= 0.90  # measured 0.957 (the thesis's raw threshold of 80: 0.21)
    assert total.vertical_precision >= 0.95 and total.precision >= 0.90  # 0.980, 0.927


@pytest.mark.slow
def test_segments_do_not_run_across_the_board(boards, chessboard_lines):
    """A square's side is its own segment: no reported segment on the board is much longer
    than a square's side (the lines of before ran from board edge to board edge)."""
    for name, board in boards.items():
        side = max(edge.length for edge in board.edges)
        on_board = [line for line in chessboard_lines[name] if is_vertical(line, 5)]
        assert on_board
        for line in on_board:
            start, end = np.array([line.x1, line.y1]), np.array([line.x2, line.y2])
            inside = cv2.pointPolygonTest(board.outline.astype(np.float32).reshape(-1, 1, 2),
                                          tuple(float(v) for v in (start + end) / 2), True)
            if inside > 3:
                assert line.length <= side + 4, (name, line)


@pytest.mark.slow
def test_no_segment_at_the_fill_or_the_photos_rim(boards, chessboard_lines):
    """Every segment's ends lie on pixels with a source at least 4 px inside the photo
    (whose rim is dark), and its middle at least 3 px from any pixel without: none runs
    along the border of the fill."""
    checked = 0
    for name, board in boards.items():
        visible = seen(board.view.pixel_map, board.view.source_size)
        away = cv2.erode(visible.astype(np.uint8), np.ones((7, 7), np.uint8)).astype(bool)
        checked += np.count_nonzero(~visible) > 1000
        for line in chessboard_lines[name]:
            for x, y in ((line.x1, line.y1), (line.x2, line.y2)):
                assert visible[int(round(y)), int(round(x))], (name, line)
            middle_x, middle_y = (line.x1 + line.x2) / 2, (line.y1 + line.y2) / 2
            assert away[int(round(middle_y)), int(round(middle_x))], (name, line)
    assert checked >= 10  # most frontal views have a fill


@pytest.mark.slow
def test_orientation_and_min_length_filters(chessboard_lines):
    vertical = lines_of(str(DATA), *POSES, "--orientation", "vertical")
    horizontal = lines_of(str(DATA), *POSES, "--orientation", "horizontal")
    long = lines_of(str(DATA), *POSES, "--min-length", "60")
    for name, every in chessboard_lines.items():
        assert all(is_vertical(line, 5) for line in vertical[name])
        assert all(not is_vertical(line, 85) for line in horizontal[name])
        assert 0 < len(vertical[name]) < len(every) and 0 < len(horizontal[name]) < len(every)
        key = sorted((round(line.x1, 3), round(line.y1, 3)) for line in every
                     if is_vertical(line, 5))
        assert sorted((round(line.x1, 3), round(line.y1, 3)) for line in vertical[name]) == key
        assert all(line.length >= 60 for line in long.get(name, []))
        assert len(long.get(name, [])) < len(every)
        assert all(line.length >= 30 and line.votes >= 15 and line.contrast > 0
                   for line in every)


def door_score(views, **kwargs) -> tuple[Score, Score]:
    """Scores of the rendered doors: all, and the white frame on the white wall alone."""
    total, white = Score(), Score()
    for board in views:
        view = board.view
        edges = (frontal_edges(view.pixels, view.pixel_map, view.source_size) if not kwargs
                 else line_edges(view.pixels, valid=seen(view.pixel_map, view.source_size),
                                 **kwargs))
        found = hough_lines(view.pixels, edges=edges)
        total.add(score(board, found))
        board_white = SimpleNamespace(**{**board.__dict__,
                                         "edges": [e for e in board.edges if e.group == 0]})
        white.add(score(board_white, found))
    return total, white


@pytest.mark.slow
def test_rendered_doors_with_blur_noise_jpeg_and_a_white_frame_on_a_white_wall():
    views = door_views()
    total, white = door_score(views)
    uncompensated, _ = door_score(views, magnification=None)
    print(f"doors: recall {total.recall:.3f}, precision vertical {total.vertical_precision:.3f}"
          f", all {total.precision:.3f}; white frame recall {white.recall:.3f}; without the "
          f"magnification compensation recall {uncompensated.recall:.3f}")
    assert total.long_vertical >= 60 and white.long_vertical >= 20
    assert total.recall >= 0.85  # measured 0.931 (before: 0.60)
    assert total.vertical_precision >= 0.95 and total.precision >= 0.90
    assert white.recall >= 0.75
    # The compensation for the magnification of the far side is worth its cost.
    assert total.recall > uncompensated.recall




@pytest.mark.slow
def test_min_length_in_wall_units_needs_the_distance(tmp_path):
    """The corridor views have focal 280: with --distance 560 a frontal pixel is 2 units,
    so --min-length-units 80 is --min-length 40; without a distance it is each image's error."""
    corridor = [str(path) for path in sorted(SAMPLES.glob("corridor_*.png"))]
    sidecar = ["--sidecar", str(SAMPLES / "views.csv")]
    in_pixels = lines_of(*corridor, *sidecar, "--min-length", "40")
    in_units = lines_of(*corridor, *sidecar, "--distance", "560", "--min-length-units", "80")
    def ends(found):  # the distance changes the map's numbers in their last digits
        return {name: sorted((round(line.x1, 2), round(line.y1, 2), round(line.x2, 2),
                              round(line.y2, 2)) for line in rows)
                for name, rows in found.items()}

    assert ends(in_units) == ends(in_pixels) and sum(map(len, in_units.values())) > 10
    result = run_gsrwt("lines", *corridor[:2], *sidecar, "--min-length-units", "80")
    assert result.returncode == 1 and result.stdout.count("\n") == 1  # the header only
    errors = result.stderr.strip().splitlines()
    assert len(errors) == 2 and all("--min-length-units" in line and "distance" in line
                                    for line in errors)
    assert "Traceback" not in result.stderr


@pytest.mark.slow
def test_draw_over_a_directory_in_one_call(tmp_path):
    result = run_gsrwt("lines", str(DATA), *POSES, "--orientation", "vertical", "--draw",
                       str(tmp_path / "drawn"), "--format", "csv")
    assert result.returncode == 0, result.stderr
    header = result.stdout.splitlines()[0].split(",")
    assert header[:12] == ["image", "rho", "theta_deg", "votes", "x1", "y1", "x2", "y2",
                           "x1_src", "y1_src", "x2_src", "y2_src"]
    assert header[12:] == ["length", "contrast"]
    pictures = sorted(path.name for path in (tmp_path / "drawn").iterdir())
    assert pictures == sorted(f"{path.stem}.png" for path in photos())
    picture = cv2.imread(str(tmp_path / "drawn" / "right06.png"))
    red = (picture[..., 2] > 200) & (picture[..., 1] < 60) & (picture[..., 0] < 60)
    assert red.sum() > 2000  # the vertical segments, drawn in red
