"""ROS bags (gsrwt_cli/inputs/bags.py): bags written by rosbags' own writers (ROS 1, ROS 2
sqlite3 and MCAP) hold renders of a wall through the words-built camera at the known poses of
a pan-tilt sweep (tests/helpers/bags.py), with those poses published as each message type
means them; read back, the pixels, the camera and the poses are what was written."""

from __future__ import annotations

import math
import os
import re
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("rosbags")

from gsrwt_cli.geometry.camera import Intrinsics  # noqa: E402
from gsrwt_cli.geometry.lens import Lens  # noqa: E402
from gsrwt_cli.geometry.rotations import pose_from_rotation  # noqa: E402
from gsrwt_cli.inputs import bags  # noqa: E402
from gsrwt_cli.inputs.bags import (  # noqa: E402
    BagError,
    DamagedBagError,
    FrameError,
    NoCameraInfoError,
    camera_info,
    camera_info_topic_of,
    image_frames,
    pose_samples,
    write_bag,
)
from gsrwt_cli.inputs.calibration import intrinsics_close  # noqa: E402
from tests.helpers.bags import (  # noqa: E402
    FOCAL,
    FRAME_STEP_NS,
    HEIGHT,
    KINDS,
    LINK_FROM_OPTICAL,
    LOG_DELAY_NS,
    SWEEP,
    WALL_FROM_BASE,
    WIDTH,
    bag_builder,
    bag_path,
    rendered_frames,
    ros_quaternion,
    wall_from_optical,
    world_from_body,
)

K = np.array([[FOCAL, 0.25, 31.5], [0.0, FOCAL + 1.0, 23.0], [0.0, 0.0, 1.0]])
#: The camera_info of each image topic: (model, D).
CAMERAS = {
    "/camera": ("plumb_bob", [0.1, -0.05, 0.001, -0.002, 0.01]),
    "/jpeg": ("rational_polynomial", [0.1, -0.05, 0.001, -0.002, 0.01, 0.02, 0.003, 0.0004]),
    "/fisheye": ("equidistant", [0.05, -0.01, 0.002, -0.0003]),
}
CORRUPT_FRAME = 2


def _expected_raw() -> dict[str, tuple[str, list[np.ndarray], list[np.ndarray], dict]]:
    """Each raw topic: (encoding, what is stored, what must come back, Image options)."""
    colour, grey = rendered_frames(3), rendered_frames(1)
    alpha = [np.full((HEIGHT, WIDTH, 1), 40 * i + 7, np.uint8) for i in range(len(SWEEP))]
    bgra = [np.concatenate([c, a], axis=2) for c, a in zip(colour, alpha)]
    deep = [g.astype(np.uint16) * 257 + i for i, g in enumerate(grey)]
    return {
        "/camera/image_raw": ("bgr8", colour, colour, {}),
        "/rgb/image_raw": ("rgb8", [c[..., ::-1] for c in colour], colour, {"step": 200}),
        "/mono/image_raw": ("mono8", grey, grey, {}),
        "/mono16/image_raw": ("mono16", deep, deep, {"step": 140, "bigendian": True}),
        "/bgra/image_raw": ("bgra8", bgra, bgra, {}),
        "/rgba/image_raw": ("rgba8", [b[..., [2, 1, 0, 3]] for b in bgra], bgra, {}),
    }


def _png(image: np.ndarray) -> bytes:
    return cv2.imencode(".png", image)[1].tobytes()


def _jpeg(image: np.ndarray) -> bytes:
    return cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].tobytes()


