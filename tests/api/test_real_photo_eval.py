"""The real-photo evaluation (``benchmarks/real_photos.py``, ``benchmarks/bench_real_photos.py``)
checked on real values, and today's figures on the York Urban training half as a floor.

The measures are checked against hand-worked poses (docs/CONVENTIONS.md), against the York
Urban data's own orientations (each photo's pan, tilt and roll against its unit vectors), and
against rotations made by OpenCV's ``cv2.Rodrigues``. The York data lives outside the
repository (``../shared/data/york-urban-train`` beside it); the tests that need it skip where
it is absent.
"""

from __future__ import annotations

import math
import sys

import cv2
import numpy as np
import pytest

from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA, ROOT
from tests.helpers.tables import read_table

sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_real_photos  # noqa: E402
import real_photos as measure  # noqa: E402

from gsrwt_cli.geometry.rotations import rotation_from_pose  # noqa: E402

YORK = ROOT.parent / "shared" / "data" / "york-urban-train"
REAL = DATA / "real"
needs_york = pytest.mark.skipif(not (YORK / "truth.csv").is_file(),
                                reason=f"no York Urban data at {YORK}")


def york_truth() -> list[dict[str, str]]:
    return read_table(YORK / "truth.csv")


def turned(directions: measure.SceneDirections, axis: np.ndarray, degrees: float
           ) -> measure.SceneDirections:
    """All three directions turned about ``axis`` by ``degrees`` (``cv2.Rodrigues``)."""
    rotation = cv2.Rodrigues(np.radians(degrees) * axis / np.linalg.norm(axis))[0]
    return measure.SceneDirections(*(rotation @ v for v in directions))


# ------------------------------------------------------------------------------------------
# The conversion from gsrwt's pose to directions in OpenCV's camera frame
# ------------------------------------------------------------------------------------------


