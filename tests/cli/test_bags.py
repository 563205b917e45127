"""``gsrwt rectify BAG --topic TOPIC --pose-topic TOPIC``: ROS bags written by rosbags' own
writers (ROS 1, ROS 2 sqlite3 and MCAP) from renders of the independent camera
(tests/helpers/camera.py) at the known poses of a pan-tilt sweep, the poses published as a
pan-tilt unit's JointState or as a /tf chain (tests/helpers/bags.py); each rectified frame
is compared with the still image's rectification of the same render at the true pose. The
faults of a bag: no camera_info, a corrupt frame, poses with a gap or out of order, a run
killed mid-bag."""

from __future__ import annotations

import math
import os
import signal
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("scipy")

from tests.helpers.bags import (  # noqa: E402
    LINK_FROM_OPTICAL,
    WALL_FROM_BASE,
    bag_builder,
    bag_path,
    ros_quaternion,
    world_from_body,
)
from tests.helpers.camera import render_view  # noqa: E402
from tests.helpers.cli import run_gsrwt, start_gsrwt  # noqa: E402
from tests.helpers.images import psnr, smooth_texture  # noqa: E402
from tests.helpers.tables import read_table  # noqa: E402
from tests.helpers.videos import slerped_poses  # noqa: E402

pytestmark = pytest.mark.slow

WIDTH, HEIGHT, FOCAL = 160, 120, 150.0
CX, CY = (WIDTH - 1) / 2, (HEIGHT - 1) / 2
COUNT = 9
START_NS = 1_700_000_000_000_000_000
STEP_NS = 100_000_000
#: The pan-tilt unit reports every other frame: the frames between are halfway.
KEY_FRAMES = list(range(0, COUNT, 2))
CORRUPT = 3
K = np.array([[FOCAL, 0.0, CX], [0.0, FOCAL, CY], [0.0, 0.0, 1.0]])


def _stamps(count: int = COUNT) -> list[int]:
    return [START_NS + index * STEP_NS for index in range(count)]


def _key_poses() -> np.ndarray:
    """Pan and tilt (degrees, no roll) at the key frames: a sweep right to left, up, down."""
    times = np.array(KEY_FRAMES, dtype=float) / 10
    return np.column_stack([25 * np.sin(2 * np.pi * times / 1.6), 8 + 20 * times,
                            np.zeros_like(times)])


def _true_poses() -> np.ndarray:
    """Every frame's (pan, tilt, roll): scipy's slerp of the key poses at its time."""
    return slerped_poses(np.array(KEY_FRAMES, float) / 10, _key_poses(),
                         np.arange(COUNT, dtype=float) / 10)


@pytest.fixture(scope="module")
def renders() -> list[np.ndarray]:
    texture = smooth_texture(700, 900, seed=11)
    return [render_view(texture, pan, tilt, FOCAL, WIDTH, HEIGHT, CX, CY, roll=roll,
                        centre=(0.0, 0.0))[0] for pan, tilt, roll in _true_poses()]