def _write_scene(path: Path, kind: str) -> None:
    """The bag every test reads: images, cameras and poses of :data:`SWEEP`."""
    colour = rendered_frames(3)
    with bag_builder(path, kind) as bag:
        types = bag.types
        for i, sample in enumerate(SWEEP):
            stamp, log = sample.stamp_ns, sample.stamp_ns + LOG_DELAY_NS
            for topic, (encoding, stored, _, options) in _expected_raw().items():
                bag.add(topic, "sensor_msgs/msg/Image", log,
                        bag.image(stamp, stored[i], encoding, **options))
            for namespace, (model, d) in CAMERAS.items():
                bag.add(f"{namespace}/camera_info", "sensor_msgs/msg/CameraInfo", log,
                        bag.camera_info(stamp, K, d, model))
            png = _png(colour[i])
            if i == CORRUPT_FRAME:
                png = png[: len(png) // 2]
            bag.add("/fisheye/image_raw/compressed", "sensor_msgs/msg/CompressedImage", log,
                    bag.compressed(stamp, png, "png"))
            bag.add("/jpeg/image_raw/compressed", "sensor_msgs/msg/CompressedImage", log,
                    bag.compressed(stamp, _jpeg(colour[i]), "rgb8; jpeg compressed bgr8"))
            bag.add("/yuv/image_raw", "sensor_msgs/msg/Image", log,
                    bag.image(stamp, colour[i][..., :2].copy(), "yuv422"))
            bag.add("/nocam/image_raw", "sensor_msgs/msg/Image", log,
                    bag.image(stamp, colour[i], "bgr8"))
            _write_poses(bag, sample, log, types)
        static = [bag.transform(SWEEP[0].stamp_ns, "wall", "ptu_base",
                                ros_quaternion(WALL_FROM_BASE)),
                  bag.transform(SWEEP[0].stamp_ns, "camera_link", "camera_optical_frame",
                                LINK_FROM_OPTICAL),
                  bag.transform(SWEEP[0].stamp_ns, "ptu_base", "wall_up",
                                ros_quaternion(WALL_FROM_BASE.T)),
                  bag.transform(SWEEP[0].stamp_ns, "map", "odom", (0.0, 0.0, 0.0, 1.0))]
        bag.add("/tf_static", "tf2_msgs/msg/TFMessage", SWEEP[0].stamp_ns, bag.tf(static))


def _write_poses(bag, sample, log: int, types) -> None:
    """The pose of ``sample`` as PoseStamped, QuaternionStamped, Imu, JointState and /tf."""
    optical = bag.quaternion(ros_quaternion(wall_from_optical(sample.pan, sample.tilt,
                                                              sample.roll)))
    point = types["geometry_msgs/msg/Point"](x=0.3, y=-0.2, z=-2.0)
    bag.add("/camera/pose", "geometry_msgs/msg/PoseStamped", log,
            types["geometry_msgs/msg/PoseStamped"](
                header=bag.header(sample.stamp_ns, "wall"),
                pose=types["geometry_msgs/msg/Pose"](position=point, orientation=optical)))
    first = sample is SWEEP[0]
    bag.add("/camera/orientation", "geometry_msgs/msg/QuaternionStamped", log,
            types["geometry_msgs/msg/QuaternionStamped"](
                header=bag.header(0 if first else sample.stamp_ns, "/wall"), quaternion=optical))
    vector = types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=9.8)
    bag.add("/imu/data", "sensor_msgs/msg/Imu", log, types["sensor_msgs/msg/Imu"](
        header=bag.header(sample.stamp_ns, "imu_link"),
        orientation=bag.quaternion(ros_quaternion(world_from_body(sample.pan, sample.tilt,
                                                                  sample.roll))),
        orientation_covariance=np.zeros(9), angular_velocity=vector,
        angular_velocity_covariance=np.zeros(9), linear_acceleration=vector,
        linear_acceleration_covariance=np.zeros(9)))
    pan, tilt = math.radians(sample.pan), math.radians(sample.tilt)
    bag.add("/joint_states", "sensor_msgs/msg/JointState", log - 1,
            bag.joint_state(sample.stamp_ns - 1, ["gripper"], [0.5]))
    bag.add("/joint_states", "sensor_msgs/msg/JointState", log,
            bag.joint_state(sample.stamp_ns, ["arm", "ptu_tilt", "ptu_pan"], [1.0, tilt, pan]))
    bag.add("/flipped/joint_states", "sensor_msgs/msg/JointState", log,
            bag.joint_state(sample.stamp_ns, ["ptu_pan", "ptu_tilt"], [-pan, tilt]))
    moving = [bag.transform(sample.stamp_ns, "ptu_base", "camera_link",
                            ros_quaternion(world_from_body(sample.pan, sample.tilt,
                                                           sample.roll))),
              bag.transform(sample.stamp_ns, "/wall", "direct_optical",
                            ros_quaternion(wall_from_optical(sample.pan, sample.tilt,
                                                             sample.roll)))]
    bag.add("/tf", "tf2_msgs/msg/TFMessage", log, bag.tf(moving))