def test_hand_worked_poses_give_the_directions_the_conventions_describe():
    """docs/CONVENTIONS.md: pan > 0 turns the camera left, so the wall's normal leans to the
    camera's right (+x); tilt > 0 tilts it up, so world up leans forward (+z); roll > 0 leans
    its top right, so world up leans to the image's left (-x). OpenCV's y points down."""
    square = measure.directions_from_pose(0, 0, 0)
    np.testing.assert_allclose(square.up, [0, -1, 0], atol=1e-15)
    np.testing.assert_allclose(square.wall, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(square.side, [1, 0, 0], atol=1e-15)
    s, c = math.sin(math.radians(30)), math.cos(math.radians(30))
    np.testing.assert_allclose(measure.directions_from_pose(30, 0, 0).wall, [s, 0, c],
                               atol=1e-15)
    np.testing.assert_allclose(measure.directions_from_pose(0, 30, 0).up, [0, -c, s],
                               atol=1e-15)
    np.testing.assert_allclose(measure.directions_from_pose(0, 0, 30).up, [-s, -c, 0],
                               atol=1e-15)


def test_the_measures_rotation_is_the_packages():
    """The benchmark builds ``world_from_camera`` itself (to measure the package, not repeat
    it); it must be the package's rotation (two implementations: a tolerance, not equality)."""
    for pan, tilt, roll in ((33.64, 12.85, -1.17), (-41.0, -7.5, 9.0), (5.0, 60.0, -170.0)):
        np.testing.assert_allclose(measure.world_from_camera(pan, tilt, roll),
                                   rotation_from_pose(pan, tilt, roll), atol=1e-12)


@needs_york
def test_york_truth_pose_converts_to_its_own_vectors():
    """Each York photo's pan, tilt and roll (this project's convention) and its unit vectors
    (OpenCV camera frame) are the same orientation, within the 0.06 degrees the data's README
    promises: this pins the conversion the benchmark measures with."""
    rows = york_truth()
    assert len(rows) == 51
    worst = 0.0
    for row in rows:
        pose = measure.directions_from_pose(float(row["pan"]), float(row["tilt"]),
                                            float(row["roll"]))
        truth = bench_real_photos.true_directions(row)
        worst = max(worst, measure.angle_between(pose.up, truth.up),
                    measure.angle_between(pose.wall, truth.wall),
                    measure.angle_between_lines(pose.side, truth.side))
        assert measure.image_errors(pose, truth).vertical < 0.06, row["image"]
    assert worst < 0.06
    # The conversion must matter: OpenCV's axes taken for the thesis's are far off.
    row = rows[0]
    w = measure.world_from_camera(float(row["pan"]), float(row["tilt"]), float(row["roll"]))
    assert measure.angle_between(w[0], bench_real_photos.true_directions(row).up) > 45


# ------------------------------------------------------------------------------------------
# Angle errors
# ------------------------------------------------------------------------------------------


#: The York vectors are printed to six decimals: orthogonal to about 1e-6 radians.
PRINTED = 2e-4  # degrees


def truth_or_hand_worked() -> measure.SceneDirections:
    """The first York photo's truth where the data is present, else a hand-made pose."""
    if (YORK / "truth.csv").is_file():
        return bench_real_photos.true_directions(york_truth()[0])
    return measure.directions_from_pose(33.64, 12.85, -1.17)


@pytest.mark.parametrize("degrees", [0.25, 3.7, 20.0])
def test_turning_about_the_wall_normal_is_a_vertical_error_only(degrees):
    truth = truth_or_hand_worked()
    errors = measure.image_errors(turned(truth, truth.wall, degrees), truth)
    assert errors.vertical == pytest.approx(degrees, abs=PRINTED)
    assert errors.wall == pytest.approx(0.0, abs=PRINTED)


@pytest.mark.parametrize("degrees, expected", [(0.5, 0.5), (3.7, 3.7), (60.0, 30.0),
                                               (90.0, 0.0), (135.0, 45.0)])
def test_turning_about_up_moves_the_wall_toward_the_nearer_horizontal(degrees, expected):
    """Turned about the vertical by 60 degrees, the estimated normal is 30 from the other
    horizontal (the side wall's normal): the wall error is to the nearer one, as lines."""
    truth = truth_or_hand_worked()
    errors = measure.image_errors(turned(truth, truth.up, degrees), truth)
    assert errors.vertical == pytest.approx(0.0, abs=PRINTED)
    assert errors.wall == pytest.approx(expected, abs=PRINTED)


def test_a_pan_offset_is_a_wall_error_of_that_angle():
    """Pan turns about world up (the leftmost factor of W): an estimate whose pan is 5 degrees
    off has the right vertical and a wall 5 degrees off."""
    truth = measure.directions_from_pose(33.64, 12.85, -1.17)
    errors = measure.image_errors(measure.directions_from_pose(38.64, 12.85, -1.17), truth)
    assert errors.vertical == pytest.approx(0.0, abs=1e-9)
    assert errors.wall == pytest.approx(5.0, abs=1e-9)


def test_lines_are_symmetric_and_directions_are_not():
    rng = np.random.default_rng(23)
    for _ in range(20):
        a, b = rng.normal(size=3), rng.normal(size=3)
        angle = measure.angle_between(a, b)
        line = measure.angle_between_lines(a, b)
        assert line == pytest.approx(measure.angle_between_lines(b, a), abs=1e-12)
        assert line == pytest.approx(measure.angle_between_lines(-a, b), abs=1e-12)
        assert line == pytest.approx(min(angle, 180 - angle), abs=1e-12)
        assert measure.angle_between(-a, b) == pytest.approx(180 - angle, abs=1e-12)
        assert 0 <= line <= 90
    truth = truth_or_hand_worked()
    estimate = turned(truth, np.array([1.0, 2.0, 3.0]), 4.0)
    errors = measure.image_errors(estimate, truth)
    flipped_wall = measure.image_errors(estimate._replace(wall=-estimate.wall), truth)
    upside_down = measure.image_errors(estimate._replace(up=-estimate.up), truth)
    assert flipped_wall.wall == pytest.approx(errors.wall, abs=1e-12)
    assert upside_down.vertical == pytest.approx(180 - errors.vertical, abs=1e-12)


def test_tiny_angles_are_resolved():
    """atan2 of the cross and dot products: a thousandth of a degree is not lost to acos."""
    a = np.array([0.0, 0.0, 1.0])
    b = cv2.Rodrigues(np.array([math.radians(0.001), 0.0, 0.0]))[0] @ a
    assert measure.angle_between(a, b) == pytest.approx(0.001, rel=1e-6)


# ------------------------------------------------------------------------------------------
# Summaries and calibration bins
# ------------------------------------------------------------------------------------------


def test_no_estimate_counts_90_degrees_and_summaries():
    truth = truth_or_hand_worked()
    assert measure.image_errors(None, truth) == (90.0, 90.0)
    summary = measure.summarize([1.0, 2.0, 3.0, 4.0, 90.0])
    assert summary == (3.0, pytest.approx(55.6), 90.0)  # p90: 4 + 0.6 * (90 - 4)
    assert all(math.isnan(x) for x in measure.summarize([]))


def test_confidently_wrong():
    assert measure.is_confidently_wrong(True, measure.ImageErrors(3.01, 0.1))
    assert measure.is_confidently_wrong(True, measure.ImageErrors(0.1, 3.5))
    assert not measure.is_confidently_wrong(True, measure.ImageErrors(3.0, 3.0))
    assert not measure.is_confidently_wrong(False, measure.ImageErrors(90.0, 90.0))
    assert measure.is_within(measure.ImageErrors(2.0, 1.0))
    assert not measure.is_within(measure.ImageErrors(2.01, 1.0))


def test_calibration_bins():
    confidences = [0.1, 0.55, 0.55, 0.75, 0.9, 0.95, 1.0]
    within = [False, True, False, True, True, False, True]
    bins = measure.calibration_bins(confidences, within)
    assert [b.count for b in bins] == [1, 2, 0, 1, 0, 3]  # 0.9 and 1.0 in the last bin
    assert sum(b.count for b in bins) == len(confidences)
    assert bins[1].fraction_within == 0.5 and bins[1].mean_confidence == pytest.approx(0.55)
    assert bins[5].fraction_within == pytest.approx(2 / 3)
    assert math.isnan(bins[2].fraction_within)
    with pytest.raises(ValueError):
        measure.calibration_bins([0.5], [True, False])


# ------------------------------------------------------------------------------------------
# The other real photos (tests/data/real)
# ------------------------------------------------------------------------------------------


def test_other_photos_are_listed_documented_and_small():
    rows = read_table(REAL / "photos.csv")
    listed = {row["image"] for row in rows}
    assert listed == {p.name for p in REAL.glob("*.jpg")}
    readme = (REAL / "README.md").read_text()
    for row in rows:
        assert row["structure"] in ("none", "planar") and row["expected"] in ("refuse", "right")
        assert f"`{row['source'].split(':', 1)[1]}`" in readme, row["source"]
        image = cv2.imread(str(REAL / row["image"]), cv2.IMREAD_UNCHANGED)
        assert image is not None and max(image.shape[:2]) <= 640, row["image"]
        assert b"Exif" not in (REAL / row["image"]).read_bytes()[:4096], row["image"]
    assert {row["expected"] for row in rows if row["structure"] == "none"} == {"refuse"}
    assert sum(p.stat().st_size for p in REAL.iterdir()) < 3_000_000


# ------------------------------------------------------------------------------------------
# OpenCV's chessboard photos with their poses (tests/data/right*.jpg)
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(5))
def test_rodrigues_vectors_turn_as_opencv_turns_them(seed):
    rvec = np.random.default_rng(seed).normal(size=3)
    assert np.allclose(measure.rotation_from_rvec(rvec), cv2.Rodrigues(rvec)[0], atol=1e-12)
    assert np.array_equal(measure.rotation_from_rvec([0, 0, 0]), np.eye(3))


