"""``gsrwt rectify VIDEO --poses FILE``: real videos written by PyAV from renders of the
independent camera, rectified frame by frame; the faults of a stream (a file cut short, a
frame the decoder refuses, a pose log with holes or out of order, a run killed mid-video)."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.helpers.cli import run_gsrwt, start_gsrwt
from tests.helpers.images import psnr
from tests.helpers.tables import read_table

av = pytest.importorskip("av")

from tests.helpers.videos import (  # noqa: E402  (needs PyAV and scipy, checked above)
    read_video,
    render_sweep,
    slerped_poses,
    write_pose_log,
    write_video,
)

pytestmark = pytest.mark.slow

WIDTH, HEIGHT, FOCAL = 320, 240, "300"
COUNT = 17


@pytest.fixture(scope="module")
def sweep() -> tuple[list[np.ndarray], list[int], np.ndarray, np.ndarray, np.ndarray]:
    return render_sweep(COUNT, WIDTH, HEIGHT, float(FOCAL), key_every=4)


@pytest.fixture
def sweep_video(tmp_path: Path, sweep) -> tuple[Path, Path]:
    frames, pts, _, key_times, key_poses = sweep
    video, log = tmp_path / "walk.mkv", tmp_path / "poses.csv"
    write_video(video, frames, pts)
    write_pose_log(log, key_times, key_poses)
    return video, log


def test_a_sweep_matches_each_frame_rectified_alone(tmp_path: Path, sweep, sweep_video) -> None:
    """Each rectified frame is the still-image rectification of the same render with the
    pose slerped (by scipy) to its time, through a lossless codec; timestamps are kept."""
    frames, pts, _, key_times, key_poses = sweep
    video, log = sweep_video
    result = run_gsrwt("rectify", video, "--poses", log, "--focal", FOCAL, "--codec", "ffv1",
                       "-o", tmp_path / "out", "-j", "2")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert [int(row["frame"]) for row in rows] == list(range(COUNT))
    assert [float(row["time"]) for row in rows] == pytest.approx([p / 1000 for p in pts])
    assert {row["status"] for row in rows} == {"ok"}
    rectified, times = read_video(tmp_path / "out" / "walk.mkv")
    assert times == pytest.approx([p / 1000 for p in pts])

    # The reference: every rendered frame rectified alone, with scipy's slerped pose.
    poses = slerped_poses(key_times, key_poses, np.array(pts) / 1000)
    still = tmp_path / "still"
    still.mkdir()
    lines = ["image,pan,tilt,roll,focal"]
    for index, (frame, (pan, tilt, roll)) in enumerate(zip(frames, poses)):
        cv2.imwrite(str(still / f"{index:02d}.png"), frame)
        lines.append(f"{index:02d}.png,{float(pan)!r},{float(tilt)!r},{float(roll)!r},{FOCAL}")
    (tmp_path / "still.csv").write_text("\n".join(lines) + "\n")
    result = run_gsrwt("rectify", still, "--sidecar", tmp_path / "still.csv", "-o",
                       tmp_path / "ref", "-j", "1")
    assert result.returncode == 0, result.stderr
    for index, (row, output) in enumerate(zip(rows, rectified)):
        reference = cv2.imread(str(tmp_path / "ref" / f"{index:02d}.png"))
        mask = reference.any(axis=2) & output.any(axis=2)
        assert mask.mean() > 0.5
        assert psnr(output, reference, mask) >= 35, index
        assert float(row["pan_deg"]) == pytest.approx(poses[index][0], abs=1e-4)
        assert float(row["tilt_deg"]) == pytest.approx(poses[index][1], abs=1e-4)
    # Frames between samples differ from their nearest sample's rectification: the test
    # sees a pose that is not interpolated.
    nearest = cv2.imread(str(tmp_path / "ref" / "00.png"))
    assert psnr(rectified[2], nearest, nearest.any(axis=2) & rectified[2].any(axis=2)) < 30


def test_an_image_sequence_continues_where_it_stopped(tmp_path: Path, sweep_video) -> None:
    video, log = sweep_video
    args = ("rectify", video, "--poses", log, "--focal", FOCAL, "--codec", "png", "-o",
            tmp_path / "out", "-j", "1")
    assert run_gsrwt(*args).returncode == 0
    sequence = tmp_path / "out" / "walk"
    assert sorted(p.name for p in sequence.iterdir()) == [f"{i:06d}.png" for i in range(COUNT)]
    (sequence / "000005.png").unlink()
    before = (sequence / "000006.png").stat().st_mtime_ns
    result = run_gsrwt(*args)
    assert result.returncode == 0, result.stderr
    statuses = [row["status"] for row in read_table(tmp_path / "out" / "walk.csv")]
    assert statuses == ["skipped"] * 5 + ["ok"] + ["skipped"] * (COUNT - 6)
    assert (sequence / "000006.png").stat().st_mtime_ns == before


def test_a_finished_video_is_skipped_and_other_options_are_refused(tmp_path: Path,
                                                                   sweep_video) -> None:
    video, log = sweep_video
    args = ("rectify", video, "--poses", log, "--focal", FOCAL, "--codec", "ffv1", "-o",
            tmp_path / "out")
    assert run_gsrwt(*args).returncode == 0
    made = (tmp_path / "out" / "walk.mkv").read_bytes()
    again = run_gsrwt(*args)
    assert again.returncode == 0, again.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert {row["status"] for row in rows} == {"skipped"} and len(rows) == COUNT
    other = run_gsrwt(*args[:-2], "--scale", "0.5", "-o", tmp_path / "out")
    assert other.returncode == 1
    assert "exists from a run with other options" in other.stderr
    assert (tmp_path / "out" / "walk.mkv").read_bytes() == made


def test_a_file_cut_short_gives_its_frames_and_an_error_row(tmp_path: Path,
                                                             sweep_video) -> None:
    video, log = sweep_video
    data = video.read_bytes()
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(data[: len(data) * 6 // 10])
    result = run_gsrwt("rectify", cut, "--poses", log, "--focal", FOCAL, "--codec", "ffv1",
                       "-o", tmp_path / "out")
    assert result.returncode == 1
    rows = read_table(tmp_path / "out" / "cut.csv")
    decoded = [row for row in rows if row["status"] == "ok"]
    assert 3 <= len(decoded) < COUNT
    assert [int(row["frame"]) for row in rows] == list(range(len(rows)))
    assert rows[-1]["status"] == "error" and "cut short" in rows[-1]["error"]
    assert len(read_video(tmp_path / "out" / "cut.mkv")[0]) == len(decoded)


def test_a_frame_the_decoder_refuses_is_its_row_alone(tmp_path: Path, sweep) -> None:
    frames, pts, _, key_times, key_poses = sweep
    video, log = tmp_path / "walk.mp4", tmp_path / "poses.csv"
    write_video(video, frames, pts, codec="libx264", options={"crf": "18"})
    write_pose_log(log, key_times, key_poses)
    with av.open(str(video)) as container:
        packets = [(p.pos, p.size, float(p.pts * p.time_base))
                   for p in container.demux(video=0) if p.size]
    position, size, broken_time = packets[len(packets) // 2]
    data = bytearray(video.read_bytes())
    data[position + 4: position + size] = b"\xff" * (size - 4)
    video.write_bytes(bytes(data))
    result = run_gsrwt("rectify", video, "--poses", log, "--focal", FOCAL, "-o",
                       tmp_path / "out")
    assert result.returncode == 1
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert len(rows) == COUNT
    failed = [row for row in rows if row["status"] != "ok"]
    assert len(failed) == 1 and "cannot be decoded" in failed[0]["error"]
    assert float(failed[0]["time"]) == pytest.approx(broken_time, abs=1e-6)


def test_a_pose_log_with_holes_and_out_of_order(tmp_path: Path, sweep, sweep_video) -> None:
    video, _ = sweep_video
    _, pts, _, key_times, key_poses = sweep
    ordered, shuffled = tmp_path / "ordered.csv", tmp_path / "shuffled.csv"
    write_pose_log(ordered, key_times, key_poses)
    order = list(np.random.default_rng(3).permutation(len(key_times)))
    write_pose_log(shuffled, key_times, key_poses, order)
    tables = []
    for log in (ordered, shuffled):
        out = tmp_path / log.stem
        result = run_gsrwt("rectify", video, "--poses", log, "--focal", FOCAL, "--codec",
                           "png", "-o", out, "-j", "1")
        assert result.returncode == 0, result.stderr
        tables.append([(row["pan_deg"], row["tilt_deg"], row["roll_deg"])
                       for row in read_table(out / "walk.csv")])
    assert tables[0] == tables[1]

    holes = tmp_path / "holes.csv"
    keep = [i for i, t in enumerate(key_times) if not 0.1 < t < 0.45]
    write_pose_log(holes, key_times[keep], key_poses[keep])
    result = run_gsrwt("rectify", video, "--poses", holes, "--focal", FOCAL, "--codec", "png",
                       "--max-pose-gap", "0.1", "-o", tmp_path / "holes", "-j", "1")
    assert result.returncode == 1
    rows = read_table(tmp_path / "holes" / "walk.csv")
    times = np.array(pts) / 1000
    kept = key_times[keep]
    far = [bool(np.min(np.abs(kept - t)) > 0.1) for t in times]
    assert [row["status"] == "error" for row in rows] == far
    assert any(far) and not all(far)
    assert all("no pose within 0.1 s" in row["error"] for row in rows if row["error"])

    duplicate = tmp_path / "duplicate.csv"
    duplicate.write_text("time,pan,tilt\n0,1,2\n0.5,3,4\n0.5,5,6\n")
    result = run_gsrwt("rectify", video, "--poses", duplicate, "--focal", FOCAL, "-o",
                       tmp_path / "dup")
    assert result.returncode == 2
    assert "duplicate.csv line 4: time 0.5 is already given in line 3" in result.stderr


def test_usage_errors_are_one_line(tmp_path: Path, sweep_video) -> None:
    video, log = sweep_video
    for args, words in [
        ((video, "-o", tmp_path / "o"), "a video needs --poses FILE"),
        ((video, "--poses", log, "-o", tmp_path / "o"), "missing field 'focal'"),
        ((video, video, "--poses", log, "-o", tmp_path / "o"), "--poses takes one video"),
        ((video, "--poses", log, "--focal", "300", "--ext", "jpg", "-o", tmp_path / "o"),
         "--ext does not apply to a video"),
    ]:
        result = run_gsrwt("rectify", *args)
        assert result.returncode == 2, result.stderr
        assert words in result.stderr
        assert "Traceback" not in result.stderr
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_killed_mid_video_leaves_no_file_and_a_rerun_completes(tmp_path: Path, sweep) -> None:
    frames, pts, _, key_times, key_poses = sweep
    many = [frames[i % COUNT] for i in range(150)]
    stamps = [round(i * 1000 / 30) for i in range(150)]
    video, log = tmp_path / "long.mkv", tmp_path / "poses.csv"
    write_video(video, many, stamps)
    write_pose_log(log, np.array([0.0, 5.0]), np.array([[5.0, 20.0, 0.0], [-5.0, 25.0, 0.0]]))
    out = tmp_path / "out"
    args = ("rectify", video, "--poses", log, "--focal", FOCAL, "--codec", "ffv1", "-o", out,
            "--max-pose-gap", "5")
    process = start_gsrwt(*args)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if out.is_dir() and any(p.name.endswith(".part") and p.stat().st_size > 0
                                for p in out.iterdir()):
            break
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait(30)
    assert not (out / "long.mkv").exists()
    assert not (out / "long.csv").exists()
    result = run_gsrwt(*args)
    assert result.returncode == 0, result.stderr
    assert len(read_video(out / "long.mkv")[0]) == 150
    assert not [p for p in out.iterdir() if p.name.endswith(".part")]


def test_steady_keeps_the_wall_still(tmp_path: Path, sweep_video) -> None:
    """With --steady every frame shows the wall the first frame's default frame shows: the
    same wall point at the same output pixel, frame after frame (without it, the frame
    follows the optical axis and the wall moves)."""
    video, log = sweep_video
    outputs = {}
    for steady in ((), ("--steady",)):
        out = tmp_path / ("steady" if steady else "moving")
        result = run_gsrwt("rectify", video, "--poses", log, "--focal", FOCAL, "--codec", "png",
                           "-o", out, "-j", "1", *steady)
        assert result.returncode == 0, result.stderr
        outputs[bool(steady)] = [cv2.imread(str(out / "walk" / f"{index:06d}.png"))
                                 for index in range(COUNT)]
    for steady, frames in outputs.items():
        first = frames[0]
        for index in (4, 8, 12):
            mask = first.any(axis=2) & frames[index].any(axis=2)
            assert mask.mean() > 0.3
            if steady:
                assert psnr(frames[index], first, mask) >= 28, index
            else:
                assert psnr(frames[index], first, mask) < 20, index
    np.testing.assert_array_equal(outputs[True][0], outputs[False][0])
    refused = run_gsrwt("rectify", video, "--poses", log, "--focal", FOCAL, "--steady",
                        "--bbox", "full", "-o", tmp_path / "x")
    assert refused.returncode == 2 and "needs --bbox frontal" in refused.stderr