#: Each bag kind; the quick loop (``-m "not slow"``) reads MCAP only (opening a bag parses its
#: message definitions: about 0.4 s for the scene's 20 topics).
SLOW_KINDS = [kind if kind == "mcap" else pytest.param(kind, marks=pytest.mark.slow)
              for kind in KINDS]


@pytest.fixture(scope="module", params=SLOW_KINDS)
def scene(request, tmp_path_factory) -> Path:
    path = bag_path(tmp_path_factory.mktemp(request.param), request.param)
    _write_scene(path, request.param)
    return path


def _stamps() -> list[int]:
    return [sample.stamp_ns for sample in SWEEP]


# --------------------------------------------------------------------------------------------
# Frames


@pytest.mark.parametrize("topic", list(_expected_raw()))
def test_raw_frames_come_back_exactly(scene, topic):
    _, _, expected, _ = _expected_raw()[topic]
    frames = list(image_frames(scene, topic))
    assert [frame.index for frame in frames] == list(range(len(SWEEP)))
    assert [frame.stamp_ns for frame in frames] == _stamps()  # the header's, not the log's
    assert [frame.time for frame in frames] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4],
                                                             abs=1e-9)
    for frame, image in zip(frames, expected):
        assert frame.error is None
        assert frame.pixels().dtype == image.dtype
        assert frame.pixels().shape == image.shape
        assert np.array_equal(frame.pixels(), image)


def test_frames_are_read_one_at_a_time(scene):
    frames = image_frames(scene, "/camera/image_raw")
    first = next(frames)
    assert first.index == 0 and first.pixels().shape == (HEIGHT, WIDTH, 3)
    frames.close()  # the reader closes with the generator


def test_a_rerun_starts_at_a_frame_with_times_from_the_first(scene):
    frames = list(image_frames(scene, "/fisheye/image_raw/compressed", start=3))
    assert [frame.index for frame in frames] == [3, 4]
    assert [frame.time for frame in frames] == pytest.approx([0.3, 0.4], abs=1e-9)
    assert np.array_equal(frames[0].pixels(), rendered_frames(3)[3])


def test_compressed_frames_and_a_corrupt_one(scene):
    colour = rendered_frames(3)
    frames = list(image_frames(scene, "/fisheye/image_raw/compressed"))
    assert len(frames) == len(SWEEP)
    for frame, image in zip(frames, colour):
        if frame.index == CORRUPT_FRAME:
            assert frame.image is None
            assert "frame 2" in frame.error and "png" in frame.error.lower()
            assert "\n" not in frame.error
            with pytest.raises(FrameError, match="frame 2"):
                frame.pixels()
        else:
            assert np.array_equal(frame.pixels(), image)  # PNG is lossless
    jpeg = list(image_frames(scene, "/jpeg/image_raw/compressed"))
    for frame, image in zip(jpeg, colour):
        reference = cv2.imdecode(np.frombuffer(_jpeg(image), np.uint8), cv2.IMREAD_UNCHANGED)
        difference = np.abs(frame.pixels().astype(int) - reference.astype(int))
        assert frame.pixels().shape == (HEIGHT, WIDTH, 3) and difference.max() <= 2


def test_an_unknown_encoding_is_one_line_naming_it(scene):
    with pytest.raises(BagError) as error:
        list(image_frames(scene, "/yuv/image_raw"))
    message = str(error.value)
    assert "yuv422" in message and "/yuv/image_raw" in message and "\n" not in message


def test_a_missing_or_wrong_topic(scene):
    with pytest.raises(BagError, match="no topic '/nothing'.*/camera/image_raw"):
        list(image_frames(scene, "/nothing"))
    with pytest.raises(BagError, match="holds sensor_msgs/msg/CameraInfo, not an image"):
        list(image_frames(scene, "/camera/camera_info"))


def test_a_raw_image_shorter_than_its_size_is_a_frame_error(tmp_path):
    path = bag_path(tmp_path, "mcap")
    colour = rendered_frames(3)
    with bag_builder(path, "mcap") as bag:
        for i, sample in enumerate(SWEEP[:3]):
            message = bag.image(sample.stamp_ns, colour[i], "bgr8")
            if i == 1:
                message.data = message.data[:-5]
            bag.add("/camera/image_raw", "sensor_msgs/msg/Image", sample.stamp_ns, message)
    frames = list(image_frames(path, "/camera/image_raw"))
    assert [frame.error is None for frame in frames] == [True, False, True]
    assert "9211 bytes" in frames[1].error
    assert np.array_equal(frames[2].pixels(), colour[2])