def test_a_board_has_no_up_of_its_own():
    """A board facing the camera squarely, turned 30 degrees in its plane: an estimate whose
    up is the board's y axis (turned so) is right, as is one whose up is its x axis; the wall
    normal is measured against the board's normal, as lines."""
    rvec = [0.0, 0.0, math.radians(30.0)]  # the board's x axis 30 degrees from the camera's x
    board_x = np.array([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0])
    board_y = np.array([-math.sin(math.radians(30)), math.cos(math.radians(30)), 0.0])
    for up in (board_x, -board_y):
        estimate = measure.SceneDirections(up, np.array([0.0, 0.0, -1.0]), np.cross(up, [0, 0, 1]))
        errors = measure.board_errors(estimate, rvec)
        assert errors.vertical < 1e-6 and errors.wall < 1e-6
    tilted = measure.SceneDirections(np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0]),
                                     np.array([1.0, 0.0, 0.0]))
    errors = measure.board_errors(tilted, rvec)
    assert errors.vertical == pytest.approx(30.0) and errors.wall < 1e-6
    assert measure.board_errors(None, rvec) == (measure.NO_ESTIMATE_DEG, measure.NO_ESTIMATE_DEG)


def test_segments_along_a_direction_are_told_by_where_they_vanish():
    """Segments projected by ``cv2.projectPoints`` along a scene direction meet in its
    vanishing point: :func:`measure.along_direction` picks them out, and not those along a
    direction 2 degrees from it (their ends miss by more than 1 px over 100 px and more)."""
    rng = np.random.default_rng(4)
    matrix = np.array([[600.0, 0, 320], [0, 600.0, 240], [0, 0, 1]])
    direction = np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])
    other = cv2.Rodrigues(np.radians([0.0, 0.0, 2.0]))[0] @ direction  # turned in the image
    starts = rng.uniform([-2, -2, 6], [2, 2, 10], size=(30, 3))

    def segments(along: np.ndarray) -> np.ndarray:
        points = np.vstack([starts, starts + 1.5 * along])
        pixels = cv2.projectPoints(points, np.zeros(3), np.zeros(3), matrix, None)[0]
        return np.hstack([pixels[:30, 0], pixels[30:, 0]])

    assert measure.along_direction(segments(direction), matrix, direction, 0.5).all()
    assert measure.along_direction(segments(direction), matrix, -direction, 0.5).all()
    drifted = segments(other)
    long_ones = np.hypot(*(drifted[:, 2:] - drifted[:, :2]).T) > 100
    assert long_ones.sum() >= 10
    assert not measure.along_direction(drifted[long_ones], matrix, direction, 1.0).any()


