"""Guided correction through the real ``gsrwt`` command (subprocesses): ``estimate``,
``rectify`` and ``params`` with ``--corners``, ``--aspect``, ``--verticals``,
``--horizontals`` and ``--fit``, the sidecar columns, and bad guides."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import cv2
import numpy as np
import pytest

from gsrwt_cli.inputs.guides import parse_corners
from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA, ROOT, SAMPLE_VIEWS
from tests.helpers.rectangles import RectangleShot, rectangle_shot

SHOT = rectangle_shot(25.0, -15.0, 5.0, 900.0, 1.5)


def corners_text(shot: RectangleShot) -> str:
    return " ".join(f"{col:.4f},{row:.4f}" for col, row in shot.corners)


def segments_text(segments: np.ndarray) -> str:
    return ";".join(",".join(f"{v:.4f}" for v in segment) for segment in segments)


@pytest.fixture(scope="module")
def photo(tmp_path_factory) -> str:
    """A grey 1024x768 PNG with the rectangle painted in (the guides are given, not found)."""
    path = tmp_path_factory.mktemp("guides") / "shot.png"
    image = np.full((SHOT.height, SHOT.width, 3), 120, np.uint8)
    cv2.fillConvexPoly(image, np.round(SHOT.corners).astype(np.int32), (230, 230, 230))
    cv2.imwrite(str(path), image)
    return str(path)


def rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


def pose_of(row: dict[str, str], suffix: str = "") -> np.ndarray:
    return np.array([float(row[f"{name}{suffix}"]) for name in ("pan", "tilt", "roll")])


def rectified_corners(row: dict[str, str], corners: np.ndarray) -> np.ndarray:
    homography = np.array([float(v) for v in row["homography"].split()]).reshape(3, 3)
    mapped = np.column_stack([corners, np.ones(len(corners))]) @ homography.T
    return mapped[:, :2] / mapped[:, 2:]


def test_estimate_corners_writes_pose_focal_and_aspect(photo):
    done = run_gsrwt("estimate", photo, "--corners", corners_text(SHOT), "-f", "csv")
    assert done.returncode == 0, done.stderr
    [row] = rows(done.stdout)
    assert np.max(np.abs(pose_of(row) - [25.0, -15.0, 5.0])) < 0.01
    assert abs(float(row["focal"]) / 900.0 - 1) < 1e-3
    assert abs(float(row["aspect"]) / 1.5 - 1) < 1e-3
    assert (row["focal_source"], row["aspect_source"], row["status"]) == (
        "estimated", "estimated", "ok")
    given = rows(run_gsrwt("estimate", photo, "--corners", corners_text(SHOT), "--aspect",
                           "3:2", "--focal", "900", "-f", "csv").stdout)[0]
    assert (given["focal_source"], given["aspect_source"], given["aspect"]) == (
        "option", "given", "1.5")
    assert np.max(np.abs(pose_of(given) - [25.0, -15.0, 5.0])) < 0.01


def test_guides_give_the_corners_pose_with_ends_in_either_order(photo):
    verticals, horizontals = SHOT.sides()
    for order in ([0, 1, 2, 3], [2, 3, 0, 1]):
        done = run_gsrwt("estimate", photo, "--verticals", segments_text(verticals[:, order]),
                         "--horizontals", segments_text(horizontals[::-1, order]), "-f", "csv")
        assert done.returncode == 0, done.stderr
        [row] = rows(done.stdout)
        assert np.max(np.abs(pose_of(row) - [25.0, -15.0, 5.0])) < 0.3
        assert abs(float(row["focal"]) / 900.0 - 1) < 1e-2
        assert row["aspect"] == "" and row["focal_source"] == "estimated"


def test_rectify_frames_the_rectangle_upright_from_options_and_from_estimate(photo, tmp_path):
    done = run_gsrwt("rectify", photo, "--corners", corners_text(SHOT), "-o",
                     str(tmp_path / "direct"), "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    estimated = run_gsrwt("estimate", photo, "--corners", corners_text(SHOT), "-o",
                          str(tmp_path / "poses.csv"), "-q")
    assert estimated.returncode == 0, estimated.stderr
    piped = run_gsrwt("rectify", photo, "--sidecar", str(tmp_path / "poses.csv"), "-o",
                      str(tmp_path / "piped"), "-q", "-j", "1")
    assert piped.returncode == 0, piped.stderr
    for name in ("direct", "piped"):
        [row] = rows((tmp_path / name / "gsrwt.csv").read_text())
        assert row["status"] == "ok" and row["focal_source"] == (
            "estimated" if name == "direct" else "sidecar")
        # The corners' pose frames the whole wall; the pose the table gives, the thesis's box.
        assert f"bbox={'full' if name == 'direct' else 'frontal'}" in row["made_with"].split()
        tl, tr, br, bl = rectified_corners(row, SHOT.corners)
        assert abs(tl[1] - tr[1]) < 0.5 and abs(bl[1] - br[1]) < 0.5
        assert abs(tl[0] - bl[0]) < 0.5 and abs(tr[0] - br[0]) < 0.5
        assert abs((tr[0] - tl[0]) / (bl[1] - tl[1]) / 1.5 - 1) < 1e-3


def test_sidecar_columns_give_guides(photo, tmp_path):
    sidecar = tmp_path / "guides.csv"
    sidecar.write_text('image,corners,focal,fit\n'
                       f'shot.png,"{corners_text(SHOT)}",900,vertical\n')
    done = run_gsrwt("rectify", photo, "--sidecar", str(sidecar), "-o", str(tmp_path / "out"),
                     "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    [row] = rows((tmp_path / "out" / "gsrwt.csv").read_text())
    assert float(row["pan_deg"]) == 0.0  # --fit vertical: the horizontal perspective stays
    assert abs(float(row["tilt_deg"]) + 15.0) < 0.01
    tl, tr, br, bl = rectified_corners(row, SHOT.corners)
    assert abs(tl[0] - bl[0]) < 0.01 and abs(tr[0] - br[0]) < 0.01  # verticals vertical
    assert abs((bl[1] - tl[1]) / (br[1] - tr[1]) - 1) > 0.1  # horizontals still converge


def test_params_takes_guides():
    done = run_gsrwt("params", "--corners", corners_text(SHOT), "--width", "1024", "--height",
                     "768", "-f", "csv")
    assert done.returncode == 0, done.stderr
    [row] = rows(done.stdout)
    assert np.max(np.abs(pose_of(row, "_deg") - [25.0, -15.0, 5.0])) < 0.01
    assert abs(float(row["focal_px"]) / 900 - 1) < 1e-3


@pytest.mark.parametrize("args, message", [
    (["--corners", "1,2 30,4 50,60"], "option --corners: need 4 corners"),
    (["--corners", "0,0 0,100 100,100 100,0"], "option --corners: the corners go "
                                                "counter-clockwise"),
    (["--corners", "0,0 100,0 0,100 100,100"], "option --corners: the corners are not a "
                                                "convex quadrilateral"),
    (["--corners", "a,b 1,2 3,4 5,6"], "option --corners: 'a,b' is not a point"),
    (["--verticals", "0,0,0,100"], "option --verticals: need two or more vertical segments"),
    (["--horizontals", "0,0,100,0;5,5,5"], "option --horizontals: '5,5,5' is not a segment"),
    (["--aspect", "3:0"], "option --aspect: the aspect ratio is W:H or one positive number"),
    (["--corners", "312,191 712,188 715,590 310,593"],
     "option --corners: the view is too frontal to tell the focal length"),
    (["--verticals", "0,0,1,100;100,0,101,100"], "option --horizontals: --fit both needs two "
                                                 "or more horizontals (or corners); with "
                                                 "verticals alone give --fit vertical"),
])
def test_bad_guides_are_one_line_naming_the_option(args, message):
    done = run_gsrwt("params", *args, "--width", "1024", "--height", "768")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert message in done.stderr, done.stderr


def test_a_bad_guide_in_a_sidecar_fails_its_image_naming_the_row(photo, tmp_path):
    sidecar = tmp_path / "bad.csv"
    sidecar.write_text('image,corners\nshot.png,"312,191 712,188 715,590 310,593"\n')
    done = run_gsrwt("estimate", photo, "--sidecar", str(sidecar), "-f", "csv")
    assert done.returncode == 1
    [row] = rows(done.stdout)
    assert row["status"] == "error"
    assert "line 2, field 'corners': the view is too frontal" in row["error"]
    assert "give --focal or --aspect" in row["error"]


@pytest.mark.parametrize("extra", [[], ["--aspect", "3:2", "--focal", "900"],
                                   ["--max-size", "400x400"]])
def test_bbox_corners_frames_the_rectangle_upright(photo, tmp_path, extra):
    """``--bbox corners --margin 5``: the corners land on an axis-aligned rectangle of the
    aspect within 0.5 px, 5 % of its sides from the output's edges, and the output shows the
    painted rectangle there."""
    done = run_gsrwt("rectify", photo, "--corners", corners_text(SHOT), "--bbox", "corners",
                     "--margin", "5", *extra, "-o", str(tmp_path / "out"), "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    [row] = rows((tmp_path / "out" / "gsrwt.csv").read_text())
    tl, tr, br, bl = rectified_corners(row, SHOT.corners)
    assert abs(tl[1] - tr[1]) < 0.5 and abs(bl[1] - br[1]) < 0.5
    assert abs(tl[0] - bl[0]) < 0.5 and abs(tr[0] - br[0]) < 0.5
    width, height = tr[0] - tl[0], bl[1] - tl[1]
    assert abs(width / height - 1.5) < 0.5 / height * 3
    out_width, out_height = int(row["out_width"]), int(row["out_height"])
    assert abs((tl[0] + 0.5) - 0.05 * width) < 1.5 and abs((tl[1] + 0.5) - 0.05 * height) < 1.5
    assert abs(out_width / (1.1 * width) - 1) < 0.01
    if extra == ["--max-size", "400x400"]:
        assert out_width <= 400 and out_height <= 400
    else:  # the rectangle keeps its pixels: its longest side as long as in the input
        assert width >= np.max(np.linalg.norm(SHOT.corners[[1, 2]] - SHOT.corners[[0, 3]],
                                              axis=1)) - 1
    image = cv2.imread(str(tmp_path / "out" / "shot.png"))
    inside = image[int(tl[1]) + 3:int(bl[1]) - 3, int(tl[0]) + 3:int(tr[0]) - 3]
    assert inside.min() > 200
    assert image[: max(1, int(tl[1]) - 3)].max() < 150


def test_bbox_corners_needs_corners(photo, tmp_path):
    done = run_gsrwt("rectify", photo, "--pan", "10", "--tilt", "5", "--focal", "900",
                     "--bbox", "corners", "-o", str(tmp_path / "out"), "-q", "-j", "1")
    assert done.returncode == 1
    assert "--bbox corners needs the rectangle's corners" in done.stderr


def test_estimate_pipes_into_rectify_through_standard_input(photo, tmp_path):
    """``gsrwt estimate ... | gsrwt rectify --sidecar -``: CSV or YAML on standard input."""
    estimated = run_gsrwt("estimate", photo, "--corners", corners_text(SHOT), "-q")
    assert estimated.returncode == 0, estimated.stderr
    yaml_text = "- image: shot.png\n  pan: 25\n  tilt: -15\n  roll: 5\n  focal: 900\n"
    for name, text in (("csv", estimated.stdout), ("yaml", yaml_text)):
        done = run_gsrwt("rectify", photo, "--sidecar", "-", "-o", str(tmp_path / name), "-q",
                         "-j", "1", stdin=text)
        assert done.returncode == 0, done.stderr
        [row] = rows((tmp_path / name / "gsrwt.csv").read_text())
        assert np.max(np.abs(pose_of(row, "_deg") - [25.0, -15.0, 5.0])) < 0.01
    both = run_gsrwt("rectify", "-", "--sidecar", "-", "-o", str(tmp_path / "both"),
                     stdin=photo + "\n")
    assert both.returncode == 2
    assert "--sidecar - and INPUT - cannot both read standard input" in both.stderr


def test_estimate_writes_a_yaml_sidecar_that_rectify_reads(photo, tmp_path):
    poses = tmp_path / "poses.yaml"
    done = run_gsrwt("estimate", photo, "--corners", corners_text(SHOT), "-o", str(poses), "-q")
    assert done.returncode == 0, done.stderr
    import yaml

    [record] = yaml.safe_load(poses.read_text())
    assert record["image"] == "shot.png" and record["aspect_source"] == "estimated"
    assert abs(record["pan"] - 25.0) < 0.01 and "confidence" not in record
    done = run_gsrwt("rectify", photo, "--sidecar", str(poses), "-o", str(tmp_path / "out"),
                     "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    [row] = rows((tmp_path / "out" / "gsrwt.csv").read_text())
    assert np.max(np.abs(pose_of(row, "_deg") - [25.0, -15.0, 5.0])) < 0.01


def test_fit_vertical_on_a_real_photo_makes_the_clicked_verticals_vertical(tmp_path):
    """OpenCV's building.jpg with two verticals clicked by eye (docs/COMMANDS.md): after
    ``--fit vertical`` both run straight down the output, and pan is left as it was."""
    photo = DATA / "facade" / "building.jpg"
    verticals = np.array([[151, 140, 150, 370], [751, 70, 761, 300]], dtype=float)
    done = run_gsrwt("rectify", str(photo), "--verticals", segments_text(verticals),
                     "--fit", "vertical", "--focal", "1245", "-o", str(tmp_path / "out"),
                     "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    [row] = rows((tmp_path / "out" / "gsrwt.csv").read_text())
    assert float(row["pan_deg"]) == 0.0
    ends = rectified_corners(row, verticals.reshape(-1, 2)).reshape(-1, 4)
    assert np.all(np.abs(ends[:, 0] - ends[:, 2]) < 0.01)


def test_a_row_with_its_own_pose_or_guides_takes_none_of_the_options_other_kind(tmp_path):
    """Options fill what a sidecar row leaves out: a row with a pose takes no --corners, a
    row with corners takes no --pan/--tilt (and neither is an error)."""
    sidecar = tmp_path / "mixed.csv"
    sidecar.write_text(f'image,pan,tilt,corners\nposed.png,10,5,\nguided.png,,,'
                       f'"{corners_text(SHOT)}"\n')
    for extra in (["--corners", corners_text(SHOT)], ["--pan", "1", "--tilt", "2"]):
        done = run_gsrwt("params", "--sidecar", str(sidecar), "--focal", "900", "--width",
                         "1024", "--height", "768", *extra, "-f", "csv")
        assert done.returncode == 0, done.stderr
        posed, guided = rows(done.stdout)
        assert (float(posed["pan_deg"]), float(posed["tilt_deg"])) == (10.0, 5.0)
        assert np.max(np.abs(pose_of(guided, "_deg") - [25.0, -15.0, 5.0])) < 0.01


def test_corners_through_a_lens_give_the_pose(tmp_path):
    """Corners rendered through OpenCV's plumb_bob lens (k1 = -0.2): with the lens in the
    sidecar the corners are undistorted first and give the pose exactly; without it they
    do not."""
    from tests.helpers.rectangles import project

    k1 = -0.2
    pinhole = project(SHOT.world_corners(), SHOT.pan, SHOT.tilt, SHOT.roll, SHOT.focal, SHOT.cx,
                      SHOT.cy)
    rays = np.column_stack([(pinhole - [SHOT.cx, SHOT.cy]) / SHOT.focal, np.ones(4)])
    matrix = np.array([[SHOT.focal, 0, SHOT.cx], [0, SHOT.focal, SHOT.cy], [0, 0, 1.0]])
    distorted = cv2.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), matrix,
                                  np.array([k1, 0, 0, 0, 0.0]))[0].reshape(-1, 2)
    text = " ".join(f"{col:.4f},{row:.4f}" for col, row in distorted)
    sidecar = tmp_path / "lens.csv"
    sidecar.write_text(f'image,corners,focal,k1,width,height\nwith.png,"{text}",900,{k1},1024,'
                       f'768\nwithout.png,"{text}",900,,1024,768\n')
    done = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert done.returncode == 0, done.stderr
    with_lens, without = rows(done.stdout)
    assert np.max(np.abs(pose_of(with_lens, "_deg") - [25.0, -15.0, 5.0])) < 0.01
    assert np.max(np.abs(pose_of(without, "_deg") - [25.0, -15.0, 5.0])) > 0.5


def test_fit_vertical_applies_to_auto(tmp_path):
    """``rectify --auto --fit vertical``: the estimated pose with its pan set to 0 (the
    same tilt and roll as ``--auto`` alone)."""
    photo = SAMPLE_VIEWS / "door_p40_t-12_f700.jpg"
    found = {}
    for fit in ("both", "vertical"):
        done = run_gsrwt("rectify", str(photo), "--auto", "--fit", fit, "-o",
                         str(tmp_path / fit), "-q", "-j", "1")
        assert done.returncode == 0, done.stderr
        [found[fit]] = rows((tmp_path / fit / "gsrwt.csv").read_text())
    assert abs(float(found["both"]["pan_deg"]) - 40) < 2
    assert float(found["vertical"]["pan_deg"]) == 0.0
    for name in ("tilt_deg", "roll_deg"):
        assert float(found["vertical"][name]) == pytest.approx(float(found["both"][name]),
                                                                abs=1e-6)


# --------------------------------------------------------------------------------------------
# --auto document: the corners found, not given
# --------------------------------------------------------------------------------------------

PAGE = rectangle_shot(-24.0, 14.0, -6.0, 1000.0, 210 / 297, size=0.7)


@pytest.fixture(scope="module")
def page_photo(tmp_path_factory) -> Path:
    """An A4 page rendered onto a real photo (``tests/helpers/pages.py``), in its own folder."""
    from tests.helpers.pages import render_page

    folder = tmp_path_factory.mktemp("document")
    cv2.imwrite(str(folder / "page.png"), render_page(PAGE, "home.jpg"))
    return folder / "page.png"


def test_estimate_auto_document_finds_the_page_its_pose_and_aspect(page_photo):
    done = run_gsrwt("estimate", page_photo, "--auto", "document", "--focal", "1000",
                     "-f", "csv")
    assert done.returncode == 0, done.stderr
    [row] = rows(done.stdout)
    assert np.max(np.abs(pose_of(row) - [-24.0, 14.0, -6.0])) < 0.3
    assert abs(float(row["aspect"]) / (210 / 297) - 1) < 0.01
    found = np.array([[float(v) for v in point.split(",")] for point in row["corners"].split()])
    assert np.abs(found - PAGE.corners).max() < 1.0
    assert (row["aspect_source"], row["focal_source"], row["status"]) == (
        "estimated", "option", "ok")


def test_rectify_auto_document_frames_the_page_upright_and_resumes(page_photo, tmp_path):
    """``rectify --auto document --bbox corners``: the page's true corners land on an upright
    rectangle (within a pixel: the corners are found, not given); the table says how; a
    rerun skips it; ``--auto`` alone reads its next word as an input, not a mode."""
    out = tmp_path / "out"
    args = ("rectify", page_photo, "--auto", "document", "--focal", "1000", "--bbox",
            "corners", "-o", out, "-j", "1")
    done = run_gsrwt(*args)
    assert done.returncode == 0, done.stderr
    [row] = rows((out / "gsrwt.csv").read_text())
    assert (row["pose_source"], row["aspect_source"], row["status"]) == (
        "estimated", "estimated", "ok")
    assert "auto=document" in row["made_with"].split()
    tl, tr, br, bl = rectified_corners(row, PAGE.corners)
    assert abs(tl[1] - tr[1]) < 1 and abs(bl[1] - br[1]) < 1
    assert abs(tl[0] - bl[0]) < 1 and abs(tr[0] - br[0]) < 1
    assert abs((tr[0] - tl[0]) / (bl[1] - tl[1]) / (210 / 297) - 1) < 0.01
    again = run_gsrwt(*args)
    assert again.returncode == 0 and "0 ok, 1 skipped" in again.stderr
    # The word after a bare --auto is an input unless it names a mode.
    lines = run_gsrwt("rectify", "--auto", page_photo.parent, "--focal", "1000", "-o",
                      tmp_path / "lines", "-j", "1")
    assert "Usage" not in lines.stderr
    [row] = rows((tmp_path / "lines" / "gsrwt.csv").read_text())
    assert row["image"].endswith("page.png") and row["pose_source"] == "estimated"


def test_auto_takes_only_its_modes():
    done = run_gsrwt("rectify", "--auto=walls", str(SAMPLE_VIEWS), "-o", "unused")
    assert done.returncode == 2
    assert "'--auto'" in done.stderr and "'walls' is not one of 'lines', 'document'" in (
        done.stderr)


def test_auto_document_refuses_a_photo_without_one_saying_why(tmp_path):
    photo = DATA / "real" / "gravel.jpg"
    done = run_gsrwt("estimate", photo, "--auto", "document", "--focal", "500", "-f", "csv")
    assert done.returncode == 1
    [row] = rows(done.stdout)
    assert row["status"] == "error"
    assert row["error"].startswith("no convex quadrilateral of straight edges")


def test_estimate_auto_document_pipes_into_rectify_with_its_corners(page_photo, tmp_path):
    estimated = run_gsrwt("estimate", page_photo, "--auto", "document", "--focal", "1000",
                          "-q")
    assert estimated.returncode == 0, estimated.stderr
    done = run_gsrwt("rectify", page_photo, "--sidecar", "-", "--bbox", "corners", "-o",
                     tmp_path / "out", "-j", "1", "-q", stdin=estimated.stdout)
    assert done.returncode == 0, done.stderr
    [row] = rows((tmp_path / "out" / "gsrwt.csv").read_text())
    assert row["pose_source"] == "sidecar"
    tl, tr, br, bl = rectified_corners(row, PAGE.corners)
    assert abs(tl[1] - tr[1]) < 1 and abs(tl[0] - bl[0]) < 1


def test_rectify_table_says_the_aspect_ratio_and_its_source(photo, tmp_path):
    for extra, source in (([], "estimated"), (["--aspect", "3:2"], "given")):
        out = tmp_path / source
        done = run_gsrwt("rectify", photo, "--corners", corners_text(SHOT), *extra, "-o", out,
                         "-q", "-j", "1")
        assert done.returncode == 0, done.stderr
        [row] = rows((out / "gsrwt.csv").read_text())
        assert row["aspect_source"] == source
        assert abs(float(row["aspect"]) / 1.5 - 1) < 1e-3


def test_estimate_auto_document_draws_the_outline_or_why_not(page_photo, tmp_path):
    done = run_gsrwt("estimate", page_photo, DATA / "real" / "gravel.jpg", "--auto",
                     "document", "--focal", "1000", "--draw", tmp_path / "drawn", "-q")
    assert done.returncode == 1  # gravel has no document
    picture = cv2.imread(str(tmp_path / "drawn" / "page.png"))
    magenta = (picture[..., 0] > 200) & (picture[..., 2] > 200) & (picture[..., 1] < 80)
    rows_, cols = np.nonzero(magenta)
    assert len(rows_) > 1000
    # every outline pixel near a side of the page
    sides = [(PAGE.corners[k], PAGE.corners[(k + 1) % 4]) for k in range(4)]
    points = np.column_stack([cols, rows_]).astype(float)
    def from_line(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = (b - a) / np.linalg.norm(b - a)
        return np.abs(d[0] * (points[:, 1] - a[1]) - d[1] * (points[:, 0] - a[0]))

    distance = np.min([from_line(a, b) for a, b in sides], axis=0)
    assert np.percentile(distance, 99) < 12  # the line and the top-left corner's ring
    assert (tmp_path / "drawn" / "gravel.png").is_file()


def test_auto_document_refuses_a_quadrilateral_no_rectangle_makes(tmp_path):
    """With the focal length known, four corners over-determine a rectangle: a page whose
    corner is bent 8 px out is refused, saying so; without the focal length nothing can tell,
    and it is taken."""
    from tests.helpers.pages import render_page

    bent = rectangle_shot(18.0, -12.0, 3.0, 900.0, 0.75, size=0.7)
    corners = bent.corners.copy()
    corners[2] += 8 * (corners[2] - corners.mean(axis=0)) / np.linalg.norm(
        corners[2] - corners.mean(axis=0))
    shot = RectangleShot(bent.pan, bent.tilt, bent.roll, bent.focal, bent.aspect, bent.width,
                         bent.height, corners, bent.centre, bent.rect_height)
    cv2.imwrite(str(tmp_path / "bent.png"), render_page(shot, "fruits.jpg"))
    done = run_gsrwt("estimate", tmp_path / "bent.png", "--auto", "document", "--focal", "900",
                     "-f", "csv")
    assert done.returncode == 1
    [row] = rows(done.stdout)
    assert row["error"].startswith("the largest quadrilateral is no rectangle seen by this "
                                   "camera: the best rectangle's corners miss it by")
    unknown = run_gsrwt("estimate", tmp_path / "bent.png", "--auto", "document", "--aspect",
                        "0.75", "-f", "csv")
    assert rows(unknown.stdout)[0]["status"] == "ok", unknown.stdout


def test_auto_document_says_a_frontal_page_gives_no_focal_length(tmp_path):
    """A page seen about frontally, with no focal length anywhere (a PNG has no EXIF): its
    corners cannot tell the focal length, and both commands say so of the document found,
    not of a field 'corners' the user never wrote."""
    from tests.helpers.pages import render_page

    frontal = rectangle_shot(1.0, -2.0, 0.5, 900.0, 0.75, size=0.7)
    cv2.imwrite(str(tmp_path / "frontal.png"), render_page(frontal, "fruits.jpg"))
    reason = "the document's corners give no pose: the view is too frontal to tell the focal "
    estimated = run_gsrwt("estimate", tmp_path / "frontal.png", "--auto", "document", "-f", "csv")
    assert estimated.returncode == 1
    [row] = rows(estimated.stdout)
    assert row["error"].startswith(reason) and row["error"].endswith("give --focal or --aspect")
    assert np.abs(np.array(parse_corners(row["corners"])) - frontal.corners).max() < 1.0
    rectified = run_gsrwt("rectify", tmp_path / "frontal.png", "--auto", "document", "-o",
                          tmp_path / "out")
    assert rectified.returncode == 1
    assert f"frontal.png: {reason}" in rectified.stderr and "field" not in rectified.stderr
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["gsrwt.csv"]


YORK = ROOT.parent / "shared" / "data" / "york-urban-train"


@pytest.mark.skipif(not YORK.is_dir(), reason="needs ../shared/data/york-urban-train")
def test_auto_document_on_real_photos_of_buildings_is_right_or_refused(tmp_path):
    """The York Urban training photos with their calibrated focal length: buildings, doors,
    windows, not documents. Every quadrilateral taken is within 3 degrees of the truth on
    both measures (benchmarks/real_photos.py); the rest are refused."""
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from real_photos import SceneDirections, directions_from_pose, image_errors

    truth = {row["image"]: row for row in rows((YORK / "truth.csv").read_text())}
    sidecar = tmp_path / "focal.csv"
    sidecar.write_text("image,focal,cx,cy\n" + "".join(
        f"{name},{row['focal_px']},{row['cx']},{row['cy']}\n" for name, row in truth.items()))
    done = run_gsrwt("estimate", YORK / "images", "--sidecar", sidecar, "--auto", "document",
                     "-f", "csv", "-q")
    taken = [row for row in rows(done.stdout) if row["status"] == "ok"]
    assert len(rows(done.stdout)) == len(truth) and taken
    for row in taken:
        true = truth[row["image"]]
        directions = SceneDirections(*(np.array([float(true[f"{name}_{axis}"])
                                                 for axis in "xyz"])
                                       for name in ("up", "wall", "side")))
        errors = image_errors(directions_from_pose(*pose_of(row)), directions)
        assert max(errors) < 3.0, (row["image"], errors)
