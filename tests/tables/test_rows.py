"""The rows of the public tables (``tables/rows.py``): params rows of many views computed
together, against each view's own row (a second implementation, compared as the table prints
it); the rectify, gaze, track, lines and match rows from the values they describe."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

from gsrwt_cli.geometry.camera import View
from gsrwt_cli.tables.rows import PARAMS_COLUMNS, line_row, match_row, params_row, plan_row
from tests.helpers.camera import camera_axes
from tests.helpers.printed import PrintedComparison, assert_table_prints_rows


def _random_record(rng, index: int) -> tuple[str, dict[str, str], str]:
    """A sidecar record of a random kind: plain, with size or principal point, frontal,
    invalid, near the horizon limit, rolled (the long way)."""
    values = {"pan": f"{rng.uniform(-89.99, 89.99):.3f}",
              "tilt": f"{rng.uniform(-89.99, 89.99):.3f}", "focal": f"{rng.uniform(1, 3000):.2f}"}
    kind = rng.randrange(10)
    extra = [
        {"width": str(rng.randint(1, 5000)), "height": str(rng.randint(1, 5000))},
        {"cx": f"{rng.uniform(-100, 1000):.1f}", "cy": f"{rng.uniform(-100, 1000):.1f}"},
        {"cx": "10", "cy": "20", "width": "30", "height": "40"},
        {"pan": "0", "tilt": "0", "width": "640", "height": "480"},
        {"pan": "0", "tilt": "-0"},
        {"tilt": "95"},
        {"width": "64.5", "height": "3"},
        {"pan": "89.99999999", "tilt": "89.9999999", "focal": "1"},
        {"width": "640", "cx": "nan", "cy": "1"},
        {"roll": "5", "width": "640", "height": "480"},
    ][kind]
    return f"i{index}.png", {**values, **extra}, f"views.csv line {index + 2}"


def test_views_computed_together_print_what_their_views_print():
    """``params --sidecar`` computes square-pixel pinholes many at once: every row prints
    what the record's own view prints (a second implementation: values within
    :data:`printed.TOLERANCE`, cells identical but where a value lies that close to a
    rounding boundary), and every error is the view's own."""
    import random

    from gsrwt_cli.inputs.records import RecordError, view_from_values
    from gsrwt_cli.tables.rows import params_row, params_rows

    rng = random.Random(7)
    records = [_random_record(rng, index) for index in range(20_000)]
    fast = 0
    compare = PrintedComparison()
    for (image, values, where), row in zip(records, params_rows(records)):
        try:
            expected = params_row(view_from_values(values, where), image)
        except RecordError as error:
            assert isinstance(row, RecordError) and str(row) == str(error)
            continue
        assert isinstance(row, dict) and row.keys() == expected.keys(), (values, row)
        for name, value in expected.items():
            compare.values(row[name], value, (name, values))
        fast += "roll" not in values
    assert fast > 8_000  # valid rows without roll: computed together
    compare.assert_few_flips()


@pytest.mark.parametrize("kind", ["size", "principal point", "neither", "frontal rows"])
def test_a_plain_csv_chunk_computed_as_columns_writes_what_its_views_would(kind):
    """A chunk of plain CSV rows (decimal text, valid square-pixel pinholes) is computed and
    written as columns: the same csv and json, byte for byte, as each row's own view gives."""
    import random

    from gsrwt_cli.inputs.records import view_from_values
    from gsrwt_cli.tables.rows import PARAMS_CHUNK, ParamsBlock, params_row, params_rows
    from gsrwt_cli.tables.writer import TableWriter

    rng = random.Random(kind)
    records = []
    for index in range(PARAMS_CHUNK + 100):  # a whole chunk, then part of one
        values = {"pan": f"{rng.uniform(-85, 85):.4f}", "tilt": f"{rng.uniform(-85, 85):.4f}",
                  "focal": f"{rng.uniform(50, 4000):.3f}"}
        if kind == "frontal rows" and index % 3 == 0:
            values.update(pan="0", tilt="-0.0")
        if kind in ("size", "frontal rows"):
            values.update(width=str(rng.randint(1, 6000)), height=str(rng.randint(1, 6000)))
        elif kind == "principal point":
            values.update(cx=f"{rng.uniform(-50, 900):.2f}", cy=f"{rng.uniform(-50, 900):.2f}")
        records.append((f"img{index}.jpg", values, f"views.csv line {index + 2}"))
    produced = list(params_rows(records))
    assert all(isinstance(item, ParamsBlock) for item in produced) and len(produced) == 2
    rows = [params_row(view_from_values(values, where), image)
            for image, values, where in records]
    for fmt in ("csv", "json"):
        fast = io.StringIO()
        writer = TableWriter(fast, PARAMS_COLUMNS, fmt)
        for block in produced:
            writer.write_columns(block.columns, block.count)
        writer.close()
        assert_table_prints_rows(fast.getvalue(), fmt, rows, PARAMS_COLUMNS)


def test_a_chunk_with_one_odd_cell_is_computed_row_by_row():
    """One cell that is not plain decimal text (here ``1_000``, which Python's float reads)
    sends its chunk the long way: that row is the error its view gives."""
    from gsrwt_cli.inputs.records import RecordError
    from gsrwt_cli.tables.rows import ParamsBlock, params_rows

    records = [(f"i{index}", {"pan": "10", "tilt": "5", "focal": "300"}, f"v line {index}")
               for index in range(50)]
    records[7] = ("i7", {"pan": "10", "tilt": "5", "focal": "1_000"}, "v line 7")
    produced = list(params_rows(records))
    assert not any(isinstance(item, ParamsBlock) for item in produced)
    assert isinstance(produced[7], RecordError) and "not a number" in str(produced[7])
    assert sum(isinstance(item, dict) for item in produced) == 49