def test_chessboard_photos_are_right_or_refused():
    """``gsrwt estimate`` over OpenCV's 13 chessboard photos with their calibration file,
    each board's plane taken as the wall and measured against its pose (``cv2.solvePnP`` of its
    corners). 2026-12-03: 7 get a pose, all 7 within 2 degrees (vertical 0.10 to 0.49, wall
    0.32 to 1.12); none confidently wrong. ``right13`` was (7.1 and 13.6 degrees, confidence
    0.53): a frame of the board and one 13 degrees from it, which takes in the room behind,
    fit its lines equally well, and the tie went to the more upright; but the board is held
    22 degrees from level, and the frame's vertical is 30 degrees from the camera's up with
    another direction at 63: up with probability 0.91 only (``upright_probability``), which
    takes its confidence to 0.48, and it is refused (docs/REAL_PHOTOS.md). Floors at today's
    figures: they fail if the estimator gets worse (without the upright prior, by right13)."""
    boards = bench_real_photos.evaluate_chessboards()
    assert len(boards) == 13
    ok = [p for p in boards if p.status == "ok"]
    within = [p for p in ok if measure.is_within(measure.ImageErrors(p.vertical, p.wall))]
    assert len(ok) >= 7 and len(within) >= 7
    assert [p.image for p in boards if p.confidently_wrong] == []
    assert np.median([p.vertical for p in within]) < 0.5
    assert np.median([p.wall for p in within]) < 0.8
    assert all(p.error for p in boards if p.status != "ok")


def test_the_other_webcams_chessboard_photos_are_right_or_the_rooms():
    """OpenCV's left webcam's 13 chessboard photos (tests/data/left) with OpenCV's own
    calibration of it (``opencv4_left_intrinsics.yml``), measured as the right ones are.
    2026-12-03: 9 get a pose, 7 within 2 degrees of the board (vertical 0.06 to 0.37, wall
    0.21 to 0.63). left01 and left06 are 10.5 and 10.4 degrees off it (confidence 0.85 and
    0.69): their frame is the room's (the monitor's and the cabinet's verticals, the
    keyboard's and the desk's receding edges), and the board is held 10 and 24 degrees from
    the room's axes: which plane a photo's pose is of, its lines cannot tell. 2026-12-04:
    left14 (within 2) refused at 0.49, its normal's segments meeting no more than chance
    would (``false_alarms``): 8 and 6. Floors at today's figures."""
    boards = bench_real_photos.evaluate_chessboards(camera="left")
    assert len(boards) == 13
    ok = [p for p in boards if p.status == "ok"]
    within = [p for p in ok if measure.is_within(measure.ImageErrors(p.vertical, p.wall))]
    assert len(within) >= 6
    assert {p.image for p in boards if p.confidently_wrong} <= {"left01.jpg", "left06.jpg"}
    assert all(p.error for p in boards if p.status != "ok")


def test_chessboard_photos_with_no_camera_bend_and_are_refused_straightened_they_are_not(
        tmp_path):
    """The same 13 photos, and the other webcam's 13, with no camera given: their lenses
    bend straight edges (k1 -0.30 and -0.27 in their calibrations), the pinhole estimate
    takes bent pieces for directions and the focal length from vanishing points that are
    not there, and before the lens was looked for 6 right and 4 left were accepted 3.4 to 32
    degrees off the board (confidence 0.58 to 0.85). Now the lines' lens
    (:func:`~gsrwt_cli.api.lens_lines.lens_doubt`) turns right03, right06 and right09 by
    4.9 to 25 degrees and right02 and left08 by 2.05 and 2.8 (more than the 2 degrees the
    confidence is about), and left02, left05, left09 and right11 tell no pose straightened:
    they are refused for it. right11's pinhole estimate is 2097 px (537 true) and near
    frontal, 32 degrees off; k1 searched only to -0.5 at that focal length (-0.03 at its
    lens's) was not pinned down (-0.58 +- 0.99), and it was accepted until the search
    reached as far in pixels as at the long side (2026-12-04; k1 -2.6 +- 0.3 at 2097 px).
    right08 is still accepted and off: its straightened pose is within 2 degrees of the
    bent one (with a bar of 3 degrees right02 and left08 were too). Since a normal found only
    by chance counts as unseen (``false_alarms``; a board's edges recede nowhere), right09,
    right11, left05 and left09 are refused for their confidence (0.16 to 0.38) before the
    lens is looked for. Undistorted by
    OpenCV with their calibration and still given no camera, the lines show no lens: none is
    refused for it, and most of those accepted are within 2 degrees (7 accepted, 5 within;
    right05 is 6.6 off, the principal point taken as the centre is 12 px off; 2026-12-04,
    normals found only by chance counting as unseen: 4 accepted, all within 2 degrees)."""
    taken = bench_real_photos.evaluate_chessboards(calibrated=False)
    left = bench_real_photos.evaluate_chessboards(calibrated=False, camera="left")
    bent = {p.image for p in taken + left
            if p.error.startswith("the straight edges bend (the lines show a lens: k1 ")}
    assert {"right03.jpg", "right06.jpg", "left02.jpg", "left08.jpg"} <= bent
    unsure = {p.image for p in taken + left if p.error.startswith("confidence ")}
    assert {"right09.jpg", "right11.jpg", "left05.jpg", "left09.jpg"} <= bent | unsure
    assert all(p.error.endswith("give the camera's calibration (--camera)") for p in taken
               + left if p.image in bent)
    assert sum(p.confidently_wrong for p in taken + left) <= 1  # 2026-12-04: right08
    storage = cv2.FileStorage(str(DATA / "right_camera.yml"), cv2.FILE_STORAGE_READ)
    matrix = storage.getNode("camera_matrix").mat()
    distortion = storage.getNode("distortion_coefficients").mat()
    for board in taken:
        cv2.imwrite(str(tmp_path / board.image),
                    cv2.undistort(cv2.imread(str(DATA / board.image)), matrix, distortion),
                    [cv2.IMWRITE_JPEG_QUALITY, 95])
    (tmp_path / "right_poses.csv").write_bytes((DATA / "right_poses.csv").read_bytes())
    straightened = bench_real_photos.evaluate_chessboards(tmp_path, calibrated=False)
    assert not any(p.error.startswith("the straight edges bend") for p in straightened)
    ok = [p for p in straightened if p.status == "ok"]
    within = [p for p in ok if measure.is_within(measure.ImageErrors(p.vertical, p.wall))]
    assert len(ok) >= 4 and len(within) > len(ok) / 2