def _write_bag(path: Path, kind: str, frames: list[np.ndarray], *, camera_info: bool = True,
               joint_frames: list[int] | None = None, joint_order: list[int] | None = None,
               tf: bool = False, count: int = COUNT) -> None:
    """A bag: /camera/image_raw (bgr8), /camera/image_raw/compressed (PNG, frame
    :data:`CORRUPT` cut in half), /other/image_raw (no camera_info), the camera's
    camera_info, the pan-tilt unit's /joint_states at ``joint_frames`` (written in
    ``joint_order``), and with ``tf`` the /tf chain wall -> ptu_base -> camera_link ->
    camera_optical_frame at every frame."""
    stamps = _stamps(count)
    poses = _true_poses()
    keys = joint_frames if joint_frames is not None else KEY_FRAMES
    order = joint_order if joint_order is not None else list(range(len(keys)))
    with bag_builder(path, kind) as bag:
        if tf:
            static = [bag.transform(stamps[0], "wall", "ptu_base", ros_quaternion(WALL_FROM_BASE)),
                      bag.transform(stamps[0], "camera_link", "camera_optical_frame",
                                    LINK_FROM_OPTICAL)]
            bag.add("/tf_static", "tf2_msgs/msg/TFMessage", stamps[0], bag.tf(static))
        for position, key in enumerate(order):  # log times in order, stamps as ordered
            frame = keys[key]
            pan, tilt, _ = poses[frame % COUNT]
            bag.add("/joint_states", "sensor_msgs/msg/JointState", stamps[0] + position,
                    bag.joint_state(stamps[frame], ["ptu_pan", "ptu_tilt"],
                                    [math.radians(pan), math.radians(tilt)]))
        for index, stamp in enumerate(stamps):
            image = frames[index % len(frames)]
            log = stamp + 2_000_000
            bag.add("/camera/image_raw", "sensor_msgs/msg/Image", log,
                    bag.image(stamp, image, "bgr8"))
            png = cv2.imencode(".png", image)[1].tobytes()
            if index == CORRUPT:
                png = png[: len(png) // 2]
            bag.add("/camera/image_raw/compressed", "sensor_msgs/msg/CompressedImage", log,
                    bag.compressed(stamp, png, "bgr8; png compressed bgr8"))
            bag.add("/other/image_raw", "sensor_msgs/msg/Image", log,
                    bag.image(stamp, image, "bgr8"))
            if camera_info:
                bag.add("/camera/camera_info", "sensor_msgs/msg/CameraInfo", log,
                        bag.camera_info(stamp, K, [0.0] * 5, "plumb_bob", WIDTH, HEIGHT))
            if tf:
                pan, tilt, roll = poses[index % COUNT]
                moving = [bag.transform(stamp, "ptu_base", "camera_link",
                                        ros_quaternion(world_from_body(pan, tilt, roll)))]
                bag.add("/tf", "tf2_msgs/msg/TFMessage", log, bag.tf(moving))


def _references(tmp_path: Path, renders: list[np.ndarray]) -> list[np.ndarray]:
    """Every render rectified alone, as a still image, at its true pose."""
    still = tmp_path / "still"
    still.mkdir()
    lines = ["image,pan,tilt,roll,focal,cx,cy"]
    for index, (image, (pan, tilt, roll)) in enumerate(zip(renders, _true_poses())):
        cv2.imwrite(str(still / f"{index:02d}.png"), image)
        lines.append(f"{index:02d}.png,{float(pan)!r},{float(tilt)!r},{float(roll)!r},"
                     f"{FOCAL},{CX},{CY}")
    (tmp_path / "still.csv").write_text("\n".join(lines) + "\n")
    result = run_gsrwt("rectify", still, "--sidecar", tmp_path / "still.csv", "-o",
                       tmp_path / "ref", "-j", "1")
    assert result.returncode == 0, result.stderr
    return [cv2.imread(str(tmp_path / "ref" / f"{index:02d}.png")) for index in range(COUNT)]


def _sequence(directory: Path) -> list[np.ndarray]:
    return [cv2.imread(str(directory / f"{index:06d}.png")) for index in range(COUNT)]


def _assert_match(outputs: list[np.ndarray], references: list[np.ndarray]) -> None:
    for index, (output, reference) in enumerate(zip(outputs, references)):
        mask = reference.any(axis=2) & output.any(axis=2)
        assert mask.mean() > 0.5, index
        assert psnr(output, reference, mask) >= 35, index


def test_a_pan_tilt_sweep_from_joint_states(tmp_path: Path, renders) -> None:
    """JointState samples every other frame: the frames between get the slerp of the two
    around them (scipy's, halfway), and each rectified frame is the still image's."""
    bag = bag_path(tmp_path, "mcap")
    _write_bag(bag, "mcap", renders)
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic",
                       "/joint_states", "--joints", "ptu_pan,ptu_tilt", "--codec", "png",
                       "-o", tmp_path / "out", "-j", "2")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert [int(row["frame"]) for row in rows] == list(range(COUNT))
    assert [float(row["time"]) for row in rows] == pytest.approx(
        [index / 10 for index in range(COUNT)], abs=1e-9)
    assert {row["status"] for row in rows} == {"ok"}
    assert {row["image"] for row in rows} == {str(bag)}
    assert {row["focal_source"] for row in rows} == {"camera"}  # the bag's camera_info
    poses = _true_poses()
    for row, (pan, tilt, roll) in zip(rows, poses):
        assert float(row["pan_deg"]) == pytest.approx(pan, abs=1e-4)
        assert float(row["tilt_deg"]) == pytest.approx(tilt, abs=1e-4)
        assert float(row["roll_deg"]) == pytest.approx(roll, abs=1e-4)
    outputs = _sequence(tmp_path / "out" / "walk")
    references = _references(tmp_path, renders)
    _assert_match(outputs, references)
    # A frame halfway is not its neighbour's pose: rectified with frame 0's pose it differs.
    first = tmp_path / "first"
    first.mkdir()
    cv2.imwrite(str(first / "one.png"), renders[1])
    pan, tilt, _ = poses[0]
    assert run_gsrwt("rectify", first / "one.png", "--pan", repr(float(pan)), "--tilt",
                     repr(float(tilt)), "--focal", str(FOCAL), "-o", first / "out").returncode == 0
    wrong = cv2.imread(str(first / "out" / "one.png"))
    assert psnr(outputs[1], wrong, wrong.any(axis=2) & outputs[1].any(axis=2)) < 30


