"""``params``, ``estimate``, ``lines``, ``match`` and ``track`` on a video: real videos written
by PyAV (FFV1 in Matroska, lossless) from renders of independent cameras with known poses;
a row per frame, the same numbers as the command gives a still image of the same pose, a
file cut short, frames without a pose, and usage errors."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.helpers.camera import camera_axes, project_wall_points, render_view
from tests.helpers.cli import run_gsrwt
from tests.helpers.estimate_scenes import render_room
from tests.helpers.images import smooth_texture
from tests.helpers.paths import ROOT
from tests.helpers.tables import read_table

pytest.importorskip("av")

from tests.helpers.videos import (  # noqa: E402  (needs PyAV and scipy, checked above)
    render_sweep,
    slerped_poses,
    write_pose_log,
    write_video,
)

pytestmark = pytest.mark.slow

WIDTH, HEIGHT, FOCAL = 320, 240, 300.0
COUNT = 9
KNOB = ROOT / "sample_data" / "templates" / "knob.png"
#: The render's wall: ``Z = DISTANCE``, one texel per ``DISTANCE / FOCAL`` (frontal scale).
DISTANCE = 10.0
#: Where the knob's centre is on the wall (X up, Y right, render units).
KNOB_WALL = np.array([1.6, -2.4])


@pytest.fixture(scope="module")
def sweep(tmp_path_factory: pytest.TempPathFactory):
    """A pan-tilt sweep's video (FFV1) and pose log, its frames' times and true poses."""
    folder = tmp_path_factory.mktemp("sweep")
    frames, pts, _, key_times, key_poses = render_sweep(COUNT, WIDTH, HEIGHT, FOCAL,
                                                        key_every=4)
    video, log = folder / "walk.mkv", folder / "poses.csv"
    write_video(video, frames, pts)
    write_pose_log(log, key_times, key_poses)
    times = np.array(pts) / 1000
    return video, log, times, slerped_poses(key_times, key_poses, times)


def test_params_per_frame_are_params_of_each_frame_as_a_still(tmp_path: Path, sweep) -> None:
    """Each frame's row is ``gsrwt params`` of a still view at that frame's pose (scipy's
    slerp of the pose log), compared with a tolerance: two slerps, two code paths."""
    video, log, times, poses = sweep
    result = run_gsrwt("params", video, "--poses", log, "--focal", str(FOCAL), "-f", "csv")
    assert result.returncode == 0, result.stderr
    rows = read_table(result.stdout)
    assert list(rows[0])[:3] == ["frame", "time", "image"]
    assert list(rows[0])[-2:] == ["status", "error"]
    assert [int(row["frame"]) for row in rows] == list(range(COUNT))
    assert [float(row["time"]) for row in rows] == pytest.approx(times, abs=1e-6)
    sidecar = ["image,pan,tilt,roll,focal,width,height"]
    sidecar += [f"{i}.png,{pan!r},{tilt!r},{roll!r},{FOCAL},{WIDTH},{HEIGHT}"
                for i, (pan, tilt, roll) in enumerate(poses.tolist())]
    (tmp_path / "views.csv").write_text("\n".join(sidecar) + "\n")
    still = run_gsrwt("params", "--sidecar", tmp_path / "views.csv", "-f", "csv")
    assert still.returncode == 0, still.stderr
    for row, known in zip(rows, read_table(still.stdout), strict=True):
        assert row["status"] == "ok" and row["image"] == str(video)
        for name, value in known.items():
            if name == "image":
                continue
            if value in ("", "true", "false"):
                assert row[name] == value, name
            else:
                assert float(row[name]) == pytest.approx(float(value), rel=1e-5, abs=1e-5), name


def test_estimate_per_frame_recovers_each_frames_pose(tmp_path: Path) -> None:
    """Rooms rendered through OpenCV's own projection at known poses, one per frame: each
    frame's estimate is within 0.5 degree (the tolerance of the still room in
    tests/cli/test_estimate.py), in one process or on workers."""
    poses = [(20, -8, 3), (12, -4, 2), (5, 0, 0), (-3, 4, -1), (-10, 8, -2)]
    frames = [render_room(pan, tilt, roll, focal=520, seed=4).image
              for pan, tilt, roll in poses]
    video = tmp_path / "room.mkv"
    write_video(video, frames, [index * 100 for index in range(len(frames))])
    result = run_gsrwt("estimate", video, "--focal", "520", "-o", tmp_path / "poses.csv")
    assert result.returncode == 0, result.stderr
    assert "5 frames estimated, 0 failed" in result.stderr
    rows = read_table(tmp_path / "poses.csv")
    assert [(int(row["frame"]), float(row["time"])) for row in rows] == [
        (index, index / 10) for index in range(len(poses))]
    for row, (pan, tilt, roll) in zip(rows, poses, strict=True):
        assert row["status"] == "ok" and row["focal_source"] == "option"
        assert float(row["pan"]) == pytest.approx(pan, abs=0.5)
        assert float(row["tilt"]) == pytest.approx(tilt, abs=0.5)
        assert float(row["roll"]) == pytest.approx(roll, abs=0.5)
    # Two worker processes (the frames still decoded by the command): the same rows.
    result = run_gsrwt("estimate", video, "--focal", "520", "-j", "2", "-f", "csv")
    assert result.returncode == 0, result.stderr
    assert read_table(result.stdout) == rows


def _knob_texture() -> tuple[np.ndarray, tuple[float, float]]:
    """A quiet wall with the sample knob on it at frontal scale (one texel per
    ``DISTANCE / FOCAL``), and the knob's centre in texels (col, row)."""
    texture = smooth_texture(900, 1200, seed=5)
    texture = (128 + (texture.astype(np.int16) - 128) // 4).astype(np.uint8)  # low contrast
    knob = cv2.imread(str(KNOB))
    unit = DISTANCE / FOCAL
    th, tw = texture.shape[:2]
    col = (KNOB_WALL[1] / unit) + (tw - 1) / 2  # the render's texel of a wall point
    row = (th - 1) / 2 - KNOB_WALL[0] / unit
    height, width = knob.shape[:2]
    top, left = round(row - (height - 1) / 2), round(col - (width - 1) / 2)
    texture[top:top + height, left:left + width] = knob
    return texture, (left + (width - 1) / 2, top + (height - 1) / 2)


def test_track_follows_a_landmark_and_its_gaze_commands_centre_it(tmp_path: Path) -> None:
    """A knob on the wall, seen from a pan-tilt sweep: each frame's match is where the
    independent camera projects the knob (within 1 px; 0.3 px measured), and the command
    (pan_deg, tilt_deg) turns that camera's optical axis within 0.2 degree of the true
    direction to the knob, so that it lands within 1 px of the principal point (0.3 px
    measured)."""
    texture, (col, row) = _knob_texture()
    unit = DISTANCE / FOCAL
    th, tw = texture.shape[:2]
    wall = np.array([[((th - 1) / 2 - row) * unit, (col - (tw - 1) / 2) * unit]])
    assert wall[0] == pytest.approx(KNOB_WALL, abs=unit)
    times = np.arange(COUNT) / 15
    key_times = times[::4]
    key_poses = np.column_stack([24 * key_times / times[-1], 8 + 6 * key_times,
                                 np.zeros_like(key_times)])
    poses = slerped_poses(key_times, key_poses, times)
    cx, cy = (WIDTH - 1) / 2, (HEIGHT - 1) / 2
    frames, truth = [], []
    for pan, tilt, roll in poses:
        image, _, _ = render_view(texture, pan, tilt, FOCAL, WIDTH, HEIGHT, cx, cy,
                                  distance=DISTANCE, centre=(0.0, 0.0), roll=roll)
        frames.append(image)
        truth.append(project_wall_points(wall, DISTANCE, pan, tilt, FOCAL, cx, cy, roll)[0][0])
    video, log = tmp_path / "walk.mkv", tmp_path / "poses.csv"
    write_video(video, frames, [round(t * 1000) for t in times])
    write_pose_log(log, key_times, key_poses)
    result = run_gsrwt("track", video, "--poses", log, "--focal", str(FOCAL), "--template",
                       KNOB, "-f", "csv")
    assert result.returncode == 0, result.stderr
    rows = read_table(result.stdout)
    assert [int(r["frame"]) for r in rows] == list(range(COUNT))
    found = np.array([[float(r["x_src"]), float(r["y_src"])] for r in rows])
    assert np.ptp(found[:, 0]) > 40  # the knob moves across the frames
    towards = np.array([*wall[0], DISTANCE]) / np.linalg.norm([*wall[0], DISTANCE])
    for r, seen in zip(rows, truth, strict=True):
        assert r["status"] == "ok" and float(r["score"]) >= 0.6
        assert np.hypot(*(np.array([float(r["x_src"]), float(r["y_src"])]) - seen)) < 1
        pan, tilt = float(r["pan_deg"]), float(r["tilt_deg"])
        centred = project_wall_points(wall, DISTANCE, pan, tilt, FOCAL, cx, cy)[0][0]
        assert np.hypot(centred[0] - cx, centred[1] - cy) < 1
        forward = camera_axes(pan, tilt)[2]  # the optical axis the command gives
        assert np.degrees(np.arccos(min(1.0, forward @ towards))) < 0.2
    match = run_gsrwt("match", video, "--poses", log, "--focal", str(FOCAL), "--template",
                      KNOB, "-f", "csv")
    assert match.returncode == 0, match.stderr
    assert [(r["frame"], r["x_src"]) for r in read_table(match.stdout)] == [
        (r["frame"], r["x_src"]) for r in rows]

    # Frames the landmark is not in are lost, not failed.
    blank = tmp_path / "blank.mkv"
    write_video(blank, [np.full((HEIGHT, WIDTH, 3), 128, np.uint8)] * 3, [0, 33, 67])
    result = run_gsrwt("track", blank, "--poses", log, "--focal", str(FOCAL), "--template",
                       KNOB, "-f", "csv")
    assert result.returncode == 0, result.stderr
    assert {r["status"] for r in read_table(result.stdout)} == {"lost"}


def test_a_cut_file_and_frames_without_a_pose_are_error_rows(tmp_path: Path, sweep) -> None:
    video, log, times, poses = sweep
    data = video.read_bytes()
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(data[: len(data) * 6 // 10])
    result = run_gsrwt("params", cut, "--poses", log, "--focal", str(FOCAL), "-f", "csv")
    assert result.returncode == 1
    rows = read_table(result.stdout)
    decoded = [row for row in rows if row["status"] == "ok"]
    assert 2 <= len(decoded) < COUNT and rows[:-1] == decoded
    assert [int(row["frame"]) for row in rows] == list(range(len(rows)))
    assert rows[-1]["status"] == "error" and "cut short" in rows[-1]["error"]
    assert result.stderr.count("Error:") == 1 and "cut short" in result.stderr
    # --frames: a slice of the frames; decoding stops at STOP, before the cut.
    result = run_gsrwt("params", cut, "--poses", log, "--focal", str(FOCAL), "--frames",
                       f"0:{len(decoded) - 1}:2", "-f", "csv")
    assert result.returncode == 0, result.stderr
    rows = read_table(result.stdout)
    assert [int(row["frame"]) for row in rows] == list(range(0, len(decoded) - 1, 2))
    assert {row["status"] for row in rows} == {"ok"}
    assert float(rows[1]["pan_deg"]) == pytest.approx(poses[2][0], abs=1e-4)

    holes = tmp_path / "holes.csv"
    write_pose_log(holes, times[[0, COUNT - 1]], poses[[0, COUNT - 1]])
    result = run_gsrwt("params", video, "--poses", holes, "--focal", str(FOCAL),
                       "--max-pose-gap", "0.05", "-f", "csv")
    assert result.returncode == 1
    rows = read_table(result.stdout)
    far = [bool(min(abs(t - times[0]), abs(t - times[-1])) > 0.05) for t in times]
    assert [row["status"] == "error" for row in rows] == far and any(far) and not all(far)
    assert all("no pose within 0.05 s" in row["error"] for row in rows if row["error"])


def test_usage_errors_are_one_line(tmp_path: Path, sweep) -> None:
    video, log, _, _ = sweep
    still = tmp_path / "still.png"
    cv2.imwrite(str(still), np.zeros((20, 20, 3), np.uint8))
    for args, words in [
        (("params", video, "--focal", "300"), "params needs --poses FILE"),
        (("params", "--poses", log, "--pan", "1", "--tilt", "2"), "--poses applies to a video"),
        (("track", video, "--poses", log, "--focal", "300"), "track needs --template FILE"),
        (("track", video, "--poses", log, "--template", KNOB, "--positions", "1,2"),
         "--positions does not apply to a video"),
        (("track", "--distance", "25", "--object", "3", "--positions", "0", "--template",
          KNOB), "--template applies to a VIDEO only"),
        (("lines", video, still), "a video is read frame by frame as the only INPUT"),
        (("match", still, "--template", KNOB, "--poses", log), "--poses applies to a video"),
        (("estimate", video, "--draw", tmp_path / "d"), "--draw does not apply to a video"),
        (("estimate", video, "--auto", "document"), "--auto document does not apply"),
        (("params", tmp_path / "none.mkv", "--poses", log, "--focal", "300"), "no such file"),
        (("params", video, "--poses", log, "--focal", "300", "--frames", "3:x"),
         "expected START:STOP or START:STOP:STEP"),
        (("lines", still, "--frames", "0:3"), "--frames applies to a video"),
    ]:
        result = run_gsrwt(*args)
        assert result.returncode == 2, (args, result.stderr)
        assert words in result.stderr, result.stderr
        assert result.stderr.count("Error") == 1 and "Traceback" not in result.stderr


def test_the_light_options_repeat_the_package_s_values() -> None:
    """The video options of the light commands repeat constants of heavy modules."""
    from gsrwt_cli.batch import video_jobs
    from gsrwt_cli.cli import gaze, sequence_options
    from gsrwt_cli.vision import ght

    assert sequence_options.TIME_MODES == video_jobs.TIME_MODES
    assert sequence_options.DEFAULT_MAX_POSE_GAP == video_jobs.DEFAULT_MAX_POSE_GAP
    assert gaze.DEFAULT_MATCH_THRESHOLD == ght.DEFAULT_MATCH_THRESHOLD
