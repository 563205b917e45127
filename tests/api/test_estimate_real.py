"""A real photo nobody here made: OpenCV's ``building.jpg`` (tests/data/README.md), a facade
seen at an angle, rectified by ``gsrwt rectify --auto`` with no focal length given.

Measured in the output: the floors' long horizontal edges (LSD) must be horizontal, the
columns of dark gaps between the facade's panels vertical (their positions floor by floor),
and the panels of each floor equally wide (their front edges' spacing in the left half of a
row against the right half).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

BUILDING = DATA / "facade" / "building.jpg"


def segments(grey: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """LSD segments, their lengths and their angles from the horizontal (degrees, -90..90)."""
    lines = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD).detect(grey)[0].reshape(-1, 4)
    delta = lines[:, 2:] - lines[:, :2]
    angle = (np.degrees(np.arctan2(delta[:, 1], delta[:, 0])) + 90) % 180 - 90
    return lines, np.hypot(delta[:, 0], delta[:, 1]), angle


def floors(lines: np.ndarray, lengths: np.ndarray, angles: np.ndarray, width: int
           ) -> tuple[list[float], np.ndarray]:
    """Rows of the long horizontal edges (clustered within 8 px) and those edges' angles."""
    long = (lengths > 0.1 * width) & (np.abs(angles) < 5)
    rows = np.sort((lines[long, 1] + lines[long, 3]) / 2)
    clusters: list[list[float]] = []
    for row in rows:
        if clusters and row - clusters[-1][-1] <= 8:
            clusters[-1].append(row)
        else:
            clusters.append([row])
    return [float(np.mean(c)) for c in clusters], angles[long]


def middle_profile(grey: np.ndarray, top: float, bottom: float) -> np.ndarray:
    """Mean grey of each column over the middle half of one floor."""
    band = grey[int(top + 0.25 * (bottom - top)):int(bottom - 0.25 * (bottom - top))]
    return band.astype(np.float64).mean(axis=0)


def band_profile(grey: np.ndarray, top: float, bottom: float) -> np.ndarray:
    """:func:`middle_profile` with its slow trend removed."""
    profile = middle_profile(grey, top, bottom)
    return profile - np.convolve(profile, np.ones(151) / 151, "same")


def panel_edges(profile: np.ndarray, separation: int = 30) -> np.ndarray:
    """Columns of the panels' left front edges: the sharpest rises of a floor's profile
    (dark recess to the white face, left to right), each the steepest within ``separation``
    pixels and at least 40 % of the row's steepest, to a tenth of a pixel.

    The panels stand proud of the recesses between them, so the recesses show more of their
    windows toward the near end of the facade and their darkest column is no fixed point on
    the wall; a panel's front edge is, and all of them lie in one plane parallel to the wall.
    Seen from the facade's right, the left edges are the sharp ones (the right edges have the
    panel's own side beyond them)."""
    slope = np.gradient(np.convolve(profile, np.ones(3) / 3, "same"))
    least = 0.4 * np.percentile(slope, 99.5)
    found = [x for x in range(separation, len(slope) - separation)
             if slope[x] == slope[x - separation:x + separation + 1].max() and slope[x] > least]
    return np.array([x + _vertex(slope[x - 1:x + 2]) for x in found])


def _vertex(three: np.ndarray) -> float:
    """Where a parabola through three neighbouring values has its extremum (-0.5 to 0.5)."""
    a, b, c = three
    curvature = a - 2 * b + c
    return float(np.clip(0.5 * (a - c) / curvature, -0.5, 0.5)) if curvature else 0.0


def panel_pitch(edges: np.ndarray) -> float | None:
    """The width of the panels whose edges are ``edges`` (sorted columns): the least-squares
    slope of column against panel number, the panel numbers counted from the spacings (in
    the usual spacing, the median of the shorter ones: a missed edge doubles one), and edges
    more than 8 % of a panel off that lattice (a window's edge) left out.
    None with fewer than three edges on it."""
    if len(edges) < 3:
        return None
    spacing = np.diff(edges)
    pitch = float(np.median(spacing[spacing <= 1.5 * np.percentile(spacing, 25)]))
    number = np.concatenate([[0.0], np.cumsum(np.round(spacing / pitch))])
    on_lattice = np.ones(len(edges), dtype=bool)
    for _ in range(3):
        start = np.median(edges[on_lattice] - pitch * number[on_lattice])
        on_lattice = np.abs(edges - start - pitch * number) < 0.08 * pitch
        if on_lattice.sum() < 3 or np.ptp(number[on_lattice]) == 0:
            return None
        pitch = float(np.polyfit(number[on_lattice], edges[on_lattice], 1)[0])
    return pitch


def _peak(values: np.ndarray, lags: np.ndarray) -> float:
    """The lag of the largest value, refined by a parabola through it and its neighbours."""
    k = int(np.argmax(values[1:-1])) + 1
    a, b, c = values[k - 1], values[k], values[k + 1]
    offset = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
    return float(lags[k] + offset)