def test_a_tf_chain_through_the_pan_tilt_unit(tmp_path: Path, renders) -> None:
    """/tf from the wall through ptu_base and camera_link to the optical frame (static and
    moving transforms, a ROS 1 bag): each frame rectified as the still image is."""
    bag = bag_path(tmp_path, "ros1")
    _write_bag(bag, "ros1", renders, tf=True)
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic", "/tf",
                       "--wall-frame", "wall", "--camera-frame", "camera_optical_frame",
                       "--codec", "ffv1", "-o", tmp_path / "out", "-j", "1")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert {row["status"] for row in rows} == {"ok"} and len(rows) == COUNT
    for row, (pan, tilt, roll) in zip(rows, _true_poses()):
        assert float(row["pan_deg"]) == pytest.approx(pan, abs=1e-4)
        assert float(row["tilt_deg"]) == pytest.approx(tilt, abs=1e-4)
        assert float(row["roll_deg"]) == pytest.approx(roll, abs=1e-4)
    import av

    with av.open(str(tmp_path / "out" / "walk.mkv")) as container:
        decoded = [(frame.to_ndarray(format="bgr24"), float(frame.pts * frame.time_base))
                   for frame in container.decode(video=0)]
    assert [t for _, t in decoded] == pytest.approx([i / 10 for i in range(COUNT)], abs=1e-3)
    _assert_match([image for image, _ in decoded], _references(tmp_path, renders))


def test_a_bag_output_holds_the_rectified_topic_and_its_camera(tmp_path: Path,
                                                               renders) -> None:
    """--codec bag: /camera/gsrwt/image with the input's stamps, the frames the image
    sequence holds, and a camera_info whose camera, set square to the wall, sees the
    rectified frame (the independent camera renders the wall through that K)."""
    bag = bag_path(tmp_path, "sqlite3")
    _write_bag(bag, "sqlite3", renders)
    args = ("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic", "/joint_states",
            "--joints", "ptu_pan,ptu_tilt", "-j", "1")
    assert run_gsrwt(*args, "--codec", "png", "-o", tmp_path / "png").returncode == 0
    result = run_gsrwt(*args, "--codec", "bag", "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    made = tmp_path / "out" / "walk"
    assert (made / "metadata.yaml").is_file() and list(made.glob("*.mcap"))
    assert not [p for p in (tmp_path / "out").iterdir() if ".gsrwt-" in p.name]
    from rosbags.highlevel import AnyReader

    images, infos = [], []
    with AnyReader([made]) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        assert topics == {"/camera/gsrwt/image": "sensor_msgs/msg/Image",
                          "/camera/gsrwt/camera_info": "sensor_msgs/msg/CameraInfo"}
        for connection, _, raw in reader.messages():
            message = reader.deserialize(raw, connection.msgtype)
            (images if connection.msgtype.endswith("Image") else infos).append(message)
    stamp = [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in images]
    assert stamp == _stamps()
    sequence = _sequence(tmp_path / "png" / "walk")
    texture = smooth_texture(700, 900, seed=11)
    for message, info, expected in zip(images, infos, sequence):
        assert message.encoding == "bgr8"
        pixels = np.asarray(message.data, np.uint8).reshape(message.height, message.width, 3)
        np.testing.assert_array_equal(pixels, expected)
        k = np.asarray(info.k, float).reshape(3, 3)
        assert (info.width, info.height) == (message.width, message.height)
        assert k[0, 0] == pytest.approx(FOCAL) and k[1, 1] == pytest.approx(FOCAL)
        scores = []
        for shift in (0.0, 1.0):  # a camera a pixel off sees another picture
            frontal, seen, _ = render_view(texture, 0.0, 0.0, k[0, 0], message.width,
                                           message.height, k[0, 2] + shift, k[1, 2],
                                           centre=(0.0, 0.0))
            inside = (seen & pixels.any(axis=2)).astype(np.uint8)  # less the blended edge
            mask = cv2.erode(inside, np.ones((5, 5), np.uint8)).astype(bool)
            assert mask.mean() > 0.5
            scores.append(psnr(pixels, frontal, mask))
        assert scores[0] >= 33 and scores[1] < 30, scores
    rerun = run_gsrwt(*args, "--codec", "bag", "-o", tmp_path / "out")
    assert rerun.returncode == 0, rerun.stderr
    assert {row["status"] for row in read_table(tmp_path / "out" / "walk.csv")} == {"skipped"}


def test_a_corrupt_frame_is_its_row_alone(tmp_path: Path, renders) -> None:
    bag = bag_path(tmp_path, "mcap")
    _write_bag(bag, "mcap", renders)
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw/compressed",
                       "--pose-topic", "/joint_states", "--joints", "ptu_pan,ptu_tilt",
                       "--codec", "png", "-o", tmp_path / "out", "-j", "1")
    assert result.returncode == 1, result.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert [row["status"] for row in rows] == ["error" if i == CORRUPT else "ok"
                                               for i in range(COUNT)]
    assert f"frame {CORRUPT}" in rows[CORRUPT]["error"]
    assert not (tmp_path / "out" / "walk" / f"{CORRUPT:06d}.png").exists()
    assert "Traceback" not in result.stderr