def test_chessboard_photos_with_an_exif_focal_length_and_no_lens_are_checked_for_one(
        tmp_path):
    """The 26 webcam photos as a photographer's camera would give them: an EXIF focal length
    (29 mm for 35 mm film, written with Pillow) and nothing of the lens. Refined by the
    segments but straight through the bent edges, 17 were accepted, 15 of them 3.0 to 22
    degrees off the board (confidence 0.57 to 0.87). An EXIF focal length says nothing of
    the lens, so these are checked as photos with no camera are: the lines' k1 (-0.19 to
    -0.37, against the calibrations' -0.30 and -0.27) turns 14 of them by more than 2 degrees
    or leaves no pose, and they are refused for it (2026-12-03: 3 accepted, all off: left01
    and left06 the room's frame, right12 at 3.0; with a bar of 3 degrees instead of 2, 6:
    right08, left08 and left14 too)."""
    from PIL import Image

    for camera in ("right", "left"):
        folder = bench_real_photos.BOARD_CAMERAS[camera][0]
        poses = folder / f"{camera}_poses.csv"
        (tmp_path / poses.name).write_bytes(poses.read_bytes())
        for row in read_table(poses):
            exif = Image.Exif()
            exif.get_ifd(0x8769)[0xA405] = 29  # FocalLengthIn35mmFilm
            Image.open(folder / row["image"]).save(tmp_path / row["image"], exif=exif,
                                                   quality=95)
    boards = [board for camera in ("right", "left") for board in
              bench_real_photos.evaluate_chessboards(tmp_path, calibrated=False, camera=camera)]
    bent = [board for board in boards if board.error.startswith("the straight edges bend")]
    assert len(bent) >= 10  # 12 until a normal found by chance counted as unseen (2026-12-04)
    assert sum(board.confidently_wrong for board in boards) <= 4
    (row,) = read_table(run_gsrwt("estimate", str(tmp_path / "right09.jpg"), "-f",
                                  "csv").stdout)
    assert row["focal_source"] == "exif+lines"  # the EXIF focal length was read
    assert row["error"].startswith("the straight edges bend (the lines show a lens: k1 -0.")


# ------------------------------------------------------------------------------------------
# The York Urban training half: EXIF removal, and today's figures as a floor
# ------------------------------------------------------------------------------------------


@needs_york
def test_strip_exif_keeps_the_pixels_and_drops_the_focal_length(tmp_path):
    original = (YORK / "images" / "P1020177.jpg").read_bytes()
    assert b"Exif" in original[:64]
    bare = bench_real_photos.strip_exif(original)
    assert b"Exif" not in bare and len(bare) < len(original)
    decode = lambda data: cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)  # noqa: E731
    assert np.array_equal(decode(bare), decode(original))


@pytest.fixture(scope="module")
def york_runs() -> list[bench_real_photos.RunResult]:
    if not (YORK / "truth.csv").is_file():
        pytest.skip(f"no York Urban data at {YORK}")
    return bench_real_photos.evaluate(YORK, jobs=1)


def accepted_errors(run: bench_real_photos.RunResult) -> tuple[measure.Summary, ...]:
    """Vertical and wall-normal errors over the photos the run gave a pose."""
    ok = [p for p in run.photos if p.status == "ok"]
    return (measure.summarize(p.vertical for p in ok), measure.summarize(p.wall for p in ok))


