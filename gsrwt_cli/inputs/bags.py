"""ROS bags: image frames, the camera of ``camera_info``, pose samples, and a rectified bag.

ROS 1 (``.bag``) and ROS 2 bags (a directory with ``metadata.yaml``, sqlite3 or MCAP, or a
bare ``.mcap`` / ``.db3`` file) are read by rosbags' ``AnyReader`` (pure Python, no ROS
install), imported on first use: without it every function raises :class:`BagError` saying
``pip install 'gsrwt[ros]'``. What each message means in gsrwt's frames is in docs/BAGS.md.

- :func:`image_frames`: the frames of a ``sensor_msgs/Image`` or ``CompressedImage`` topic,
  one at a time (a generator: memory holds one frame), in OpenCV's layout.
- :func:`camera_info`: the :class:`~gsrwt_cli.geometry.camera.Intrinsics` (lens included) of
  the ``sensor_msgs/CameraInfo`` beside an image topic.
- :func:`pose_samples`: timestamped rotations (``world_from_camera``, thesis frames) from
  ``PoseStamped``, ``QuaternionStamped``, ``Imu``, ``JointState`` or ``/tf`` + ``/tf_static``.
- :func:`write_bag`: a bag with an image topic and its ``camera_info``, written whole.
- :func:`bag_topics`, :func:`is_bag_name`: a bag's topics, and which inputs are bags.

Time
----
A message's time is its ``header.stamp`` (when the camera or sensor took it, the time tf and
every driver stamp with), or, when the stamp is zero (a driver that leaves it unset), the
time the recorder logged it. The log time includes transport and queueing delays, which
differ between topics, so it is only the fallback. Times are integers of nanoseconds;
:attr:`Frame.time` is seconds from the first frame's stamp.

Errors
------
:class:`BagError`: one line naming the bag (and the topic) and what is wrong; the bag or
topic is unusable. :class:`NoCameraInfoError` is the one for a missing ``camera_info``,
:class:`DamagedBagError` the one for data that breaks off after the bag opened (the frames
before it have been given).
A frame whose data cannot be decoded (a corrupt ``CompressedImage``, a raw image shorter than
its size says) does not stop :func:`image_frames`: its :class:`Frame` carries ``error``
instead of ``image``, and :meth:`Frame.pixels` raises :class:`FrameError` with it.

No module below ``cli/`` names a command-line flag: errors name the topics and frames, and
the CLI words them with its options.

Over 400 lines: four uses of one format (frames, the camera, poses from five message types
and tf chains, a bag written whole) sharing the opening, the walk over messages and their
errors; what a message means is here, the rotations are :mod:`~gsrwt_cli.geometry.rotations`'s.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import secrets
import shutil
from array import array
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..base.messages import one_line, quote
from ..geometry.camera import Intrinsics
from ..geometry.rotations import (
    Matrix,
    Pose,
    PoseError,
    pose_from_rotation,
    rotation_from_pose,
    rotation_from_quaternion,
    world_from_camera_from_opencv,
    world_from_camera_from_ros_body,
)
from .calibration import CalibrationError, intrinsics_from_camera_info

#: How to install what this module needs.
INSTALL_HINT = "pip install 'gsrwt[ros]'"
#: The largest raw image read, in pixels (as for image files: a damaged size, not a photo).
MAX_FRAME_PIXELS = 300e6

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
QUATERNION_STAMPED = "geometry_msgs/msg/QuaternionStamped"
IMU = "sensor_msgs/msg/Imu"
JOINT_STATE = "sensor_msgs/msg/JointState"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
#: ROS 1's older tf message (``tf/tfMessage``), the same fields.
TF_MESSAGES = (TF_MESSAGE, "tf/msg/tfMessage")
#: The message types :func:`pose_samples` reads.
POSE_TYPES = (POSE_STAMPED, QUATERNION_STAMPED, IMU, JOINT_STATE, *TF_MESSAGES)

#: Raw ``sensor_msgs/Image`` encodings read: (sample type, channels, OpenCV conversion to
#: BGR/BGRA or None). ``8UC3``/``8UC4``/``16UC3``/``16UC4`` carry no colour order; they are
#: taken as BGR(A), as cv_bridge does.
ENCODINGS: dict[str, tuple[str, int, str | None]] = {
    "mono8": ("u1", 1, None), "8UC1": ("u1", 1, None),
    "mono16": ("u2", 1, None), "16UC1": ("u2", 1, None),
    "bgr8": ("u1", 3, None), "8UC3": ("u1", 3, None),
    "rgb8": ("u1", 3, "COLOR_RGB2BGR"),
    "bgra8": ("u1", 4, None), "8UC4": ("u1", 4, None),
    "rgba8": ("u1", 4, "COLOR_RGBA2BGRA"),
    "bgr16": ("u2", 3, None), "16UC3": ("u2", 3, None),
    "rgb16": ("u2", 3, "COLOR_RGB2BGR"),
    "bgra16": ("u2", 4, None), "16UC4": ("u2", 4, None),
    "rgba16": ("u2", 4, "COLOR_RGBA2BGRA"),
}
#: The encoding :func:`write_bag` gives an array of (sample type, channels).
_ENCODING_OF = {("u1", 1): "mono8", ("u2", 1): "mono16", ("u1", 3): "bgr8",
                ("u1", 4): "bgra8", ("u2", 3): "bgr16", ("u2", 4): "bgra16"}
#: A ROS topic name: tokens of letters, digits and ``_`` (none starting with a digit).
_ROS_NAME = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
#: Sub-topics of image_transport's plugins, which share the raw topic's namespace.
_TRANSPORTS = ("compressed", "compressedDepth", "theora", "zstd")


class BagError(ValueError):
    """A bag, topic or message gsrwt cannot use: one line naming the bag and what is wrong."""


class NoCameraInfoError(BagError):
    """No ``sensor_msgs/CameraInfo`` on the topic looked for: ``bag``, ``image_topic``,
    ``topic`` (the one looked for) and ``found`` (the CameraInfo topics the bag has)."""

    def __init__(self, bag: str, image_topic: str, topic: str, found: list[str]) -> None:
        self.bag, self.image_topic, self.topic, self.found = bag, image_topic, topic, found
        others = (f"; its CameraInfo topics: {', '.join(quote(t) for t in found[:10])}"
                  if found else "; it has no CameraInfo topic")
        super().__init__(
            f"{one_line(bag, 200)}: no sensor_msgs/CameraInfo on {quote(topic)} (the camera of "
            f"{quote(image_topic)}){others}: name the camera_info topic, or give the camera's "
            "intrinsics instead"
        )


class DamagedBagError(BagError):
    """The bag could be opened but its data is damaged from message ``index`` of the topic
    on (a torn chunk, overwritten bytes): what came before it was read."""

    def __init__(self, message: str, index: int) -> None:
        super().__init__(message)
        self.index = index


class FrameError(ValueError):
    """One frame that cannot be decoded; the other frames of the topic may be fine."""


@dataclass(frozen=True)
class Frame:
    """One image of a topic.

    ``index``: its place in the topic, from 0, in the bag's order (the log time's);
    ``stamp_ns``: its time (the header stamp, else the log time: the module's docstring);
    ``time``: seconds from the first frame's ``stamp_ns`` (negative for a frame stamped
    before it); ``image``: the pixels in OpenCV's layout (grey ``(H, W)``, BGR ``(H, W, 3)``
    or BGRA ``(H, W, 4)``, uint8 or uint16), a fresh array the caller owns, or None when the
    frame cannot be decoded, and then ``error`` says why (one line).
    """

    index: int
    time: float
    stamp_ns: int
    image: np.ndarray | None
    error: str | None = None

    def pixels(self) -> np.ndarray:
        """The image; raises :class:`FrameError` with the reason when there is none."""
        if self.image is None:
            raise FrameError(self.error or f"frame {self.index} has no image")
        return self.image


@dataclass(frozen=True)
class PoseSamples:
    """A camera's orientation over time, as a pose topic gives it.

    ``stamps_ns``: ``(N,)`` int64 nanoseconds, sorted (a stable sort: samples with equal
    stamps keep the bag's order); ``world_from_camera``: ``(N, 3, 3)`` rotations in the
    thesis's frames (world: X up, Y right, Z into the wall; camera: X up, Y right, Z forward;
    docs/CONVENTIONS.md), ``rotation_from_pose(pan, tilt, roll)`` of each sample's pose;
    ``message_type``: the topic's type; ``constant``: the rotation holds at every time (a
    chain of ``/tf_static`` transforms only: one sample, stamped with its message's time).
    Rotations, not angles: interpolate them (slerp) and decompose after
    (:meth:`poses`, :func:`~gsrwt_cli.geometry.rotations.pose_from_rotation`).
    """

    stamps_ns: np.ndarray
    world_from_camera: np.ndarray
    message_type: str
    constant: bool = False

    def __len__(self) -> int:
        return len(self.stamps_ns)

    def poses(self) -> list[Pose]:
        """Each sample's pan, tilt, roll (degrees); raises
        :class:`~gsrwt_cli.geometry.rotations.PoseError` for a sample whose wall is not in
        front of the camera."""
        return [pose_from_rotation(rotation) for rotation in self.world_from_camera]


# --------------------------------------------------------------------------------------------
# Opening bags


def _rosbags() -> Any:
    """rosbags' highlevel module, imported on first use (it is an optional extra)."""
    try:
        from rosbags import highlevel
    except ImportError:
        raise BagError(f"reading ROS bags needs rosbags: {INSTALL_HINT}") from None
    return highlevel