def test_a_ros2_bag_without_message_definitions(tmp_path):
    """sqlite3 bags recorded by Foxy to Humble hold no message definitions; the standard
    messages are read all the same."""
    import sqlite3

    path = bag_path(tmp_path, "sqlite3")
    colour = rendered_frames(3)
    with bag_builder(path, "sqlite3") as bag:
        for sample, image in zip(SWEEP, colour):
            bag.add("/camera/image_raw", "sensor_msgs/msg/Image", sample.stamp_ns,
                    bag.image(sample.stamp_ns, image, "bgr8"))
    (database,) = path.glob("*.db3")
    with sqlite3.connect(database) as connection:
        connection.execute("DELETE FROM message_definitions")
    frames = list(image_frames(path, "/camera/image_raw"))
    assert len(frames) == len(SWEEP)
    assert all(np.array_equal(f.pixels(), image) for f, image in zip(frames, colour))


def _long_bag(directory: Path, kind: str, count: int = 40) -> tuple[Path, Path]:
    """A bag of ``count`` frames of the sweep's renders, and the file that holds them."""
    path = bag_path(directory, kind)
    colour = rendered_frames(3)
    with bag_builder(path, kind) as bag:
        for i in range(count):
            stamp = SWEEP[0].stamp_ns + i * FRAME_STEP_NS
            bag.add("/camera/image_raw", "sensor_msgs/msg/Image", stamp,
                    bag.image(stamp, colour[i % len(colour)], "bgr8"))
    data = path if kind == "ros1" else next(p for p in path.iterdir() if p.suffix != ".yaml")
    return path, data