def test_york_with_the_calibrated_focal_length_is_no_worse_than_today(york_runs):
    """Issue 23, 2026-12-03: vertical 0.48 / 1.28 / 90 degrees (median, 90th percentile,
    worst; 0.48 / 1.24 / 3.40 over the 50 with a pose), wall normal 0.58 / 1.61 / 90 (0.57 /
    1.47 / 2.75), 1 refused (P1040822, whose frame's own segments disagree with it: 6.2
    degrees off the wall), 1 confidently wrong (P1030004), 46 of 51 within 2 degrees on both
    (before each direction was fitted alone and reconciled: vertical 0.52 / 1.94, wall 0.69 /
    1.83, 45; before the confidence weighed the frame's misfit: 2 confidently wrong, none
    refused; before the clutter tie-break: worst 8.20 and 13.47, 4 confidently wrong, 44).
    Floors a little below: they fail if the estimator gets worse (the vertical's 90th
    percentile fails without the reconciling)."""
    run = york_runs[0]
    assert run.name == "calibrated focal" and len(run.photos) == 51
    assert {p.focal_source for p in run.photos} == {"sidecar"}
    vertical, wall = accepted_errors(run)
    assert run.vertical.median < 0.6 and run.vertical.p90 < 1.6 and vertical.worst < 4.5
    assert run.wall.median < 0.75 and run.wall.p90 < 2.0 and wall.worst < 4.5
    assert len(run.refused) <= 2  # at least 95 % of the photos get a pose
    assert len(run.confidently_wrong) <= 1
    within = sum(measure.is_within(measure.ImageErrors(p.vertical, p.wall))
                 for p in run.photos)
    assert within >= 45


def test_york_without_a_focal_length_is_no_worse_than_today(york_runs):
    """2026-12-03: 8 refused (5 cannot tell the focal length, 2 whose focal length does not
    pin the pose to 3 degrees, 1 below the confidence bar), vertical median 0.87, wall median
    1.15 degrees, 1 confidently wrong (P1030004, 4.15 and 3.35: with the focal length given
    it is too, its labelled segments' own frame 3 degrees off the truth), 36 of 51 within 2
    degrees on both, the focal length 2.0 % off at the median. Before the focal length was
    settled where the refitted frame fits best (:func:`~gsrwt_cli.api.estimate.
    settle_focal`): 10 refused, 1 confidently wrong (P1080015: 775 px for 675, 3.51 and
    4.70 degrees; now 679 px and within 2.2), 35 within, 2.5 %; before each direction was
    fitted alone and reconciled, 2 confidently wrong; 4 before the confidence weighed the
    frame's misfit, 7 before the refusals."""
    run = york_runs[1]
    assert run.name.startswith("no focal")
    assert {p.focal_source for p in run.photos} == {"estimated"}
    assert len(run.refused) <= 10
    assert run.vertical.median < 1.1 and run.wall.median < 1.4
    assert len(run.confidently_wrong) <= 1
    assert sum(measure.is_within(measure.ImageErrors(p.vertical, p.wall))
               for p in run.photos) >= 34
    assert run.focal_errors().median < 3.5


def test_york_as_taken_with_the_exif_focal_length(york_runs):
    """The photos as a photographer gives them: the focal length from their EXIF (4.1 % short
    of the calibrated one), the principal point the image's centre (13 px off the calibrated
    one). The EXIF focal length is refined by the segments where they pin it
    (``focal_source`` ``exif+lines``). 2026-12-03: none refused; 1 confidently wrong
    (P1030004, 4.11 degrees; its labelled segments' own orthogonal frame is itself 3 degrees
    off the truth: docs/REAL_PHOTOS.md); 42 of 51 within 2 degrees on both; vertical 0.69 /
    1.94 / 4.11, wall 0.99 / 2.09 / 3.33; the focal length 2.1 % off at the median. Taken as
    exact (before): 2 refused, 3 confidently wrong, 36 within, vertical 0.65 / 2.11 / 90, wall
    1.17 / 2.49 / 90."""
    run = york_runs[2]
    assert run.name.startswith("EXIF focal")
    assert {p.focal_source for p in run.photos} == {"exif+lines"}
    assert len(run.refused) <= 2  # at least 95 % of the photos get a pose
    assert len(run.confidently_wrong) <= 2
    assert run.vertical.median < 0.8 and run.wall.median < 1.2
    assert run.vertical.p90 < 2.2 and run.wall.p90 < 2.3
    assert sum(measure.is_within(measure.ImageErrors(p.vertical, p.wall))
               for p in run.photos) >= 40
    assert run.focal_errors().median < 3.0


@needs_york
def test_york_photos_smaller_than_taken_are_refused_more_not_trusted_more():
    """The York photos shrunk to 480x360 and 320x240 with their focal length scaled
    (2026-12-03: 4 and 29 of 51 refused, 1 confidently wrong each, P1030004 and P1080015 at
    0.50): the distances set at 640x480 admit a wider angle in a smaller photo, so more is
    refused as having no structure, and what is accepted is as often right as at full size."""
    for run, most_refused in zip(bench_real_photos.evaluate_smaller(YORK), (6, 35)):
        ok = [p for p in run.photos if p.status == "ok"]
        within = [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok]
        assert sum(p.status != "ok" for p in run.photos) <= most_refused, run.name
        assert len(run.confidently_wrong) <= 1, run.name
        assert np.mean(within) >= 0.85, run.name


