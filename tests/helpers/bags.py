"""ROS bags written by rosbags' own writers (ROS 1, ROS 2 sqlite3 and MCAP), with messages
built here, independently of the package: renders of a wall through the words-built camera
(:mod:`tests.helpers.camera`) at known poses of a pan-tilt sweep, and the ROS rotations of
those poses as SciPy turns matrices into quaternions.

The frames are written out from their words, not from gsrwt's formulas:

- OpenCV wall frame (the wall frame of ROS messages here): x right, y down, z into the wall.
- Camera optical frame: x right, y down, z forward.
- ROS body frames (REP 103: an Imu, ``ptu_base``, ``camera_link``): x forward, y left, z up.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from tests.helpers.camera import camera_axes, render_view
from tests.helpers.images import smooth_texture

#: The bag kinds: ROS 1, ROS 2 with each storage plugin.
KINDS = ("ros1", "sqlite3", "mcap")
#: The first frame's stamp, and the delay between the stamp and the log time of every message
#: (a recorder logs a message after the camera stamped it).
START_NS = 1_700_000_000_123_456_789
LOG_DELAY_NS = 3_000_000
FRAME_STEP_NS = 100_000_000
WIDTH, HEIGHT, FOCAL = 64, 48, 50.0


@dataclass(frozen=True)
class Sample:
    """One frame of the sweep: its stamp and the camera's pose (degrees)."""

    stamp_ns: int
    pan: float
    tilt: float
    roll: float


#: A pan-tilt sweep: panning from right to left while tilting up then down, a little roll.
SWEEP = tuple(
    Sample(START_NS + i * FRAME_STEP_NS, pan, tilt, roll)
    for i, (pan, tilt, roll) in enumerate(
        [(-25.0, 5.0, 0.0), (-12.5, 12.0, 3.0), (0.0, 18.0, -4.0), (12.5, 12.0, 7.5),
         (25.0, 5.0, -2.0)]
    )
)


def rendered_frames(channels: int = 3) -> list[np.ndarray]:
    """What the camera sees of a textured wall at each pose of :data:`SWEEP` (8-bit)."""
    texture = smooth_texture(160, 200, seed=7, channels=channels)
    frames = []
    for sample in SWEEP:
        image, _, _ = render_view(texture, sample.pan, sample.tilt, FOCAL, WIDTH, HEIGHT,
                                  (WIDTH - 1) / 2, (HEIGHT - 1) / 2, roll=sample.roll)
        frames.append(np.ascontiguousarray(image, dtype=np.uint8))
    return frames


def _columns(*vectors: np.ndarray) -> np.ndarray:
    return np.column_stack(vectors)


def wall_from_optical(pan: float, tilt: float, roll: float) -> np.ndarray:
    """The camera's optical axes (x right, y down, z forward) in the OpenCV wall frame."""
    up, right, forward = camera_axes(pan, tilt, roll)  # in the thesis world: X up, Y right

    def in_wall(v: np.ndarray) -> np.ndarray:  # thesis world -> OpenCV wall: right, down, in
        return np.array([v[1], -v[0], v[2]])

    return _columns(in_wall(right), in_wall(-up), in_wall(forward))


def world_from_body(pan: float, tilt: float, roll: float) -> np.ndarray:
    """The camera's ROS body axes (x forward, y left, z up) in a ROS world frame whose x
    faces the wall squarely (x into the wall, y left, z up)."""
    up, right, forward = camera_axes(pan, tilt, roll)

    def in_world(v: np.ndarray) -> np.ndarray:  # thesis world -> ROS world: in, left, up
        return np.array([v[2], -v[1], v[0]])

    return _columns(in_world(forward), in_world(-right), in_world(up))


def ros_quaternion(matrix: np.ndarray) -> tuple[float, float, float, float]:
    """``(x, y, z, w)`` of a rotation matrix, as SciPy computes it (ROS's order)."""
    x, y, z, w = Rotation.from_matrix(matrix).as_quat()
    return float(x), float(y), float(z), float(w)


#: ``camera_link`` (REP 103) -> ``camera_optical_frame``: the rotation every ROS camera driver
#: publishes (``static_transform_publisher 0 0 0 -1.5708 0 -1.5708``), as a quaternion.
LINK_FROM_OPTICAL = (-0.5, 0.5, -0.5, 0.5)
#: ``ptu_base`` (x into the wall, y left, z up) in the OpenCV wall frame (x right, y down,
#: z into the wall): its x is the wall's z, its y (left) the wall's -x, its z (up) the wall's -y.
WALL_FROM_BASE = _columns(np.array([0.0, 0, 1]), np.array([-1.0, 0, 0]), np.array([0.0, -1, 0]))