@pytest.mark.parametrize("kind", SLOW_KINDS)
def test_a_truncated_bag_is_one_line(tmp_path, kind):
    """A recording killed mid-write: the bag cannot be opened (no index, no end magic, a
    malformed database), said in one line."""
    path, data = _long_bag(tmp_path, kind)
    os.truncate(data, data.stat().st_size // 2)
    with pytest.raises(BagError, match="cannot be read as a ROS bag") as error:
        list(image_frames(path, "/camera/image_raw"))
    assert "\n" not in str(error.value)


def test_a_bag_damaged_mid_stream_gives_its_frames_then_the_damage(tmp_path):
    path, data = _long_bag(tmp_path, "ros1")
    with open(data, "r+b") as handle:
        handle.seek(data.stat().st_size // 2)
        handle.write(b"\xff" * 50_000)
    colour = rendered_frames(3)
    read = []
    with pytest.raises(DamagedBagError, match="damaged at message") as error:
        for frame in image_frames(path, "/camera/image_raw"):
            read.append(frame)
    assert 10 < len(read) < 40 and error.value.index == len(read)
    # ROS 1 has no checksums: frames whose bytes were overwritten read as other pixels; the
    # first ten lie well before the damage
    assert all(np.array_equal(f.pixels(), colour[f.index % len(colour)]) for f in read[:10])


def test_not_a_bag(tmp_path):
    path = tmp_path / "walk.bag"
    path.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 10)
    with pytest.raises(BagError, match="walk.bag: cannot be read as a ROS bag"):
        list(image_frames(path, "/camera/image_raw"))
    with pytest.raises(BagError, match="no such file"):
        camera_info(tmp_path / "missing.bag", "/camera/image_raw")


def test_without_rosbags_the_error_names_the_extra(scene, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags", None)
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(BagError, match=r"pip install 'gsrwt\[ros\]'"):
        list(image_frames(scene, "/camera/image_raw"))


# --------------------------------------------------------------------------------------------
# The camera


@pytest.mark.parametrize("topic", ["/camera/image_raw", "/jpeg/image_raw/compressed",
                                   "/fisheye/image_raw/compressed"])
def test_camera_info_is_the_camera_written(scene, topic):
    namespace = topic.split("/")[1]
    model, d = CAMERAS[f"/{namespace}"]
    camera = camera_info(scene, topic)
    names = {"plumb_bob": ("k1", "k2", "p1", "p2", "k3"),
             "rational_polynomial": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
             "equidistant": ("k1", "k2", "k3", "k4")}[model]
    written = Intrinsics(fx=K[0, 0], fy=K[1, 1], cx=K[0, 2], cy=K[1, 2], skew=K[0, 1],
                         width=WIDTH, height=HEIGHT, lens=Lens(model, tuple(zip(names, d))))
    assert camera.lens is not None and camera.lens.model == model
    assert intrinsics_close(camera, written, 1e-12)
    assert np.array_equal(camera.matrix(), K)


def test_camera_info_topic_named_and_topic_rule(scene):
    assert camera_info_topic_of("/camera/image_raw") == "/camera/camera_info"
    assert camera_info_topic_of("/camera/image_raw/compressed") == "/camera/camera_info"
    assert camera_info_topic_of("/a/b/image_rect") == "/a/b/camera_info"
    assert camera_info_topic_of("/image") == "/camera_info"
    camera = camera_info(scene, "/nocam/image_raw", "/fisheye/camera_info")
    assert camera.lens.model == "equidistant"


def test_no_camera_info_is_one_line_saying_what_to_give(scene):
    with pytest.raises(NoCameraInfoError) as error:
        camera_info(scene, "/nocam/image_raw")
    message = str(error.value)
    assert "\n" not in message
    assert "no sensor_msgs/CameraInfo on '/nocam/camera_info'" in message
    assert "'/camera/camera_info'" in message  # the ones it has
    assert "camera_info topic, or give the camera's intrinsics" in message
    assert error.value.topic == "/nocam/camera_info"


def test_camera_info_that_changes_or_is_binned_or_uncalibrated_is_refused(tmp_path):
    path = bag_path(tmp_path, "mcap")
    other = K.copy()
    other[0, 0] += 1
    model, d = CAMERAS["/camera"]
    with bag_builder(path, "mcap") as bag:
        for sample, k in zip(SWEEP[:2], (K, other)):
            bag.add("/a/camera_info", "sensor_msgs/msg/CameraInfo", sample.stamp_ns,
                    bag.camera_info(sample.stamp_ns, k, d, model))
        binned = bag.camera_info(SWEEP[0].stamp_ns, K, d, model)
        binned.binning_x = 2
        bag.add("/b/camera_info", "sensor_msgs/msg/CameraInfo", SWEEP[0].stamp_ns, binned)
        bag.add("/c/camera_info", "sensor_msgs/msg/CameraInfo", SWEEP[0].stamp_ns,
                bag.camera_info(SWEEP[0].stamp_ns, np.zeros((3, 3)), [], ""))
    faults = {"/a/image": "the camera on '/a/camera_info' changes at message 1",
              "/b/image": "has binning 2x1",
              "/c/image": "/c/camera_info: key 'K': all zeros: an uncalibrated camera"}
    for topic, message in faults.items():
        with pytest.raises(BagError, match=re.escape(message)):
            camera_info(path, topic)


# --------------------------------------------------------------------------------------------
# Poses


def _assert_sweep(samples, stamps=None) -> None:
    assert list(samples.stamps_ns) == (stamps or _stamps())
    assert samples.world_from_camera.shape == (len(SWEEP), 3, 3)
    for pose, sample in zip(samples.poses(), SWEEP):
        expected_roll = sample.roll if samples.message_type != bags.JOINT_STATE else 0.0
        assert pose.pan == pytest.approx(sample.pan, abs=1e-6)
        assert pose.tilt == pytest.approx(sample.tilt, abs=1e-6)
        assert pose.roll == pytest.approx(expected_roll, abs=1e-6)


def test_pose_stamped_is_the_camera_in_the_wall_frame(scene):
    samples = pose_samples(scene, "/camera/pose", wall_frame="wall")
    assert samples.message_type == "geometry_msgs/msg/PoseStamped" and not samples.constant
    _assert_sweep(samples)


def test_pose_stamped_in_another_frame_is_refused(scene):
    with pytest.raises(BagError, match="header.frame_id is 'wall', not the wall frame 'door'"):
        pose_samples(scene, "/camera/pose", wall_frame="door")


def test_quaternion_stamped_and_an_unset_stamp(scene):
    samples = pose_samples(scene, "/camera/orientation", wall_frame="wall")
    # the first message's stamp is 0 (unset): its log time stands in
    _assert_sweep(samples, [SWEEP[0].stamp_ns + LOG_DELAY_NS] + _stamps()[1:])


def test_imu_orientation(scene):
    _assert_sweep(pose_samples(scene, "/imu/data"))


def test_joint_state_of_a_pan_tilt_sweep(scene):
    samples = pose_samples(scene, "/joint_states", joints=("ptu_pan", "ptu_tilt"))
    _assert_sweep(samples)  # the gripper's messages are skipped
    flipped = pose_samples(scene, "/flipped/joint_states", joints=("ptu_pan", "ptu_tilt"),
                           joint_signs=(-1, 1))
    _assert_sweep(flipped)
    unflipped = pose_samples(scene, "/flipped/joint_states", joints=("ptu_pan", "ptu_tilt"))
    assert unflipped.poses()[0].pan == pytest.approx(-SWEEP[0].pan, abs=1e-6)


def test_joint_state_without_the_named_joints(scene):
    with pytest.raises(BagError) as error:
        pose_samples(scene, "/joint_states", joints=("pan_joint", "tilt_joint"))
    message = str(error.value)
    assert "no JointState on '/joint_states' names the joints 'pan_joint' and 'tilt_joint'" in (
        message)
    assert "'ptu_pan'" in message and "\n" not in message
    with pytest.raises(BagError, match="names joint 'ptu_pan' but not 'tilt_joint'"):
        pose_samples(scene, "/joint_states", joints=("ptu_pan", "tilt_joint"))
    with pytest.raises(BagError, match="name its pan and tilt joints"):
        pose_samples(scene, "/joint_states")
    for signs in ((2, 1), ("up", 1), (1,), 1):
        with pytest.raises(BagError, match="two of"):
            pose_samples(scene, "/joint_states", joints=("ptu_pan", "ptu_tilt"),
                         joint_signs=signs)


@pytest.mark.parametrize("wall, camera", [
    ("wall", "camera_optical_frame"),  # through ptu_base and camera_link
    ("wall", "direct_optical"),  # parent and child
    ("wall_up", "camera_optical_frame"),  # up the tree first: wall_up is ptu_base's child
    ("/wall", "/direct_optical"),  # ROS 1's leading slashes
])
def test_tf_chains(scene, wall, camera):
    samples = pose_samples(scene, "/tf", wall_frame=wall, camera_frame=camera)
    assert samples.message_type == "tf2_msgs/msg/TFMessage"
    _assert_sweep(samples)


def test_ros1_tf_messages_of_the_old_type(tmp_path):
    path = bag_path(tmp_path, "ros1")
    with bag_builder(path, "ros1") as bag:
        for sample in SWEEP:
            q = ros_quaternion(wall_from_optical(sample.pan, sample.tilt, sample.roll))
            bag.add("/tf", "tf/msg/tfMessage", sample.stamp_ns,
                    bag.tf([bag.transform(sample.stamp_ns, "/wall", "/optical", q)],
                           "tf/msg/tfMessage"))
    _assert_sweep(pose_samples(path, "/tf", wall_frame="wall", camera_frame="optical"))


def test_tf_quaternions_are_checked_on_the_chain_only(tmp_path):
    path = bag_path(tmp_path, "mcap")
    with bag_builder(path, "mcap") as bag:
        for i, sample in enumerate(SWEEP):
            q = ros_quaternion(wall_from_optical(sample.pan, sample.tilt, sample.roll))
            bad = (0.0, 0.0, 0.0, 2.0)
            bag.add("/tf", "tf2_msgs/msg/TFMessage", sample.stamp_ns, bag.tf([
                bag.transform(sample.stamp_ns, "wall", "optical", bad if i == 3 else q),
                bag.transform(sample.stamp_ns, "map", "odom", bad)]))
        bag.add("/tf_static", "tf2_msgs/msg/TFMessage", sample.stamp_ns, bag.tf([
            bag.transform(sample.stamp_ns, "wall", "fixed", bad)]))
    with pytest.raises(BagError, match="'/tf' message 3, transform 'wall' -> 'optical': the "
                                       "quaternion .* is not a unit quaternion"):
        pose_samples(path, "/tf", wall_frame="wall", camera_frame="optical")
    with pytest.raises(BagError, match="'/tf_static' message 0, transform 'wall' -> 'fixed'"):
        pose_samples(path, "/tf", wall_frame="wall", camera_frame="fixed")


def test_tf_of_static_transforms_only_is_constant(scene):
    samples = pose_samples(scene, "/tf", wall_frame="wall", camera_frame="wall_up")
    assert samples.constant and len(samples) == 1
    assert np.allclose(samples.world_from_camera[0], np.eye(3), atol=1e-12)


def test_tf_chain_that_does_not_connect(scene):
    with pytest.raises(BagError) as error:
        pose_samples(scene, "/tf", wall_frame="wall", camera_frame="odom")
    message = str(error.value)
    assert "no chain of transforms on /tf and /tf_static connects the wall frame 'wall' to " \
           "the camera frame 'odom'" in message
    assert "'camera_link'" in message and "\n" not in message
    with pytest.raises(BagError, match="name the wall frame and the camera's optical frame"):
        pose_samples(scene, "/tf", wall_frame="wall")


def test_poses_out_of_order_come_sorted_and_a_bad_quaternion_is_refused(tmp_path):
    path = bag_path(tmp_path, "mcap")
    order = [2, 0, 4, 1, 3]
    with bag_builder(path, "mcap") as bag:
        for i in order:
            sample = SWEEP[i]
            q = ros_quaternion(wall_from_optical(sample.pan, sample.tilt, sample.roll))
            bag.add("/pose", "geometry_msgs/msg/QuaternionStamped", SWEEP[0].stamp_ns,
                    bag.types["geometry_msgs/msg/QuaternionStamped"](
                        header=bag.header(sample.stamp_ns, "wall"), quaternion=bag.quaternion(q)))
            bag.add("/bad", "geometry_msgs/msg/QuaternionStamped", SWEEP[0].stamp_ns,
                    bag.types["geometry_msgs/msg/QuaternionStamped"](
                        header=bag.header(sample.stamp_ns, "wall"),
                        quaternion=bag.quaternion((0.0, 0.0, 0.0, 2.0 if i == 4 else 1.0))))
    _assert_sweep(pose_samples(path, "/pose"))
    with pytest.raises(BagError, match="'/bad' message 2: the quaternion .* is not a unit"):
        pose_samples(path, "/bad")


def test_a_pose_topic_of_another_type(scene):
    with pytest.raises(BagError, match="holds sensor_msgs/msg/Image, not a pose topic"):
        pose_samples(scene, "/camera/image_raw")


def test_poses_agree_with_the_package_frames_hand_worked():
    """The helper's construction against POSES.md's hand-worked pan = 30: the wall in the
    camera is ``q = (cos 15°, 0, sin 15°, 0)``, so the camera in the wall is its conjugate."""
    x, y, z, w = ros_quaternion(wall_from_optical(30.0, 0.0, 0.0))
    assert (w, x, y, z) == pytest.approx((math.cos(math.radians(15)), 0.0,
                                          -math.sin(math.radians(15)), 0.0), abs=1e-12)
    pose = pose_from_rotation(np.eye(3))
    assert (pose.pan, pose.tilt, pose.roll) == (0.0, 0.0, 0.0)


# --------------------------------------------------------------------------------------------
# Writing


@pytest.mark.parametrize("kind", SLOW_KINDS)
def test_write_bag_round_trip(tmp_path, kind):
    colour = rendered_frames(3)
    deep = [g.astype(np.uint16) * 257 for g in rendered_frames(1)]
    output = Intrinsics(fx=FOCAL, fy=FOCAL, cx=30.0, cy=20.5, width=WIDTH, height=HEIGHT)
    path = bag_path(tmp_path, kind, "rectified")
    storage = "sqlite3" if kind == "sqlite3" else "mcap"
    count = write_bag(path, "/rectified/image", ((s.stamp_ns, image) for s, image in
                                                 zip(SWEEP, colour)), output, storage=storage)
    assert count == len(SWEEP)
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left
    frames = list(image_frames(path, "/rectified/image"))
    assert [frame.stamp_ns for frame in frames] == _stamps()
    for frame, image in zip(frames, colour):
        assert np.array_equal(frame.pixels(), image)
    camera = camera_info(path, "/rectified/image")
    assert camera.lens is None and np.array_equal(camera.matrix(), output.matrix())
    assert (camera.width, camera.height) == (WIDTH, HEIGHT)
    # 16-bit grey, a camera per frame
    other = bag_path(tmp_path, kind, "deep")
    per_frame = Intrinsics(fx=60.0, fy=61.0, cx=31.5, cy=23.5)
    write_bag(other, "/deep/image", [(s.stamp_ns, image, per_frame)
                                     for s, image in zip(SWEEP, deep)], None, storage=storage)
    assert all(np.array_equal(f.pixels(), image)
               for f, image in zip(image_frames(other, "/deep/image"), deep))
    assert camera_info(other, "/deep/image").fy == 61.0


def test_write_bag_compressed(tmp_path):
    colour = rendered_frames(3)
    deep = [g.astype(np.uint16) * 257 + 3 for g in rendered_frames(1)]
    camera = Intrinsics(fx=FOCAL, fy=FOCAL, cx=30.0, cy=20.5)
    png = tmp_path / "png"
    write_bag(png, "/frontal/image/compressed", zip(_stamps(), deep), camera.matrix(),
              compression="png")
    frames = list(image_frames(png, "/frontal/image/compressed"))
    assert all(np.array_equal(f.pixels(), image) for f, image in zip(frames, deep))
    assert [f.stamp_ns for f in frames] == _stamps()
    assert camera_info(png, "/frontal/image/compressed").cx == 30.0
    jpeg = tmp_path / "jpeg.bag"
    write_bag(jpeg, "/frontal/image/compressed", zip(_stamps(), colour), camera,
              compression="jpeg", quality=90)
    for frame, image in zip(image_frames(jpeg, "/frontal/image/compressed"), colour):
        reference = cv2.imdecode(cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 90])[1],
                                 cv2.IMREAD_UNCHANGED)
        assert np.abs(frame.pixels().astype(int) - reference.astype(int)).max() <= 2
    with pytest.raises(BagError, match="frame 0: cannot write it as jpeg"):
        write_bag(tmp_path / "deep", "/deep", zip(_stamps(), deep), camera,
                  compression="jpeg")
    with pytest.raises(BagError, match=r"frame 0: the camera matrix must be \[\[fx"):
        write_bag(tmp_path / "bad", "/a", zip(_stamps(), deep), np.eye(3)[::-1])
    for topic in ("/frontal/2image", "frontal image", "/frontal//image", ""):
        with pytest.raises(BagError, match="is not a ROS topic name"):
            write_bag(tmp_path / "bad", topic, [], camera)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["jpeg.bag", "png"]


