"""``gsrwt rectify VIDEO --auto``: each frame's pose estimated from its own lines, one wall for
the whole video, refused frames interpolated within --max-pose-gap, optionally smoothed
(--smooth). Rooms rendered through OpenCV's own projection at known poses, one per frame,
encoded losslessly by PyAV."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gsrwt_cli.imaging.images import read_image
from tests.helpers.cli import run_gsrwt
from tests.helpers.estimate_scenes import render_room
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

pytest.importorskip("av")

from tests.helpers.videos import write_video  # noqa: E402  (needs PyAV, checked above)

#: (pan, tilt, roll) of each frame: a pan-tilt sweep at 10 frames per second.
POSES = [(20 - 3 * i, -8 + 2 * i, 0.5 * i - 2) for i in range(12)]
BLANK = 6  # a frame with nothing in it: its own estimate is refused


@pytest.fixture(scope="module")
def room_video(tmp_path_factory: pytest.TempPathFactory) -> Path:
    frames = [render_room(pan, tilt, roll, focal=520, seed=4).image for pan, tilt, roll in POSES]
    frames[BLANK] = np.full_like(frames[BLANK], 128)
    video = tmp_path_factory.mktemp("video") / "room.mkv"
    write_video(video, frames, [index * 100 for index in range(len(frames))], rate=10)
    return video


def pose_errors(rows: list[dict[str, str]]) -> list[float]:
    return [max(abs(float(row[f"{name}_deg"]) - truth)
                for name, truth in zip(("pan", "tilt", "roll"), pose))
            for row, pose in zip(rows, POSES, strict=True)]


def test_each_frame_is_estimated_and_a_refused_one_interpolated(tmp_path, room_video):
    result = run_gsrwt("rectify", room_video, "--auto", "--focal", "520", "--codec", "png",
                       "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "room.csv")
    assert [row["status"] for row in rows] == ["ok"] * len(POSES)
    assert max(pose_errors(rows)) < 0.5
    assert {row["pose_source"] for row in rows} == {"estimated"}
    assert {row["focal_source"] for row in rows} == {"option"}
    assert rows[BLANK]["confidence"] == "" and all(
        float(row["confidence"]) >= 0.5 for index, row in enumerate(rows) if index != BLANK)
    assert len(list((tmp_path / "out" / "room").glob("*.png"))) == len(POSES)
    # No accepted estimate within --max-pose-gap: the frame's row is an error that gives
    # its own estimate's reason.
    result = run_gsrwt("rectify", room_video, "--auto", "--focal", "520", "--codec", "png",
                       "--max-pose-gap", "0", "-o", tmp_path / "gap")
    assert result.returncode == 1
    rows = read_table(tmp_path / "gap" / "room.csv")
    assert [row["status"] for row in rows].count("error") == 1
    assert rows[BLANK]["error"].startswith("too few straight segments")
    assert "the nearest accepted estimate is 0.1 s away (--max-pose-gap 0)" in rows[BLANK]["error"]


def test_one_wall_for_the_whole_video_and_smoothing(tmp_path, room_video):
    """Without the focal length and with --wall dominant, the last frame's own estimate
    takes the side wall (pan 77 for -13); the video keeps the wall most frames chose. The
    smoothed poses stay within half a degree, and a rerun skips every frame."""
    single = run_gsrwt("estimate", room_video, "--wall", "dominant", "-f", "csv")
    own = [float(row["pan"]) for row in read_table(single.stdout) if row["status"] == "ok"]
    assert any(abs(pan - truth - 90) < 1 for pan, (truth, _, _) in zip(
        own, [pose for index, pose in enumerate(POSES) if index != BLANK]))
    arguments = ["rectify", room_video, "--auto", "--wall", "dominant", "--smooth", "0.5",
                 "--codec", "png", "-o", tmp_path / "out"]
    result = run_gsrwt(*arguments)
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "room.csv")
    assert max(pose_errors(rows)) < 0.5
    assert {row["focal_source"] for row in rows} == {"estimated"}
    assert all(abs(float(row["focal_px"]) - 520) < 10 for row in rows)
    assert "auto=lines wall=dominant min_confidence=0.5 smooth=0.5" in rows[0]["made_with"]
    again = run_gsrwt(*arguments)
    assert again.returncode == 0 and f"0 frames ok, {len(POSES)} skipped" in again.stderr


def test_a_webcams_frames_given_its_focal_length_alone_are_checked_for_its_lens(tmp_path):
    """OpenCV's 13 webcam photos (``right*.jpg``, a lens of k1 about -0.26 nobody named) as
    the frames of a lossless video, given the focal length alone (``--focal 537``): each frame
    is judged as its photo is. The photos' lens check refuses 9 of them (their poses 2.3 to 21
    degrees off what the straightened lines give); the frames went unchecked and were all 9
    accepted. Given the principal point too (a calibration's, which measures the lens), they
    are taken as the pinhole they say, photos and frames alike. (Since a normal found only by
    chance counts as unseen, 7 and 7: two boards are refused for their confidence first; their
    frames' reason does not offer guides, which a video does not take.)"""
    photos = sorted(DATA.glob("right*.jpg"))
    video = tmp_path / "webcam.mkv"
    grey = [read_image(photo) for photo in photos]  # as gsrwt decodes them: grey JPEGs
    write_video(video, [np.dstack([pixels] * 3) for pixels in grey],
                [index * 100 for index in range(len(photos))], rate=10)
    for extra in ([], ["--cx", "319.5", "--cy", "239.5"]):
        stills = read_table(run_gsrwt("estimate", *photos, "--focal", "537", *extra,
                                      "-f", "csv").stdout)
        frames = read_table(run_gsrwt("estimate", video, "--focal", "537", *extra,
                                      "-f", "csv").stdout)
        # the same, but that a video's frames take no guides (a usage error)
        assert [(row["status"], row["error"]) for row in frames] == [
            (row["status"], row["error"].replace(", or guides (--verticals)", ""))
            for row in stills]
        assert not any("--verticals" in row["error"] for row in frames)
        bent = [row for row in frames if row["error"].startswith("the straight edges bend")]
        assert len(bent) == (0 if extra else 7)
        assert sum(row["status"] == "ok" for row in frames) == (7 if extra else 0)


def test_a_refused_frame_says_what_would_settle_it_for_a_video(tmp_path):
    """scikit-image's cat (``chelsea.jpg``) as the two frames of a video, no focal length: each
    is refused as its photo is, "no clear man-made structure", and the remedy is what a video
    takes: the focal length or the pose, not guides (``--verticals`` is a usage error for a
    video)."""
    photo = DATA / "real" / "chelsea.jpg"
    still = read_table(run_gsrwt("estimate", photo, "-f", "csv").stdout)[0]["error"]
    assert still.endswith("; give the focal length, the pose, or guides (--verticals)")
    pixels = read_image(photo)
    video = tmp_path / "cat.mkv"
    write_video(video, [pixels, pixels], [0, 100], rate=10)
    result = run_gsrwt("estimate", video, "-f", "csv")
    assert result.returncode == 1
    frames = read_table(result.stdout)
    assert [row["error"] for row in frames] == [still.replace(
        "; give the focal length, the pose, or guides (--verticals)",
        "; give the focal length or the pose")] * 2
    usage = run_gsrwt("estimate", video, "--verticals", "1,1,1,9;5,1,5,9")
    assert usage.returncode == 2 and "--verticals does not apply to a video" in usage.stderr
    # rectify --auto: the same reason for each frame, and no video, which the summary says
    rectified = run_gsrwt("rectify", video, "--auto", "-o", tmp_path / "out")
    assert rectified.returncode == 1
    assert "give the focal length or the pose; no frame's estimate was accepted" in (
        rectified.stderr)
    assert "0 frames ok, 0 skipped, 2 failed; no output written" in rectified.stderr
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["cat.csv"]


@pytest.mark.parametrize("arguments, message", [
    (["--auto", "--poses", "poses.csv"], "use either --poses FILE or --auto"),
    (["--auto", "document"], "--auto document does not apply to a video"),
    (["--smooth", "1", "--poses", "poses.csv"], "--smooth smooths poses estimated with --auto"),
    (["--auto", "--bbox", "full"], "--bbox full gives every frame a size of its own, and a "
                                   "h264 video has one: use --codec png"),
])
def test_usage_errors_are_one_line(tmp_path, room_video, arguments, message):
    (tmp_path / "poses.csv").write_text("time,pan,tilt\n0,1,2\n")
    result = run_gsrwt("rectify", room_video, *arguments, "--focal", "520", "-o", "out",
                       cwd=tmp_path)
    assert result.returncode == 2
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("Error:")]
    assert message in line and "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()