def shift(upper: np.ndarray, lower: np.ndarray, most: int = 15) -> float:
    """How many pixels right the lower floor's profile lies of the upper one's."""
    lags = np.arange(-most, most + 1)
    core = slice(most, len(upper) - most)
    values = np.array([np.dot(upper[core], np.roll(lower, -lag)[core]) for lag in lags])
    return _peak(values, lags)


def facade_floors(grey: np.ndarray) -> list[tuple[float, float]]:
    """The floors of panels: bands between consecutive long horizontal edges, 5-15 % of the
    image's height apart."""
    lines, lengths, angles = segments(grey)
    rows, _ = floors(lines, lengths, angles, grey.shape[1])
    return [(top, bottom) for top, bottom in zip(rows[:-1], rows[1:])
            if 0.05 * grey.shape[0] < bottom - top < 0.15 * grey.shape[0]]


def facade_columns(grey: np.ndarray, band: tuple[float, float]) -> tuple[int, int]:
    """The columns of the panels in one floor: where the floors' long edges run (their ends'
    quartiles), and the floor has picture (no fill)."""
    lines, lengths, angles = segments(grey)
    long = (lengths > 0.1 * grey.shape[1]) & (np.abs(angles) < 5)
    left = np.minimum(lines[long, 0], lines[long, 2])
    right = np.maximum(lines[long, 0], lines[long, 2])
    first, last = int(np.percentile(left, 25)), int(np.percentile(right, 75))
    covered = grey[int(band[0]):int(band[1])].min(axis=0) > 8
    columns = np.flatnonzero(covered[first:last]) + first
    return int(columns.min()), int(columns.max())


@pytest.fixture(scope="module")
def rectified(tmp_path_factory) -> tuple[np.ndarray, dict[str, str]]:
    out = tmp_path_factory.mktemp("building")
    result = run_gsrwt("rectify", str(BUILDING), "--auto", "--bbox", "full", "--max-size",
                       "1600x1200", "-o", str(out / "out"), "--table", str(out / "table.csv"))
    assert result.returncode == 0, result.stderr
    (row,) = read_table(out / "table.csv")
    return cv2.imread(str(out / "out" / "building.jpg"), cv2.IMREAD_GRAYSCALE), row


def test_the_pose_and_focal_length_are_estimated(rectified):
    _, row = rectified
    assert row["pose_source"] == "estimated" and row["focal_source"] == "estimated"
    assert float(row["confidence"]) > 0.5  # the chance of being within 2 degrees
    assert 45 < float(row["pan_deg"]) < 70  # the facade, seen from its right


def test_estimate_reports_the_more_frontal_plane_and_rectify_auto_the_facade(tmp_path):
    """The two defaults differ on purpose (docs/COMMANDS.md): ``estimate`` reports the wall
    most frontal (the building's end, |pan| <= 45), ``rectify --auto`` the plane with the
    more horizontal edges (the facade); each command's ``--wall`` gives the other's choice."""
    def pan(*args: str) -> float:
        result = run_gsrwt("estimate", str(BUILDING), "-f", "csv", *args)
        assert result.returncode == 0, result.stderr
        (row,) = read_table(result.stdout)
        return float(row["pan"])

    frontal, dominant = pan(), pan("--wall", "dominant")
    assert abs(frontal) <= 45 and 45 < dominant < 70
    assert abs(abs(dominant - frontal) - 90) < 1e-6
    result = run_gsrwt("rectify", str(BUILDING), "--auto", "--wall", "frontal", "-o",
                       str(tmp_path / "out"), "--table", "-", "-q")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout)
    assert float(row["pan_deg"]) == pytest.approx(frontal, abs=1e-4)


def test_rows_are_horizontal_and_columns_vertical_within_half_a_degree(rectified):
    grey, _ = rectified
    lines, lengths, angles = segments(grey)
    _, horizontal = floors(lines, lengths, angles, grey.shape[1])
    assert len(horizontal) >= 10
    assert abs(np.median(horizontal)) <= 0.5
    bands = facade_floors(grey)
    assert len(bands) >= 3
    first = max(facade_columns(grey, band)[0] for band in bands)
    last = min(facade_columns(grey, band)[1] for band in bands)
    profiles = [band_profile(grey, *band)[first:last] for band in bands]
    leans = [math.degrees(math.atan2(shift(upper, lower), (b2[0] + b2[1] - b1[0] - b1[1]) / 2))
             for upper, lower, b1, b2 in zip(profiles, profiles[1:], bands, bands[1:])]
    assert abs(np.median(leans)) <= 0.5


def half_row_ratio(edges: np.ndarray) -> float | None:
    """The panels' width in the right half of a row over the left half's, minus 1 (0 when
    they are equal); None when a half has too few edges on its lattice."""
    middle = np.median(edges)
    left, right = panel_pitch(edges[edges <= middle]), panel_pitch(edges[edges >= middle])
    return None if left is None or right is None else right / left - 1