class BagBuilder:
    """A bag being written by rosbags: ``add(topic, msgtype, log_ns, message)``; messages
    built from :attr:`types` (``builder.types['sensor_msgs/msg/Image'](...)``) and
    :meth:`header`."""

    def __init__(self, path: Path, kind: str) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.kind = kind
        self.ros1 = kind == "ros1"
        self.typestore = get_typestore(Stores.ROS1_NOETIC if self.ros1 else Stores.ROS2_HUMBLE)
        if self.ros1:  # rosbags' noetic store has neither tf message
            from rosbags.typesys import get_types_from_msg

            for name in ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage"):
                self.typestore.register(get_types_from_msg(
                    "geometry_msgs/TransformStamped[] transforms", name))
        self.types = self.typestore.types
        if self.ros1:
            from rosbags.rosbag1 import Writer

            self.writer = Writer(path)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer

            plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
            self.writer = Writer(path, version=8, storage_plugin=plugin)
        self.connections: dict[tuple[str, str], Any] = {}

    def header(self, stamp_ns: int, frame_id: str = "camera_optical_frame") -> Any:
        stamp = self.types["builtin_interfaces/msg/Time"](
            sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
        extra = {"seq": 0} if self.ros1 else {}
        return self.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id, **extra)

    def quaternion(self, xyzw: tuple[float, float, float, float]) -> Any:
        x, y, z, w = xyzw
        return self.types["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w)

    def add(self, topic: str, msgtype: str, log_ns: int, message: Any) -> None:
        key = (topic, msgtype)
        if key not in self.connections:
            self.connections[key] = self.writer.add_connection(topic, msgtype,
                                                               typestore=self.typestore)
        serialize = self.typestore.serialize_ros1 if self.ros1 else self.typestore.serialize_cdr
        self.writer.write(self.connections[key], log_ns, serialize(message, msgtype))

    def image(self, stamp_ns: int, pixels: np.ndarray, encoding: str, step: int | None = None,
              bigendian: bool = False) -> Any:
        """A ``sensor_msgs/Image`` of ``pixels`` as stored (already in ``encoding``'s channel
        order), rows padded to ``step`` bytes."""
        height, width = pixels.shape[:2]
        dtype = pixels.dtype.newbyteorder(">" if bigendian else "<")
        rows = np.ascontiguousarray(pixels, dtype=dtype).reshape(height, -1).view(np.uint8)
        step = step or rows.shape[1]
        padded = np.zeros((height, step), np.uint8)
        padded[:, :rows.shape[1]] = rows
        return self.types["sensor_msgs/msg/Image"](
            header=self.header(stamp_ns), height=height, width=width, encoding=encoding,
            is_bigendian=int(bigendian), step=step, data=padded.reshape(-1))

    def compressed(self, stamp_ns: int, data: bytes, form: str) -> Any:
        return self.types["sensor_msgs/msg/CompressedImage"](
            header=self.header(stamp_ns), format=form, data=np.frombuffer(data, np.uint8))

    def camera_info(self, stamp_ns: int, k: np.ndarray, d: list[float], model: str,
                    width: int = WIDTH, height: int = HEIGHT) -> Any:
        fields = {"d": np.asarray(d, float), "k": np.asarray(k, float).ravel(),
                  "r": np.eye(3).ravel(), "p": np.hstack([k, np.zeros((3, 1))]).ravel()}
        if self.ros1:
            fields = {key.upper(): value for key, value in fields.items()}
        roi = self.types["sensor_msgs/msg/RegionOfInterest"](
            x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
        return self.types["sensor_msgs/msg/CameraInfo"](
            header=self.header(stamp_ns), height=height, width=width, distortion_model=model,
            binning_x=0, binning_y=0, roi=roi, **fields)

    def transform(self, stamp_ns: int, parent: str, child: str,
                  xyzw: tuple[float, float, float, float]) -> Any:
        types = self.types
        transform = types["geometry_msgs/msg/Transform"](
            translation=types["geometry_msgs/msg/Vector3"](x=0.1, y=0.0, z=0.2),
            rotation=self.quaternion(xyzw))
        return types["geometry_msgs/msg/TransformStamped"](
            header=self.header(stamp_ns, parent), child_frame_id=child, transform=transform)

    def tf(self, transforms: list[Any], msgtype: str = "tf2_msgs/msg/TFMessage") -> Any:
        return self.types[msgtype](transforms=transforms)

    def joint_state(self, stamp_ns: int, names: list[str], positions: list[float]) -> Any:
        return self.types["sensor_msgs/msg/JointState"](
            header=self.header(stamp_ns, ""), name=names,
            position=np.asarray(positions, float), velocity=np.zeros(0), effort=np.zeros(0))


@contextlib.contextmanager
def bag_builder(path: Path, kind: str) -> Iterator[BagBuilder]:
    """A :class:`BagBuilder` of ``kind`` (:data:`KINDS`), closed (written) at the end."""
    builder = BagBuilder(path, kind)
    builder.writer.open()
    yield builder
    builder.writer.close()


def bag_path(directory: Path, kind: str, name: str = "walk") -> Path:
    """Where a bag of ``kind`` goes: ``walk.bag`` for ROS 1, a directory for ROS 2."""
    return directory / (f"{name}.bag" if kind == "ros1" else name)