@pytest.mark.parametrize("enlarge", [False, True])
def test_a_telephoto_view_sees_the_points_where_the_photo_does(enlarge):
    """:func:`bench_real_photos.telephoto_view`: points projected by ``cv2.projectPoints``
    through the photo's camera and through the view's land where the crop (and the resize)
    put the photo's pixels, and a dot drawn in the photo appears there in the view."""
    from gsrwt_cli.geometry.camera import Intrinsics

    camera = Intrinsics(674.9, 674.9, 307.6, 251.5, width=640, height=480)
    photo = np.zeros((480, 640), np.uint8)
    cv2.circle(photo, (300, 240), 4, 255, -1)
    points = np.random.default_rng(3).uniform([-1, -1, 4], [1, 1, 6], (20, 3))
    rvec, tvec = np.array([0.05, -0.2, 0.03]), np.array([0.1, -0.05, 0.3])

    def seen(cam: Intrinsics) -> np.ndarray:
        matrix = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1.0]])
        return cv2.projectPoints(points, rvec, tvec, matrix, None)[0][:, 0]

    for fraction in (0.7, 0.5, 1 / 3):
        view, lens = bench_real_photos.telephoto_view(photo, camera, fraction, enlarge)
        left, top = round(camera.cx - round(640 * fraction) / 2), round(
            camera.cy - round(480 * fraction) / 2)
        scale = 640 / round(640 * fraction) if enlarge else 1.0
        expected = (seen(camera) - [left, top] + 0.5) * scale - 0.5
        assert np.abs(seen(lens) - expected).max() < 1e-9
        assert view.shape == ((480, 640) if enlarge else (round(480 * fraction),
                                                          round(640 * fraction)))
        dot = np.argwhere(view > 128).mean(axis=0)[::-1]  # (x, y)
        assert np.abs(dot - ((np.array([300, 240]) - [left, top] + 0.5) * scale - 0.5)).max() < 0.6
        assert lens.focal / max(lens.width, lens.height) == pytest.approx(
            674.9 / 640 / fraction, rel=0.01)


@needs_york
def test_york_photos_seen_through_a_longer_lens_are_no_worse_than_today():
    """The York photos cropped around their principal point to 0.7, 1/2, 0.4 and 1/3 of their
    sides (1.5 to 3.2 long sides of focal length), as cropped and enlarged back to 640x480.
    2026-12-04: the estimator is much less sure of them, and not yet honest there. Confidently
    wrong per run: 1, 4, 3, 2, 4, 3, 1, 8 at first (the enlarged crops at 3.2 long sides: 29
    accepted, 8 of them more than 3 degrees off, nearly all in the wall's normal: its
    horizontals converge too little at that focal length, and short pieces of clutter meeting
    near the middle passed for the edges receding from the camera); 1, 4, 2, 2, 0, 3, 0, 5
    once a normal found only by chance is taken as unseen (``false_alarms``): 17 in all. A
    ceiling, not a goal: fewer is better. LSD's segments come from floating-point code, and
    a photo on the edge of 3 degrees may tip on another CPU: each run may have one more, and
    all of them two more, than today (the old counts, 25 in all, fail)."""
    ceilings = (1, 4, 2, 2, 0, 3, 0, 5)
    runs = bench_real_photos.evaluate_telephoto(YORK)
    counts = [len(run.confidently_wrong) for run in runs]
    assert all(count <= most + 1 for count, most in zip(counts, ceilings)), counts
    assert sum(counts) <= sum(ceilings) + 2, counts


@needs_york
def test_york_photos_altered_on_their_way_are_right_or_refused():
    """The York photos re-encoded at JPEG quality 60, with noise of 4 grey levels, blurred by
    1 px, their shadows brightened (gamma 0.6) and underexposed (x0.35): the same scenes in
    pixels that differ as another photographer's would. 2026-12-04: confidently wrong 2, 1,
    1, 1, 1 (`P1030004` in each, whose labelled segments' own frame is 3 degrees off its
    truth; `P1040822` re-encoded, at 0.51: as taken it is refused at 0.06), refused 0, 2, 3,
    1, 2, within 2 degrees 45, 45, 45, 47, 43 of 51, and the mean confidence below the
    fraction within in each (0.86 to 0.87 against 0.88 to 0.94). Ceilings one over today's (a
    photo sits at 0.51, one at 2.9 degrees), floors one under, and the confidence at most 0.05
    above the fraction within: not trusted more than it is right."""
    runs = bench_real_photos.evaluate_altered(YORK)
    assert [run.name for run in runs] == list(bench_real_photos.ALTERATIONS)
    for run, most_wrong in zip(runs, (2, 1, 1, 1, 1)):
        ok = [p for p in run.photos if p.status == "ok"]
        within = [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok]
        assert len(run.confidently_wrong) <= most_wrong + 1, run.name
        assert len(run.refused) <= 4 and sum(within) >= 42, run.name
        assert np.mean([p.confidence for p in ok]) <= np.mean(within) + 0.05, run.name