def test_write_bag_never_overwrites_and_leaves_nothing_when_it_fails(tmp_path):
    path = tmp_path / "out.bag"
    path.write_bytes(b"mine")
    camera = Intrinsics(fx=FOCAL, fy=FOCAL, cx=30.0, cy=20.5)
    with pytest.raises(BagError, match="exists"):
        write_bag(path, "/image", [], camera)
    assert path.read_bytes() == b"mine"
    failing = tmp_path / "failing"
    bad = [(SWEEP[0].stamp_ns, rendered_frames(3)[0]), (SWEEP[1].stamp_ns, np.zeros((4, 4, 2)))]
    with pytest.raises(BagError, match="frame 1: cannot write an image of shape"):
        write_bag(failing, "/image", bad, camera)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bag"]


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_frames_are_read_in_bounded_memory(tmp_path, kind):
    """40 frames of 640x480 BGR (37 MB): reading them all holds about the reader's chunks
    and a frame (measured: peaks of 4-10 MB, whatever the bag's length: docs/BAGS.md)."""
    import tracemalloc

    path = bag_path(tmp_path, kind)
    image = np.random.default_rng(1).integers(0, 256, (480, 640, 3), dtype=np.uint8)
    count = 40
    with bag_builder(path, kind) as bag:
        for i in range(count):
            stamp = SWEEP[0].stamp_ns + i * 33_000_000
            bag.add("/camera/image_raw", "sensor_msgs/msg/Image", stamp,
                    bag.image(stamp, image, "bgr8"))
    tracemalloc.start()
    try:
        read = sum(1 for frame in image_frames(path, "/camera/image_raw")
                   if np.array_equal(frame.pixels(), image))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert read == count
    assert peak < 14 * image.nbytes, f"peak {peak / 1e6:.1f} MB"