POSES = [(15, 30, 0), (15, 30, 10), (-30, 20, -25), (40, -10, 5), (70, 5, 0)]


@pytest.mark.parametrize("pose", POSES, ids=lambda pose: "pan{}_tilt{}_roll{}".format(*pose))
def test_a_views_row_is_what_the_camera_built_from_words_sees(pose):
    """:func:`params_row` against the camera of ``tests/helpers/camera.py``: theta is the
    angle between the optical axis and the wall's normal, the foreshortening its cosine, the
    vanishing point the image of the wall's direction from the foot of the perpendicular to
    where the axis meets the wall, the vanishing line the pixels whose rays run parallel to
    the wall (positive on the side that sees it), and the horizon is in the image when a
    corner's ray does not reach the wall."""
    pan, tilt, roll = pose
    focal, width, height = 280.0, 320, 240
    cx, cy = (width - 1) / 2, (height - 1) / 2
    row = params_row(View(pan, tilt, focal, roll=roll, width=width, height=height), "v.png")
    assert set(row) == set(PARAMS_COLUMNS)  # every column (the writer puts them in order)
    up, right, forward = camera_axes(pan, tilt, roll)
    assert row["theta_deg"] == pytest.approx(np.degrees(np.arccos(forward[2])), abs=1e-9)
    assert row["foreshortening"] == pytest.approx(forward[2], abs=1e-12)
    lean = np.array([*forward[:2], 0.0])  # the wall's direction the axis leans along
    x, y = focal * (lean @ up) / (lean @ forward), focal * (lean @ right) / (lean @ forward)
    assert (row["vp_x"], row["vp_y"]) == pytest.approx((x, y), abs=1e-6)  # x up, y right
    assert (row["vp_col"], row["vp_row"]) == pytest.approx((cx + y, cy - x), abs=1e-6)
    # Rays x up + y right + f forward with no component along the wall's normal (Z).
    line = np.array([right[2], -up[2], cy * up[2] - cx * right[2] + focal * forward[2]])
    line /= np.hypot(*line[:2]) * np.sign(line @ [cx, cy, 1.0])
    assert (row["vl_a"], row["vl_b"], row["vl_c"]) == pytest.approx(tuple(line), abs=1e-9)
    corners = np.array([[c, r] for c in (-0.5, width - 0.5) for r in (-0.5, height - 0.5)])
    rays = ((cy - corners[:, 1])[:, None] * up + (corners[:, 0] - cx)[:, None] * right
            + focal * forward)
    assert row["horizon_in_image"] is bool((rays[:, 2] <= 0).any())
    assert row["image"] == "v.png" and row["roll_deg"] == roll


def test_values_that_do_not_exist_are_left_out_or_infinite():
    """A frontal view's vanishing point is at infinity (no line); without a size there is no
    principal point to place it in pixels, nor a horizon to cross the image."""
    frontal = params_row(View(0, 0, 300, width=320, height=240))
    assert math.isinf(frontal["a_px"]) and math.isinf(frontal["vp_x"])
    assert "vl_a" not in frontal and frontal["horizon_in_image"] is False
    unsized = params_row(View(15, 30, 280))
    assert "vp_col" not in unsized and "vl_a" not in unsized
    assert unsized["horizon_in_image"] is None


def test_a_plan_row_gives_the_output_and_its_homography_to_twelve_digits():
    from gsrwt_cli.geometry.framing import Framing, plan_output

    plan = plan_output(View(20, 10, 400, width=640, height=480), Framing(bbox="full",
                                                                          scale=0.5))
    row = plan_row(plan)
    assert (row["out_width"], row["out_height"], row["scale"]) == (*plan.size, 0.5)
    cells = np.array(row["homography"].split(), dtype=float).reshape(3, 3)
    np.testing.assert_allclose(cells, plan.homography, rtol=1e-11)
    assert params_row(plan.view).items() <= row.items()


def test_lines_and_matches_give_their_source_points_only_when_there_is_a_map():
    from pathlib import Path

    from gsrwt_cli.tables.columns import LINES_COLUMNS, MATCH_COLUMNS
    from gsrwt_cli.vision.ght import Match
    from gsrwt_cli.vision.hough import Line

    line = Line(rho=12.0, theta_deg=90.0, votes=50, x1=1.0, y1=12.0, x2=61.0, y2=12.0,
                length=60.0, contrast=80.0)
    match = Match(x=30.0, y=40.0, scale=1.05, votes=120, score=0.8)

    def shifted(points: np.ndarray) -> np.ndarray:
        return points + [100.0, -5.0]

    bare = line_row(Path("a.png"), line, lambda points: None)
    mapped = line_row(Path("a.png"), line, shifted)
    assert set(bare) < set(mapped) <= set(LINES_COLUMNS)
    assert (mapped["x1_src"], mapped["y1_src"], mapped["x2_src"], mapped["y2_src"]) == (
        101.0, 7.0, 161.0, 7.0)
    found = match_row(Path("a.png"), "knob.png", match, shifted)
    assert set(found) == set(MATCH_COLUMNS) and (found["x_src"], found["y_src"]) == (130.0, 35.0)
    assert "x_src" not in match_row(Path("a.png"), "knob.png", match, lambda points: None)