@contextlib.contextmanager
def _open(bag: str | Path) -> Iterator[Any]:
    """An open ``AnyReader`` of ``bag``; what rosbags cannot read is a :class:`BagError`."""
    highlevel = _rosbags()
    path = Path(bag)
    name = one_line(str(bag), 200)
    if not path.exists():
        raise BagError(f"{name}: no such file or directory")
    try:
        try:
            reader = highlevel.AnyReader([path])
            reader.open()
        except highlevel.AnyReaderError as error:
            if "no type definitions" not in str(error):
                raise
            # A ROS 2 bag without message definitions (sqlite3 bags of Foxy to Humble): the
            # messages read are the same in every ROS 2 distribution.
            from rosbags.typesys import Stores, get_typestore

            reader = highlevel.AnyReader(
                [path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            reader.open()
    except Exception as error:  # rosbags raises its own errors, OSError, KeyError on bad data
        reason = one_line(str(error), 300) or type(error).__name__
        raise BagError(f"{name}: cannot be read as a ROS bag ({reason})") from None
    try:
        yield reader
    finally:
        with contextlib.suppress(Exception):
            reader.close()


def _messages(reader: Any, connections: list[Any], bag: str | Path,
              what: str) -> Iterator[tuple[int, Any, int, bytes]]:
    """``(index, connection, log_ns, raw)`` of ``connections``' messages in the bag's order;
    data rosbags cannot read raises :class:`DamagedBagError` (``what``: the topics, for the
    message), never rosbags' own errors."""
    messages = reader.messages(connections)
    index = 0
    while True:
        try:
            connection, log_ns, raw = next(messages)
        except StopIteration:
            return
        except Exception as error:
            reason = one_line(str(error), 300) or type(error).__name__
            raise DamagedBagError(
                f"{one_line(str(bag), 200)}: damaged at message {index} of {what} "
                f"({reason})", index) from None
        yield index, connection, log_ns, raw
        index += 1


def _connections(reader: Any, bag: str | Path, topic: str, types: tuple[str, ...],
                 what: str) -> list[Any]:
    """The connections of ``topic``, refused unless it is in the bag with one of ``types``."""
    found = [c for c in reader.connections if c.topic == topic]
    name = one_line(str(bag), 200)
    if not found:
        topics = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
        listed = ", ".join(topics[:12]) + (", ..." if len(topics) > 12 else "")
        raise BagError(f"{name}: no topic {quote(topic)} (its topics: {listed or 'none'})")
    wrong = sorted({c.msgtype for c in found if c.msgtype not in types})
    if wrong:
        raise BagError(f"{name}: topic {quote(topic)} holds {wrong[0]}, not {what} "
                       f"({', '.join(types)})")
    return found


def _deserialize(reader: Any, raw: bytes, connection: Any, where: str, index: int) -> Any:
    """One message, or :class:`DamagedBagError` naming it when its bytes are not one."""
    try:
        return reader.deserialize(raw, connection.msgtype)
    except Exception as error:
        reason = one_line(str(error), 200) or type(error).__name__
        raise DamagedBagError(f"{where} message {index} is damaged ({reason})", index) from None


def _stamp_ns(message: Any, log_ns: int) -> int:
    """The header stamp in nanoseconds, or the log time when the stamp is zero (unset)."""
    header = getattr(message, "header", None)
    if header is not None:
        stamp = header.stamp
        ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        if ns != 0:
            return ns
    return int(log_ns)


def _frame_name(frame_id: str) -> str:
    """A tf frame name as tf2 compares them (ROS 1's leading ``/`` dropped)."""
    return frame_id.lstrip("/")


def camera_info_topic_of(image_topic: str) -> str:
    """The ``camera_info`` topic of an image topic, as image_transport pairs them: the
    image's namespace plus ``camera_info`` (``/camera/image_raw`` -> ``/camera/camera_info``;
    ``/camera/image_raw/compressed`` -> ``/camera/camera_info`` as well)."""
    parts = image_topic.rstrip("/").split("/")
    if len(parts) > 2 and parts[-1] in _TRANSPORTS:
        parts = parts[:-1]
    return "/".join(parts[:-1] + ["camera_info"]) or "/camera_info"


def bag_topics(bag: str | Path) -> dict[str, str]:
    """Every topic of ``bag`` and its message type (the first, for a topic with several),
    sorted by name; :class:`BagError` when the bag cannot be read."""
    with _open(bag) as reader:
        topics: dict[str, str] = {}
        for connection in reader.connections:
            topics.setdefault(connection.topic, connection.msgtype)
    return dict(sorted(topics.items()))


#: The file names of bags (a ROS 2 bag may also be the directory of its ``metadata.yaml``).
BAG_EXTENSIONS = (".bag", ".mcap", ".db3")


def is_bag_name(path: str | Path) -> bool:
    """Whether ``path`` names a bag: a ``.bag``, ``.mcap`` or ``.db3`` file, or a directory
    holding a ROS 2 bag's ``metadata.yaml`` (a directory that cannot be read is not known
    to be one: it is left to the reading of directories to report)."""
    path = Path(path)
    if path.suffix.lower() in BAG_EXTENSIONS:
        return True
    try:
        return path.is_dir() and (path / "metadata.yaml").is_file()
    except OSError:  # no permission to look inside
        return False


# --------------------------------------------------------------------------------------------
# Frames


def image_frames(bag: str | Path, topic: str, start: int = 0) -> Iterator[Frame]:
    """The frames of the image topic ``topic`` of ``bag``, one at a time.

    ``sensor_msgs/Image`` in the encodings of :data:`ENCODINGS` (``mono8``, ``mono16``,
    ``bgr8``, ``rgb8``, ``bgra8``, ``rgba8``, their 16-bit twins and OpenCV's type names),
    rows padded to ``step`` and big-endian data included; colour comes back BGR or BGRA,
    exactly the samples stored. ``sensor_msgs/CompressedImage`` (JPEG, PNG, any format
    OpenCV decodes) decoded as an image file is
    (:func:`~gsrwt_cli.imaging.images.decode_image`: a damaged JPEG is an error, not a grey
    half). See :class:`Frame` for what each holds and the module's docstring for the time.

    A generator: the bag is read as frames are asked for, and memory holds one frame (and
    the reader's current chunk). Raises :class:`BagError` (from the first ``next``) when the
    bag or topic cannot be read, and for an encoding it does not read (``yuv422``, Bayer,
    ``compressedDepth``: the topic, not one frame, is at fault); a frame whose data is
    damaged comes back with ``error`` set and the frames after it are read on.

    ``start``: the index of the first frame to give (a rerun that continues): the frames
    before it are not decoded, and times stay seconds from frame 0's stamp.
    """
    with _open(bag) as reader:
        connections = _connections(reader, bag, topic, (IMAGE, COMPRESSED_IMAGE),
                                   "an image topic")
        first: int | None = None
        for index, connection, log_ns, raw in _messages(reader, connections, bag,
                                                         quote(topic)):
            try:
                message = reader.deserialize(raw, connection.msgtype)
            except Exception as error:
                stamp = int(log_ns)
                first = stamp if first is None else first
                if index < start:
                    continue
                yield Frame(index, (stamp - first) / 1e9, stamp, None,
                            f"frame {index}: damaged message ({one_line(str(error), 200)})")
                continue
            stamp = _stamp_ns(message, log_ns)
            first = stamp if first is None else first
            if index < start:
                continue
            try:
                if connection.msgtype == IMAGE:
                    image = _raw_pixels(message, bag, topic)
                else:
                    image = _compressed_pixels(message, bag, topic)
            except FrameError as error:
                yield Frame(index, (stamp - first) / 1e9, stamp, None,
                            f"frame {index}: {error}")
                continue
            yield Frame(index, (stamp - first) / 1e9, stamp, image)


def _raw_pixels(message: Any, bag: str | Path, topic: str) -> np.ndarray:
    """A ``sensor_msgs/Image``'s pixels in OpenCV's layout (a fresh array)."""
    encoding = str(message.encoding)
    if encoding not in ENCODINGS:
        raise BagError(
            f"{one_line(str(bag), 200)}: topic {quote(topic)} has image encoding "
            f"{quote(encoding, 40)}, which gsrwt does not read (it reads "
            f"{', '.join(ENCODINGS)})"
        )
    kind, channels, conversion = ENCODINGS[encoding]
    height, width, step = int(message.height), int(message.width), int(message.step)
    if height <= 0 or width <= 0:
        raise FrameError(f"the image is {width}x{height} pixels")
    if width * height > MAX_FRAME_PIXELS:
        raise FrameError(f"the image says {width}x{height} pixels, above the limit of "
                         f"{MAX_FRAME_PIXELS / 1e6:g} megapixels")
    dtype = np.dtype(kind).newbyteorder(">" if message.is_bigendian else "<")
    row_bytes = width * channels * dtype.itemsize
    if step < row_bytes:
        raise FrameError(f"its step of {step} bytes is shorter than a row of {width} "
                         f"{encoding} pixels ({row_bytes} bytes)")
    data = np.asarray(message.data, dtype=np.uint8).reshape(-1)
    if data.size < step * (height - 1) + row_bytes:
        raise FrameError(f"its data holds {data.size} bytes, not the {step * height} that "
                         f"{height} rows of {step} bytes take")
    rows = np.lib.stride_tricks.as_strided(data, (height, row_bytes), (step, 1))
    pixels = np.ascontiguousarray(rows).view(dtype).astype(dtype.newbyteorder("="), copy=False)
    pixels = pixels.reshape((height, width, channels) if channels > 1 else (height, width))
    if conversion is not None:
        import cv2  # only to turn RGB into BGR

        pixels = cv2.cvtColor(pixels, getattr(cv2, conversion))
    return pixels


def _compressed_pixels(message: Any, bag: str | Path, topic: str) -> np.ndarray:
    """A ``sensor_msgs/CompressedImage``'s pixels, decoded as an image file's are."""
    from ..imaging.images import ImageError, decode_image

    form = str(message.format)
    if "compressedDepth" in form:
        raise BagError(
            f"{one_line(str(bag), 200)}: topic {quote(topic)} has format {quote(form, 60)}: "
            "compressedDepth images (depth maps) are not read"
        )
    try:
        return decode_image(np.asarray(message.data, dtype=np.uint8).tobytes(),
                            MAX_FRAME_PIXELS)
    except ImageError as error:
        raise FrameError(one_line(f"{form or 'compressed'} image: {error}", 300)) from None


# --------------------------------------------------------------------------------------------
# The camera


def camera_info(bag: str | Path, image_topic: str,
                camera_info_topic: str | None = None) -> Intrinsics:
    """The camera of ``image_topic``: the ``sensor_msgs/CameraInfo`` on
    ``camera_info_topic``, by default the image topic's namespace's ``camera_info``
    (:func:`camera_info_topic_of`).

    ``K`` gives ``fx, fy, cx, cy`` and the skew, ``D`` and ``distortion_model``
    (``plumb_bob``, ``rational_polynomial``, ``equidistant``, and the aliases ``radtan``,
    ``fisheye``) the lens, checked as a ``camera_info`` YAML file is
    (:func:`~gsrwt_cli.inputs.calibration.intrinsics_from_camera_info`); ``width`` and
    ``height`` the size (0: unknown). ``R`` and ``P`` (stereo rectification) are not the raw
    camera and are ignored. Every message on the topic must agree (a driver repeats one per
    frame); a camera whose calibration changes during the bag, one with binning or a region
    of interest, and one with ``K`` all zeros (uncalibrated) are refused.

    Raises :class:`NoCameraInfoError` when the topic is not in the bag, :class:`BagError`
    otherwise.
    """
    topic = camera_info_topic or camera_info_topic_of(image_topic)
    name = one_line(str(bag), 200)
    with _open(bag) as reader:
        found = [c for c in reader.connections if c.topic == topic]
        if not found or all(c.msgtype != CAMERA_INFO for c in found):
            others = sorted({c.topic for c in reader.connections if c.msgtype == CAMERA_INFO})
            raise NoCameraInfoError(str(bag), image_topic, topic, others)
        connections = _connections(reader, bag, topic, (CAMERA_INFO,), "a camera_info topic")
        first: tuple | None = None
        for index, connection, _, raw in _messages(reader, connections, bag, quote(topic)):
            message = _deserialize(reader, raw, connection, f"{name}: {quote(topic)}", index)
            fields = _camera_fields(message)
            if first is None:
                first = fields
                _check_camera_window(message, name, topic)
            elif fields != first:
                raise BagError(f"{name}: the camera on {quote(topic)} changes at message "
                               f"{index} (gsrwt takes one camera per topic)")
        if first is None:
            raise NoCameraInfoError(str(bag), image_topic, topic, [])
    k, d, model, width, height = first
    try:
        return intrinsics_from_camera_info(f"{name} {topic}", k, d, model, width, height)
    except CalibrationError as error:
        raise BagError(one_line(str(error), 500)) from None


def _camera_fields(message: Any) -> tuple:
    """``K, D, distortion_model, width, height`` of a CameraInfo (ROS 1 names them ``K``,
    ``D``; ROS 2 ``k``, ``d``)."""
    k = getattr(message, "k", None)
    k = message.K if k is None else k
    d = getattr(message, "d", None)
    d = message.D if d is None else d
    return (tuple(float(v) for v in np.asarray(k).ravel()),
            tuple(float(v) for v in np.asarray(d).ravel()),
            str(message.distortion_model), int(message.width), int(message.height))


def _check_camera_window(message: Any, name: str, topic: str) -> None:
    """Refuse binning and a region of interest: ``K`` is then the full sensor's."""
    binning = (max(1, int(message.binning_x)), max(1, int(message.binning_y)))  # 0: none
    roi = message.roi
    if max(binning) > 1:
        raise BagError(f"{name}: the camera on {quote(topic)} has binning {binning[0]}x"
                       f"{binning[1]}, which gsrwt does not apply to K")
    if int(roi.width) or int(roi.height) or int(roi.x_offset) or int(roi.y_offset):
        raise BagError(f"{name}: the camera on {quote(topic)} has a region of interest, which "
                       "gsrwt does not apply to K")


# --------------------------------------------------------------------------------------------
# Poses


def pose_samples(
    bag: str | Path, pose_topic: str, joints: tuple[str, str] | None = None,
    joint_signs: tuple[float, float] | None = None, wall_frame: str | None = None,
    camera_frame: str | None = None,
) -> PoseSamples:
    """The camera's orientation over time from ``pose_topic``, whatever its message type.

    Every rotation is turned into the thesis's ``world_from_camera`` by
    :mod:`~gsrwt_cli.geometry.rotations`. The wall frame of a ROS message is OpenCV's (x
    right, y down, z into the wall: a chessboard's object frame seen from its front) and the
    camera's frame its optical frame (x right, y down, z forward), as for a tf lookup
    (docs/POSES.md), except for ``Imu`` and ``JointState``:

    - ``geometry_msgs/PoseStamped`` (ROS's usual meaning): the pose of the camera's optical
      frame in ``header.frame_id``, the wall frame; its orientation maps camera vectors to
      wall vectors (``wall_from_camera``; the conjugate of
      :func:`~gsrwt_cli.geometry.rotations.pose_from_quaternion`'s ``camera_from_wall``).
      The position is not used. ``wall_frame`` given: every ``header.frame_id`` must be it.
    - ``geometry_msgs/QuaternionStamped``: the same orientation, alone.
    - ``sensor_msgs/Imu``: ``orientation``, the IMU's frame in a gravity-aligned world frame,
      both in ROS's body axes (REP 103/145: x forward, y left, z up); the IMU's x axis is the
      optical axis and the world's x axis faces the wall squarely (yaw 0: pan 0). Yaw is
      pan, pitch is minus tilt (a ROS pitch down is positive), roll is roll
      (:func:`~gsrwt_cli.geometry.rotations.world_from_camera_from_ros_body`). An Imu without
      orientation (``orientation_covariance[0] == -1``) is refused.
    - ``sensor_msgs/JointState`` of a pan-tilt unit: ``joints = (pan_name, tilt_name)``, the
      positions in radians in gsrwt's signs (pan > 0 turns left, tilt > 0 up; both 0: facing
      the wall squarely); ``joint_signs`` (each +1 or -1, default ``(1, 1)``) multiplies them
      for a unit whose signs differ. Roll is 0. Messages that name neither joint (other
      joint groups on the same topic) are skipped; one that names only one is refused.
    - ``tf2_msgs/TFMessage`` or ROS 1's ``tf/tfMessage`` (``/tf``; the ``/tf_static``
      beside it is read too): the
      rotation of ``camera_frame`` (the optical frame) in ``wall_frame``, composed through
      any intermediate frames (up or down the tree). The samples are the stamps of the
      chain's moving (``/tf``) transforms; with several, the stamps they share (as one
      ``robot_state_publisher`` message gives them); a chain of static transforms alone is
      one sample, ``constant``.

    Raises :class:`BagError` naming the bag, topic, message, joint or frame at fault.
    """
    name = one_line(str(bag), 200)
    with _open(bag) as reader:
        connections = _connections(reader, bag, pose_topic, POSE_TYPES, "a pose topic")
        kind = connections[0].msgtype
        if kind in TF_MESSAGES:
            stamps, rotations, constant = _tf_samples(reader, name, pose_topic, wall_frame,
                                                      camera_frame)
        else:
            stamps, rotations = _message_samples(reader, connections, name, pose_topic, kind,
                                                 joints, joint_signs, wall_frame)
            constant = False
    if not stamps:
        raise BagError(f"{name}: no pose on {quote(pose_topic)}")
    order = np.argsort(np.asarray(stamps, dtype=np.int64), kind="stable")
    return PoseSamples(np.asarray(stamps, dtype=np.int64)[order],
                       np.asarray(rotations, dtype=np.float64)[order], kind, constant)


def _quaternion_rotation(qw: float, qx: float, qy: float, qz: float, where: str) -> Matrix:
    """The rotation of a quaternion (:func:`rotation_from_quaternion`); refused, naming
    ``where``, if not of unit length."""
    try:
        return rotation_from_quaternion(qw, qx, qy, qz)
    except PoseError as error:
        raise BagError(f"{where}: {error}") from None


def _message_rotation(q: Any, where: str) -> Matrix:
    """The rotation of a ROS ``geometry_msgs/Quaternion`` (fields ``x, y, z, w``)."""
    return _quaternion_rotation(float(q.w), float(q.x), float(q.y), float(q.z), where)


def _message_samples(
    reader: Any, connections: list[Any], name: str, topic: str, kind: str,
    joints: tuple[str, str] | None, joint_signs: tuple[float, float] | None,
    wall_frame: str | None,
) -> tuple[list[int], list[Matrix]]:
    """Samples of the stamped message types (all but tf)."""
    signs = _joint_signs(joint_signs)
    if kind == JOINT_STATE and (joints is None or len(joints) != 2):
        raise BagError(f"{name}: {quote(topic)} is a JointState topic: name its pan and tilt "
                       "joints")
    stamps: list[int] = []
    rotations: list[Matrix] = []
    names_seen: set[str] = set()
    for index, connection, log_ns, raw in _messages(reader, connections, name, quote(topic)):
        message = _deserialize(reader, raw, connection, f"{name}: {quote(topic)}", index)
        where = f"{name}: {quote(topic)} message {index}"
        if kind in (POSE_STAMPED, QUATERNION_STAMPED):
            frame = _frame_name(str(message.header.frame_id))
            if wall_frame is not None and frame != _frame_name(wall_frame):
                raise BagError(f"{where}: its header.frame_id is {quote(frame, 60)}, not the "
                               f"wall frame {quote(wall_frame, 60)}")
            q = message.pose.orientation if kind == POSE_STAMPED else message.quaternion
            wall_from_camera = _message_rotation(q, where)
            rotation = world_from_camera_from_opencv(wall_from_camera.T)
        elif kind == IMU:
            if float(message.orientation_covariance[0]) == -1.0:
                raise BagError(f"{where}: the Imu gives no orientation "
                               "(orientation_covariance[0] = -1)")
            world_from_body = _message_rotation(message.orientation, where)
            rotation = world_from_camera_from_ros_body(world_from_body)
        else:
            names = [str(n) for n in message.name]
            names_seen.update(names)
            present = [joint in names for joint in joints]
            if not any(present):
                continue
            if not all(present):
                missing = joints[present.index(False)]
                raise BagError(f"{where}: names joint {quote(joints[present.index(True)], 60)}"
                               f" but not {quote(missing, 60)} (its joints: "
                               f"{', '.join(quote(n, 40) for n in names[:12])})")
            positions = np.asarray(message.position, dtype=np.float64)
            if len(positions) != len(names):
                raise BagError(f"{where}: {len(names)} joint names but {len(positions)} "
                               "positions")
            pan, tilt = (signs[i] * math.degrees(float(positions[names.index(joints[i])]))
                         for i in range(2))
            try:
                rotation = rotation_from_pose(pan, tilt, 0.0)
            except PoseError as error:
                raise BagError(f"{where}: {error}") from None
        stamps.append(_stamp_ns(message, log_ns))
        rotations.append(rotation)
    if kind == JOINT_STATE and not stamps:
        seen = ", ".join(quote(n, 40) for n in sorted(names_seen)[:12]) or "none"
        raise BagError(f"{name}: no JointState on {quote(topic)} names the joints "
                       f"{quote(joints[0], 60)} and {quote(joints[1], 60)} (the joints it "
                       f"names: {seen})")
    return stamps, rotations


def _joint_signs(joint_signs: tuple[float, float] | None) -> tuple[float, float]:
    if joint_signs is None:
        return 1.0, 1.0
    try:
        signs = tuple(float(s) for s in joint_signs)
    except (TypeError, ValueError):
        signs = ()
    if len(signs) != 2 or any(s not in (1.0, -1.0) for s in signs):
        raise BagError(f"the joint signs must be two of +1 and -1, got {quote(joint_signs)}")
    return signs[0], signs[1]


class _EdgeSamples:
    """One moving tf edge's samples, compactly (a long bag's ``/tf`` holds millions): stamps,
    quaternions ``(x, y, z, w)`` and the index of the message of each."""

    def __init__(self) -> None:
        self.stamps = array("q")
        self.quaternions = array("d")
        self.messages = array("q")

    def add(self, stamp: int, q: Any, index: int) -> None:
        self.stamps.append(stamp)
        self.quaternions.extend((float(q.x), float(q.y), float(q.z), float(q.w)))
        self.messages.append(index)

    def rows(self) -> dict[int, int]:
        """Each stamp's row (the last, when one is given twice)."""
        return {stamp: row for row, stamp in enumerate(self.stamps)}


def _tf_samples(
    reader: Any, name: str, topic: str, wall_frame: str | None, camera_frame: str | None,
) -> tuple[list[int], list[Matrix], bool]:
    """Samples of the rotation of ``camera_frame`` in ``wall_frame`` through the tf tree."""
    if not wall_frame or not camera_frame:
        raise BagError(f"{name}: {quote(topic)} is a tf topic: name the wall frame and the "
                       "camera's optical frame")
    wall, camera = _frame_name(wall_frame), _frame_name(camera_frame)
    static_topic = topic + "_static" if topic.endswith("tf") else None
    topics = {topic} | ({static_topic} if static_topic else set())
    connections = [c for c in reader.connections
                   if c.topic in topics and c.msgtype in TF_MESSAGES]
    # Each edge's quaternions as read, with where they were (a rotation is made only for the
    # edges of the chain: a bad quaternion elsewhere in the tree is none of gsrwt's business).
    static: dict[tuple[str, str], tuple[int, tuple[float, ...], str]] = {}
    moving: dict[tuple[str, str], _EdgeSamples] = {}
    what = " and ".join(quote(t) for t in sorted(topics))
    counts = dict.fromkeys(topics, 0)  # each message's index in its own topic
    for merged, connection, log_ns, raw in _messages(reader, connections, name, what):
        message = _deserialize(reader, raw, connection, f"{name}: {what}", merged)
        index = counts[connection.topic]
        counts[connection.topic] += 1
        for transform in message.transforms:
            edge = (_frame_name(str(transform.header.frame_id)),
                    _frame_name(str(transform.child_frame_id)))
            stamp = _stamp_ns(transform, log_ns)
            q = transform.transform.rotation
            if connection.topic == static_topic:
                static[edge] = (stamp, (float(q.x), float(q.y), float(q.z), float(q.w)),
                                f"{quote(connection.topic)} message {index}")
            else:
                moving.setdefault(edge, _EdgeSamples()).add(stamp, q, index)
    path = _frame_path(set(static) | set(moving), wall, camera)
    if path is None:
        frames = sorted({f for edge in set(static) | set(moving) for f in edge})
        listed = ", ".join(quote(f, 40) for f in frames[:16]) + (", ..." if len(frames) > 16
                                                                  else "")
        raise BagError(f"{name}: no chain of transforms on {' and '.join(sorted(topics))} "
                       f"connects the wall frame {quote(wall, 60)} to the camera frame "
                       f"{quote(camera, 60)} (its frames: {listed or 'none'})")
    steps = [(edge, forward, edge in moving) for edge, forward in path]
    rows = {edge: moving[edge].rows() for edge, _, is_moving in steps if is_moving}
    if rows:
        shared = set.intersection(*(set(edge_rows) for edge_rows in rows.values()))
        if not shared:
            raise BagError(
                f"{name}: the moving transforms of the chain from {quote(wall, 60)} to "
                f"{quote(camera, 60)} ({', '.join(f'{a} -> {b}' for a, b in rows)}) "
                "are never stamped at the same time"
            )
        stamps = sorted(shared)
    else:
        stamps = [max(static[edge][0] for edge, _, _ in steps)]

    def rotation(edge: tuple[str, str], q: tuple[float, ...], where: Any) -> Matrix:
        """The rotation of ``q = (x, y, z, w)``; ``where()`` names its message."""
        x, y, z, w = q
        try:
            return rotation_from_quaternion(w, x, y, z)
        except PoseError as error:
            raise BagError(f"{name}: {where()}, transform {quote(edge[0], 60)} -> "
                           f"{quote(edge[1], 60)}: {error}") from None

    fixed = {edge: rotation(edge, static[edge][1], lambda edge=edge: static[edge][2])
             for edge, _, is_moving in steps if not is_moving}
    rotations = []
    for stamp in stamps:
        wall_from_camera = np.eye(3)
        for edge, forward, is_moving in steps:
            if is_moving:
                samples, row = moving[edge], rows[edge][stamp]
                parent_from_child = rotation(
                    edge, tuple(samples.quaternions[4 * row:4 * row + 4]),
                    lambda: f"{quote(topic)} message {samples.messages[row]}")  # noqa: B023
            else:
                parent_from_child = fixed[edge]
            wall_from_camera = wall_from_camera @ (parent_from_child if forward
                                                   else parent_from_child.T)
        try:
            rotations.append(world_from_camera_from_opencv(wall_from_camera.T))
        except PoseError as error:  # only a product far from orthonormal could fail
            raise BagError(f"{name}: the tf chain at {stamp} ns: {error}") from None
    return stamps, rotations, not rows


def _frame_path(edges: set[tuple[str, str]], start: str,
                goal: str) -> list[tuple[tuple[str, str], bool]] | None:
    """The shortest chain of tf edges from ``start`` to ``goal``: each step an edge
    ``(parent, child)`` and whether it is walked from parent to child; None if unconnected."""
    if start == goal:
        return []
    neighbours: dict[str, list[tuple[str, tuple[str, str], bool]]] = {}
    for parent, child in sorted(edges):
        neighbours.setdefault(parent, []).append((child, (parent, child), True))
        neighbours.setdefault(child, []).append((parent, (parent, child), False))
    previous: dict[str, tuple[str, tuple[str, str], bool]] = {}
    queue = deque([start])
    seen = {start}
    while queue:
        frame = queue.popleft()
        for other, edge, forward in neighbours.get(frame, []):
            if other in seen:
                continue
            seen.add(other)
            previous[other] = (frame, edge, forward)
            if other == goal:
                path = []
                while other != start:
                    other, edge, forward = previous[other]
                    path.append((edge, forward))
                return path[::-1]
            queue.append(other)
    return None


# --------------------------------------------------------------------------------------------
# Writing


def write_bag(
    path: str | Path, topic: str,
    frames: Iterable[tuple[int, np.ndarray] | tuple[int, np.ndarray, Intrinsics | np.ndarray]],
    camera: Intrinsics | np.ndarray | None, *, storage: str = "mcap",
    frame_id: str = "gsrwt_frontal",
    compression: str | None = None, quality: int = 95,
) -> int:
    """Write ``frames`` as a ``sensor_msgs/Image`` topic ``topic`` and, beside it, the
    ``sensor_msgs/CameraInfo`` of the camera that sees them, one per frame (as
    image_transport's camera publishers do), on :func:`camera_info_topic_of`; returns the
    number of frames written.

    ``frames``: ``(stamp_ns, image)`` or ``(stamp_ns, image, camera)`` (a camera per frame
    overrides ``camera``): each image grey, BGR or BGRA, uint8 or uint16 (``mono8``,
    ``mono16``, ``bgr8``, ``bgra8``, ``bgr16``, ``bgra16``), its header stamp and log time
    ``stamp_ns``, ``header.frame_id`` ``frame_id``. ``camera``: the output view's camera,
    an :class:`~gsrwt_cli.geometry.camera.Intrinsics` or its 3x3 ``K``: ``K``; ``D`` five
    zeros of ``plumb_bob`` (the rectified view is a pinhole; a lens, if any, is written as
    :func:`~gsrwt_cli.inputs.calibration.write_ros_yaml` writes it); ``R`` the identity;
    ``P = [K | 0]``; the size is the image's (a camera whose size differs is refused).

    ``compression`` ``png`` (lossless, 8 or 16 bits) or ``jpeg`` (8-bit grey or BGR, at
    ``quality``): a ``sensor_msgs/CompressedImage`` topic instead, its ``format`` as
    image_transport's compressed plugin writes it (``bgr8; png compressed bgr8``); name the
    topic as that plugin does (``/frontal/image/compressed``: its ``camera_info`` is then
    ``/frontal/camera_info``). ``topic`` must be a ROS name (letters, digits, ``_``, ``/``).

    ``path`` ending in ``.bag``: ROS 1. Otherwise a ROS 2 bag directory (format version 8),
    ``storage`` ``mcap`` (the default: ROS 2's default storage since Iron, one
    self-describing file with its message definitions that Foxglove and the MCAP tools open
    without ROS, and whose chunks written before a crash stay readable) or ``sqlite3`` (the
    default of Foxy and Humble). The bag is written under a temporary name in the same
    directory and renamed to ``path`` when complete, so ``path`` is the whole bag or
    nothing; an existing ``path`` is refused, never overwritten.
    """
    _rosbags()
    from rosbags.typesys import Stores, get_typestore

    target = Path(path)
    ros1 = target.suffix == ".bag"
    if storage not in ("mcap", "sqlite3"):
        raise BagError(f"unknown ROS 2 storage {quote(storage)}: mcap or sqlite3")
    if compression not in (None, "png", "jpeg"):
        raise BagError(f"unknown image compression {quote(compression)}: png or jpeg")
    if not _ROS_NAME.fullmatch(topic):
        raise BagError(f"{quote(topic)} is not a ROS topic name (letters, digits, _ and /, "
                       "no token starting with a digit)")
    if os.path.lexists(target):
        raise BagError(f"{one_line(str(path), 200)}: exists; a bag is never overwritten")
    parent = target.parent
    temporary = parent / f".{target.name}.gsrwt-{os.getpid()}-{secrets.token_hex(4)}.part"
    temporary.mkdir()
    try:
        inner = temporary / target.name
        typestore = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
        with _writer(inner, ros1, storage) as writer:
            image_type = IMAGE if compression is None else COMPRESSED_IMAGE
            image_connection = writer.add_connection(topic, image_type, typestore=typestore)
            info_connection = writer.add_connection(camera_info_topic_of(topic), CAMERA_INFO,
                                                    typestore=typestore)
            serialize = typestore.serialize_ros1 if ros1 else typestore.serialize_cdr
            count = 0
            for item in frames:
                stamp_ns, image = int(item[0]), item[1]
                frame_camera = item[2] if len(item) > 2 else camera
                image_message, info_message = _frame_messages(
                    typestore, ros1, stamp_ns, image, frame_camera, frame_id, count,
                    compression, quality)
                writer.write(image_connection, stamp_ns, serialize(image_message, image_type))
                writer.write(info_connection, stamp_ns, serialize(info_message, CAMERA_INFO))
                count += 1
        if os.path.lexists(target):
            raise BagError(f"{one_line(str(path), 200)}: appeared while the bag was written; "
                           "not overwritten")
        os.rename(inner, target)
    finally:
        shutil.rmtree(temporary, ignore_errors=True)
    return count


def _camera_of_matrix(matrix: np.ndarray, seq: int) -> Intrinsics:
    """The pinhole :class:`Intrinsics` of a camera matrix ``K``."""
    k = np.asarray(matrix, dtype=np.float64)
    if k.shape != (3, 3) or k[1, 0] != 0 or k[2, 0] != 0 or k[2, 1] != 0 or k[2, 2] != 1:
        raise BagError(f"frame {seq}: the camera matrix must be [[fx, skew, cx], [0, fy, cy], "
                       f"[0, 0, 1]], got {np.array2string(k, separator=', ')}")
    try:
        return Intrinsics(fx=k[0, 0], fy=k[1, 1], cx=k[0, 2], cy=k[1, 2], skew=k[0, 1])
    except ValueError as error:
        raise BagError(f"frame {seq}: {error}") from None


@contextlib.contextmanager
def _writer(path: Path, ros1: bool, storage: str) -> Iterator[Any]:
    """An open rosbags writer: ROS 1, or ROS 2 with ``storage``."""
    if ros1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(path, version=8, storage_plugin=plugin)
    writer.open()
    try:
        yield writer
    except BaseException:
        with contextlib.suppress(Exception):
            writer.abort()
        raise
    writer.close()


def _frame_messages(typestore: Any, ros1: bool, stamp_ns: int, image: np.ndarray,
                    camera: Intrinsics | None, frame_id: str, seq: int,
                    compression: str | None, quality: int) -> tuple[Any, Any]:
    """The Image (or CompressedImage) and CameraInfo messages of one frame."""
    types = typestore.types
    image = np.asarray(image)
    channels = 1 if image.ndim == 2 else image.shape[2] if image.ndim == 3 else 0
    encoding = _ENCODING_OF.get((image.dtype.str[1:], channels))
    if encoding is None:
        raise BagError(f"frame {seq}: cannot write an image of shape {image.shape} and type "
                       f"{image.dtype} (grey, BGR or BGRA of uint8 or uint16)")
    if camera is None:
        raise BagError(f"frame {seq}: no camera for its camera_info")
    if not isinstance(camera, Intrinsics):
        camera = _camera_of_matrix(camera, seq)
    height, width = image.shape[:2]
    if camera.width is not None and (camera.width, camera.height) != (width, height):
        raise BagError(f"frame {seq}: the camera is {camera.width}x{camera.height} pixels, the "
                       f"image {width}x{height}")
    little = np.ascontiguousarray(image, dtype=image.dtype.newbyteorder("<"))
    stamp = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000,
                                                 nanosec=stamp_ns % 1_000_000_000)
    header_type = types["std_msgs/msg/Header"]
    header = (header_type(seq=seq, stamp=stamp, frame_id=frame_id) if ros1
              else header_type(stamp=stamp, frame_id=frame_id))
    if compression is None:
        image_message = types[IMAGE](
            header=header, height=height, width=width, encoding=encoding, is_bigendian=0,
            step=width * channels * little.dtype.itemsize,
            data=np.frombuffer(little.tobytes(), dtype=np.uint8),
        )
    else:
        from ..imaging.images import ImageError, encode_image

        try:
            data = encode_image(image, ".png" if compression == "png" else ".jpg", quality)
        except ImageError as error:
            raise BagError(f"frame {seq}: cannot write it as {compression} ({error})") from None
        image_message = types[COMPRESSED_IMAGE](
            header=header, format=f"{encoding}; {compression} compressed {encoding}",
            data=np.frombuffer(data, dtype=np.uint8))
    k = camera.matrix()
    lens = camera.lens
    d = np.zeros(5) if lens is None else lens.opencv_coefficients()
    model = "plumb_bob" if lens is None else lens.model
    matrices = {"d": d, "k": k.ravel(), "r": np.eye(3).ravel(),
                "p": np.hstack([k, np.zeros((3, 1))]).ravel()}
    if ros1:
        matrices = {key.upper(): value for key, value in matrices.items()}
    roi = types["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0,
                                                    do_rectify=False)
    info_message = types[CAMERA_INFO](
        header=header, height=height, width=width, distortion_model=model, binning_x=0,
        binning_y=0, roi=roi, **{key: np.asarray(value, dtype=np.float64)
                                 for key, value in matrices.items()},
    )
    return image_message, info_message