@needs_york
def test_york_photos_altered_as_a_photographer_gives_them_are_right_or_refused():
    """The same alterations, the photos given as a photographer gives them: the EXIF focal
    length (4 % short) refined by the segments, the principal point the image's centre (13 px
    off), each estimate checked for a lens as ``gsrwt estimate`` checks it. 2026-12-04:
    confidently wrong 1, 2, 1, 1, 2 (`P1030004` in each, `P1040822` at 3.3 and 4.4 degrees
    with noise and underexposed), refused 1, 1, 3, 2, 1, within 2 degrees 41, 40, 41, 41, 42
    of 51 (as taken: 1, 0 and 42), the mean confidence 0.01 to 0.04 above the fraction
    within in four. Ceilings one over today's (`P1080018` sits at 2.99 degrees blurred),
    floors one under, the confidence at most 0.06 above the fraction within."""
    runs = bench_real_photos.evaluate_altered(YORK, exif=True)
    for run, most_wrong in zip(runs, (1, 2, 1, 1, 2)):
        ok = [p for p in run.photos if p.status == "ok"]
        within = [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok]
        assert {p.focal_source for p in run.photos} == {"exif+lines"}, run.name
        assert len(run.confidently_wrong) <= most_wrong + 1, run.name
        assert len(run.refused) <= 4 and sum(within) >= 39, run.name
        assert np.mean([p.confidence for p in ok]) <= np.mean(within) + 0.06, run.name


def test_an_alteration_keeps_the_photo_as_it_was_taken():
    """The alterations change pixel values only: size and type kept, the same twice (the
    noise is seeded), the noise of the spread its name gives and the underexposure the
    scaling."""
    photo = cv2.imread(str(DATA / "facade" / "building.jpg"))
    for name, alter in bench_real_photos.ALTERATIONS.items():
        altered = alter(photo, 7)
        assert altered.shape == photo.shape and altered.dtype == np.uint8, name
        assert np.array_equal(altered, alter(photo, 7)), name
    difference = bench_real_photos.ALTERATIONS["noise 4 grey levels"](photo, 7).astype(
        float) - photo
    assert 3.5 < difference[(photo > 20) & (photo < 235)].std() < 4.5
    dark = bench_real_photos.ALTERATIONS["underexposed (x0.35)"](photo, 0)
    assert np.abs(dark - 0.35 * photo).max() <= 0.5


@needs_york
def test_york_walls_seen_frontally_are_right_or_less_sure():
    """The York photos seen as walls about frontally (their receding edges left out) and as
    corridors (their wall's horizontals left out), the focal length given. 2026-12-03, walls
    seen frontally: 43 of 51 get a pose, 32 of them within 2 degrees, 4 confidently wrong
    (7 before the misfit weighed the wall's horizontal where no edge recedes and the
    confidence's offset for such walls, 5 before a direction was found only through segments
    no other direction explains); the mean confidence 0.743 against 0.744 within (0.79
    against 0.70 at first). Corridors: 48, 43, 2; 0.839 against 0.896. The frontal walls'
    ceiling is one over today's: `P1080023` sits at 2.95 degrees, 0.05 from the bar, and may
    tip on another CPU (LSD's segments come from floating-point code)."""
    frontal, corridor = bench_real_photos.evaluate_two_directions(YORK)
    for run, least_ok, least_within, most_wrong in ((frontal, 42, 31, 5),
                                                     (corridor, 46, 42, 2)):
        ok = [p for p in run.photos if p.status == "ok"]
        within = [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok]
        assert len(ok) >= least_ok and sum(within) >= least_within, run.name
        assert len(run.confidently_wrong) <= most_wrong, run.name
        assert abs(np.mean([p.confidence for p in ok]) - np.mean(within)) < 0.06, run.name


def test_york_confidence_is_the_chance_of_being_within_2_degrees(york_runs):
    """The confidence is calibrated (benchmarks/calibrate_confidence.py): over the photos with
    a pose, its mean is the fraction within 2 degrees on both measures, and its Brier score
    (mean squared difference from 1 within, 0 not) is low. 2026-12-03: mean 0.875 against 0.920
    within and Brier 0.078 with the focal length; 0.837 against 0.854 and 0.129 without (the
    upright prior takes 0.005 off each mean: the photos' verticals are all plainly up; before
    each direction was fitted alone and reconciled: 0.88 against 0.90, 0.086; 0.84 against
    0.83, 0.142; before the frame's misfit: 0.86 against 0.88, 0.097; 0.81 against 0.79,
    0.158; the first confidence: 0.92 against 0.86, 0.121; 0.92 against 0.74, 0.218)."""
    for run, brier in zip(york_runs, (0.10, 0.16)):
        ok = [p for p in run.photos if p.status == "ok"]
        within = [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok]
        confidences = [p.confidence for p in ok]
        assert abs(np.mean(confidences) - np.mean(within)) < 0.05, run.name
        assert np.mean((np.array(confidences) - np.array(within)) ** 2) < brier, run.name