def test_a_bag_damaged_mid_stream_gives_its_frames_then_an_error_row(tmp_path: Path,
                                                                     renders) -> None:
    """Bytes overwritten halfway through a ROS 1 bag (its poses all written before them):
    the frames before the damage are rows, then one error row; exit 1."""
    many = 40
    bag = bag_path(tmp_path, "ros1")
    small = [cv2.resize(image, (WIDTH // 2, HEIGHT // 2)) for image in renders]
    _write_bag(bag, "ros1", small, count=many, joint_frames=[0, many - 1],
               camera_info=False)
    with open(bag, "r+b") as handle:
        handle.seek(bag.stat().st_size // 2)
        handle.write(b"\xff" * 50_000)  # several messages, their headers too
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic",
                       "/joint_states", "--joints", "ptu_pan,ptu_tilt", "--focal", str(FOCAL / 2),
                       "--max-pose-gap", "10", "--codec", "png", "-o", tmp_path / "out",
                       "-j", "1")
    assert result.returncode == 1, result.stderr
    rows = read_table(tmp_path / "out" / "walk.csv")
    assert 5 < len(rows) < many
    assert [int(row["frame"]) for row in rows] == list(range(len(rows)))
    assert rows[-1]["status"] == "error" and "damaged at message" in rows[-1]["error"]
    assert {row["status"] for row in rows[:5]} == {"ok"}
    assert "Traceback" not in result.stderr


def test_poses_with_a_gap_and_out_of_order(tmp_path: Path, renders) -> None:
    """JointState stamps written shuffled give the table of those written in order; a gap
    in them makes error rows of exactly the frames beyond --max-pose-gap."""
    tables = []
    for name, order in (("ordered", None), ("shuffled", [3, 0, 4, 2, 1])):
        bag = bag_path(tmp_path, "mcap", name)
        _write_bag(bag, "mcap", renders, joint_order=order)
        result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic",
                           "/joint_states", "--joints", "ptu_pan,ptu_tilt", "--codec", "png",
                           "-o", tmp_path / name, "-j", "1")
        assert result.returncode == 0, result.stderr
        tables.append([(row["pan_deg"], row["tilt_deg"], row["roll_deg"])
                       for row in read_table(tmp_path / name / f"{name}.csv")])
    assert tables[0] == tables[1]
    # The same poses as a pose file (seconds from the first frame): the same table.
    lines = ["time,pan,tilt"] + [f"{frame / 10!r},{float(pan)!r},{float(tilt)!r}"
                                 for frame, (pan, tilt, _) in zip(KEY_FRAMES, _key_poses())]
    (tmp_path / "poses.csv").write_text("\n".join(lines) + "\n")
    result = run_gsrwt("rectify", bag_path(tmp_path, "mcap", "ordered"), "--topic",
                       "/camera/image_raw", "--poses", tmp_path / "poses.csv", "--codec", "png",
                       "-o", tmp_path / "log", "-j", "1")
    assert result.returncode == 0, result.stderr
    rows = read_table(tmp_path / "log" / "ordered.csv")
    assert [(row["pan_deg"], row["tilt_deg"], row["roll_deg"]) for row in rows] == tables[0]
    assert {row["pose_source"] for row in rows} == {"poses"}

    bag = bag_path(tmp_path, "mcap", "gap")
    kept = [0, 6, 8]  # the unit went quiet between frames 0 and 6
    _write_bag(bag, "mcap", renders, joint_frames=kept)
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic",
                       "/joint_states", "--joints", "ptu_pan,ptu_tilt", "--codec", "png",
                       "--max-pose-gap", "0.15", "-o", tmp_path / "gap", "-j", "1")
    assert result.returncode == 1
    rows = read_table(tmp_path / "gap" / "gap.csv")
    far = [min(abs(index - key) for key in kept) > 1.5 for index in range(COUNT)]
    assert [row["status"] == "error" for row in rows] == far
    assert any(far) and not all(far)
    assert all("no pose on /joint_states within 0.15 s" in row["error"]
               for row in rows if row["error"])


def test_a_bag_without_camera_info(tmp_path: Path, renders) -> None:
    bag = bag_path(tmp_path, "mcap")
    _write_bag(bag, "mcap", renders)
    args = ("rectify", bag, "--topic", "/other/image_raw", "--pose-topic", "/joint_states",
            "--joints", "ptu_pan,ptu_tilt", "--codec", "png", "-j", "1")
    refused = run_gsrwt(*args, "-o", tmp_path / "refused")
    assert refused.returncode == 2
    line = refused.stderr.strip()
    assert "\n" not in line and "Traceback" not in line
    assert "no camera_info on '/other/camera_info'" in line
    assert "/camera/camera_info" in line and "--camera-info-topic" in line
    assert not (tmp_path / "refused").exists()
    for extra, source in ((("--focal", str(FOCAL)), "option"),
                          (("--camera-info-topic", "/camera/camera_info"), "camera")):
        out = tmp_path / source
        result = run_gsrwt(*args, *extra, "-o", out)
        assert result.returncode == 0, result.stderr
        rows = read_table(out / "walk.csv")
        assert {row["focal_source"] for row in rows} == {source}
        assert {float(row["focal_px"]) for row in rows} == {FOCAL}


def test_bad_requests_are_one_line(tmp_path: Path, renders) -> None:
    bag = bag_path(tmp_path, "ros1")
    _write_bag(bag, "ros1", renders, tf=True)
    out = tmp_path / "o"
    joints = ("--pose-topic", "/joint_states", "--joints", "ptu_pan,ptu_tilt")
    for args, words in [
        ((bag, *joints, "-o", out), "a bag needs --topic, its image topic (the bag's image "
         "topics: /camera/image_raw, /camera/image_raw/compressed, /other/image_raw)"),
        ((bag, "--topic", "/camera/image", *joints, "-o", out),
         "--topic '/camera/image': is not in the bag (the bag's image topics: "
         "/camera/image_raw"),
        ((bag, "--topic", "/camera/camera_info", *joints, "-o", out),
         "is sensor_msgs/msg/CameraInfo, not an image topic"),
        ((bag, "--topic", "/camera/image_raw", "-o", out), "a bag needs its poses"),
        ((bag, "--topic", "/camera/image_raw", "--pose-topic", "/joint_states", "-o", out),
         "is a JointState topic: name its pan and tilt joints with --joints"),
        ((bag, "--topic", "/camera/image_raw", "--pose-topic", "/tf", "--joints", "a,b", "-o",
          out), "--joints goes with a JointState --pose-topic; /tf is TFMessage"),
        ((bag, "--topic", "/camera/image_raw", "--pose-topic", "/tf", "--wall-frame", "wall",
          "-o", out), "is a tf topic: name the chain's ends with --wall-frame and "
         "--camera-frame"),
        ((bag, "--topic", "/camera/image_raw", *joints, "--joint-signs", "1,2", "-o", out),
         "expected two of 1 and -1"),
        ((bag, "--topic", "/camera/image_raw", *joints[:2], "--joints", "pan,tilt", "-o", out),
         "no JointState on '/joint_states' names the joints 'pan' and 'tilt'"),
        ((bag, "--topic", "/camera/image_raw", "--pose-topic", "/tf", "--wall-frame", "wall",
          "--camera-frame", "nowhere", "-o", out), "no chain of transforms"),
        ((bag, "--topic", "/camera/image_raw", *joints, "--codec", "bag", "--sidecar",
          tmp_path / "s.csv", "-o", out), "--sidecar does not apply to a bag"),
        ((tmp_path / "missing.bag", "--topic", "/camera/image_raw", *joints, "-o", out),
         "missing.bag: no such file or directory"),
    ]:
        result = run_gsrwt("rectify", *args)
        assert result.returncode == 2, (args, result.stderr)
        assert "Traceback" not in result.stderr
        errors = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
        assert len(errors) == 1 and words in errors[0], (words, result.stderr)
    assert not out.exists()
    video = run_gsrwt("rectify", tmp_path / "x.mkv", "--poses", tmp_path / "p.csv",
                      "--codec", "bag", "-o", out)
    assert video.returncode == 2 and "--codec" in video.stderr


def test_commands_that_read_no_bags_say_so(tmp_path: Path, renders) -> None:
    """A real bag given to a command other than rectify: a usage error naming the bag and the
    command that reads it (it was read as an image, 'not an image gsrwt can decode')."""
    bag = bag_path(tmp_path, "ros1")
    _write_bag(bag, "ros1", renders, tf=True)
    for args in (("estimate", bag, "--focal", "500"), ("lines", bag),
                 ("match", bag, "--template", bag.with_suffix(".png")),
                 ("params", bag, "--poses", tmp_path / "p.csv", "--focal", "500")):
        result = run_gsrwt(*args)
        assert result.returncode == 2, (args, result.stderr)
        assert result.stderr.splitlines()[-1] == (
            f"Error: {bag}: gsrwt {args[0]} reads no ROS bags; gsrwt rectify does, their poses "
            f"from --pose-topic or --poses"), result.stderr
    assert sorted(path.name for path in tmp_path.iterdir()) == [bag.name]


def test_a_bag_without_rosbags_says_how_to_install_it(tmp_path: Path, renders) -> None:
    """rosbags absent (a package of that name that cannot be imported, first on the path):
    one line saying how to install the extra."""
    bag = bag_path(tmp_path, "mcap")
    _write_bag(bag, "mcap", renders)
    shim = tmp_path / "shim" / "rosbags"
    shim.mkdir(parents=True)
    (shim / "__init__.py").write_text("raise ImportError('No module named rosbags')\n")
    result = run_gsrwt("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic",
                       "/joint_states", "--joints", "ptu_pan,ptu_tilt", "-o", tmp_path / "o",
                       env={"PYTHONPATH": str(shim.parent)})
    assert result.returncode == 2, result.stderr
    assert "pip install 'gsrwt[ros]'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_killed_mid_bag_leaves_no_bag_and_a_rerun_completes(tmp_path: Path,
                                                            renders) -> None:
    many = 240
    big = [cv2.resize(image, (WIDTH * 3, HEIGHT * 3)) for image in renders]
    bag = bag_path(tmp_path, "mcap", "long")
    _write_bag(bag, "mcap", big, count=many, joint_frames=[0, many - 1],
               camera_info=False)
    out = tmp_path / "out"
    args = ("rectify", bag, "--topic", "/camera/image_raw", "--pose-topic", "/joint_states",
            "--joints", "ptu_pan,ptu_tilt", "--focal", str(3 * FOCAL), "--codec", "bag",
            "--max-pose-gap", "100", "-o", out, "-j", "1")
    process = start_gsrwt(*args)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        partial = [p for p in out.rglob("*") if ".gsrwt-" in str(p) and p.is_file()
                   and p.stat().st_size > 100_000] if out.is_dir() else []
        if partial:
            break
        time.sleep(0.02)
    else:
        raise AssertionError("the bag was never being written")
    os.kill(process.pid, signal.SIGKILL)
    process.wait(30)
    assert not (out / "long").exists()
    assert not (out / "long.csv").exists()
    result = run_gsrwt(*args)
    assert result.returncode == 0, result.stderr
    rows = read_table(out / "long.csv")
    assert len(rows) == many and {row["status"] for row in rows} == {"ok"}
    assert not [p for p in out.iterdir() if ".gsrwt-" in p.name]
    from rosbags.highlevel import AnyReader

    with AnyReader([out / "long"]) as reader:
        assert sum(1 for c in reader.connections for _ in reader.messages([c])) == 2 * many