def row_width_ratios(grey: np.ndarray) -> list[float]:
    """:func:`half_row_ratio` of every floor with six or more panel edges."""
    ratios = []
    for top, bottom in facade_floors(grey):
        edges = panel_edges(middle_profile(grey, top, bottom))
        ratio = half_row_ratio(edges) if len(edges) >= 6 else None
        if ratio is not None:
            ratios.append(ratio)
    return ratios


def test_panels_along_a_row_are_equally_wide(rectified):
    """The issue's goal: equal within 2 % along a row. Measured: 0.8, -1.8 and -0.9 % on the
    three floors with six or more panel edges on their lattice (in the photo: 57 % on the
    third). Before each direction was fitted alone and reconciled, the pan 0.15 degrees
    smaller: 1.0, -0.4, -0.8 and 0.5 % on four; the measure moves that much within a few
    tenths of a degree of pan either way (58.4: 1.7, -0.6, -0.1, 0.3 %; 58.9: 0.5, -0.7,
    -0.3 %), and a floor drops out or comes back as a lattice fits or not."""
    grey, _ = rectified
    ratios = row_width_ratios(grey)
    assert len(ratios) >= 3
    assert max(np.abs(ratios)) <= 0.02


def test_the_measure_tells_a_pan_one_degree_off(rectified, tmp_path):
    """The same measure on the facade rectified with the estimated pose but the pan one
    degree off either way: the panels shrink toward one end (measured: 1.0-4.9 %, medians
    2.6 and 3.7 %), so the 2 % goal holds the pan to about half a degree (at +-0.5 degrees:
    2.5 % at worst)."""
    _, row = rectified
    for offset, sign in ((-1.0, 1), (1.0, -1)):
        out = tmp_path / f"pan{offset:+}"
        result = run_gsrwt("rectify", str(BUILDING), "--pan", str(float(row["pan_deg"]) + offset),
                           "--tilt", row["tilt_deg"], "--roll", row["roll_deg"], "--focal",
                           row["focal_px"], "--bbox", "full", "--max-size", "1600x1200", "-o",
                           str(out), "-q")
        assert result.returncode == 0, result.stderr
        ratios = np.array(row_width_ratios(cv2.imread(str(out / "building.jpg"),
                                                      cv2.IMREAD_GRAYSCALE)))
        assert len(ratios) >= 3
        assert np.median(sign * ratios) > 0.015 and max(np.abs(ratios)) > 0.025


def test_the_measure_can_fail_on_the_photo_itself():
    """In the photo as taken the floors slope and the panels shrink toward the far end."""
    grey = cv2.imread(str(BUILDING), cv2.IMREAD_GRAYSCALE)
    lines, lengths, angles = segments(grey)
    _, horizontal = floors(lines, lengths, angles, grey.shape[1])
    assert len(horizontal) == 0 or abs(np.median(horizontal)) > 0.5
    edges = panel_edges(grey[200:230].mean(axis=0), separation=15)  # the third floor
    spacing = np.diff(edges)
    middle = (edges[:-1] + edges[1:]) / 2
    half = np.median(middle)
    assert np.median(spacing[middle >= half]) / np.median(spacing[middle < half]) - 1 > 0.3


def test_the_lens_is_removed_on_real_photos_of_a_chessboard():
    """OpenCV's right*.jpg (tests/data/README.md: a chessboard held in a room, k1 = -0.30,
    board poses from solvePnP): with the calibrated lens taken off the segments' end points,
    one of the three directions found is the board's normal within a degree in most photos;
    through a pinhole it is several degrees off. (The room's own lines are a second
    Manhattan frame, tilted against the board: in a few photos they win.)"""
    from dataclasses import replace

    from gsrwt_cli.api.estimate import estimate_pose
    from gsrwt_cli.inputs.records import load_camera_file
    from tests.helpers.estimate_scenes import C, angle_between

    data = BUILDING.parent.parent
    camera = load_camera_file(str(data / "right_camera.yml"))
    with_lens, pinhole, refused = [], [], []
    for row in read_table(data / "right_poses.csv"):
        image = cv2.imread(str(data / row["image"]))
        rvec = np.array([float(row[name]) for name in ("rvec_x", "rvec_y", "rvec_z")])
        normal = C @ cv2.Rodrigues(rvec)[0][:, 2]  # the board's z axis, thesis frame
        for errors, used in ((with_lens, camera), (pinhole, replace(camera, lens=None))):
            estimate = estimate_pose(image, used)
            if not estimate.ok:  # right07: a board tilted 30 degrees against the room
                assert estimate.error.startswith("no clear man-made structure")
                refused.append((row["image"], used is camera))
                continue
            errors.append(min(angle_between(axis, normal)
                              for axis in estimate.world_from_camera))
    # refused with the lens removed: right07 at most; through a pinhole the lines are curved
    assert sum(with_lens_used for _, with_lens_used in refused) <= 1, refused
    assert np.median(with_lens) < 1.0
    assert np.median(pinhole) > 4.0
