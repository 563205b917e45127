"""``gsrwt rectify BAG --topic TOPIC (--pose-topic TOPIC | --poses FILE)``: a ROS bag's
image topic rectified frame by frame, with a table row per frame.

This module checks what a bag run needs before any frame is warped (rosbags installed, the
image topic, the pose topic and the options its message type takes, the camera: the
topic's ``camera_info`` or the intrinsics given), in the options' words, and runs it as a
video is run (:func:`.videos.run_stream_command`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import click

from ..base.messages import one_line, quote
from ..batch.frame_sources import BagSource, LogPoses, TopicPoses, camera_values
from ..batch.rectify_jobs import Settings
from ..batch.video_jobs import StreamJob, output_of
from ..inputs import bags
from ..io.storage import Location
from ..io.targets import file_identity
from .options import InputError
from .videos import (
    check_codec,
    check_max_pose_gap,
    read_pose_log,
    run_stream_command,
    stream_words,
    view_fallback,
)

#: The options that only a bag takes, by parameter name.
BAG_OPTIONS = {"topic": "--topic", "pose_topic": "--pose-topic", "joints": "--joints",
               "joint_signs": "--joint-signs", "wall_frame": "--wall-frame",
               "camera_frame": "--camera-frame", "camera_info_topic": "--camera-info-topic"}


@dataclass(frozen=True)
class BagOptions:
    """The bag options of one run (None: not given)."""

    topic: str | None = None
    pose_topic: str | None = None
    joints: str | None = None
    joint_signs: str | None = None
    wall_frame: str | None = None
    camera_frame: str | None = None
    camera_info_topic: str | None = None

    @classmethod
    def pop_from(cls, options: dict[str, Any]) -> BagOptions:
        return cls(**{name: options.pop(name) for name in BAG_OPTIONS})

    def given(self) -> list[str]:
        """The flags given."""
        return [flag for name, flag in BAG_OPTIONS.items() if getattr(self, name) is not None]


def is_bag_input(text: str) -> bool:
    """Whether an INPUT names a ROS bag (:func:`~gsrwt_cli.inputs.bags.is_bag_name`)."""
    return text != "-" and bags.is_bag_name(text)


def _listed(names: list[str], limit: int = 12) -> str:
    return ", ".join(names[:limit]) + (", ..." if len(names) > limit else "") or "none"


def _pair(text: str, option: str, what: str) -> tuple[str, str]:
    parts = [part.strip() for part in text.split(",")]
    if len(parts) != 2 or not all(parts):
        raise click.BadParameter(f"expected {what}, got {quote(text)}", param_hint=f"'{option}'")
    return parts[0], parts[1]


def _signs(text: str) -> tuple[float, float]:
    pair = _pair(text, "--joint-signs", "two signs such as 1,-1 (pan, tilt)")
    values = {"1": 1.0, "+1": 1.0, "-1": -1.0, "+": 1.0, "-": -1.0}
    if any(sign not in values for sign in pair):
        raise click.BadParameter(f"expected two of 1 and -1 (pan, tilt), got {quote(text)}",
                                 param_hint="'--joint-signs'")
    return values[pair[0]], values[pair[1]]


def check_bag_options(options: BagOptions, poses: str | None) -> None:
    """Usage errors of the bag options alone, before the bag is opened."""
    if options.pose_topic is None and poses is None:
        raise click.UsageError("a bag needs its poses: --pose-topic TOPIC (PoseStamped, "
                               "QuaternionStamped, Imu, JointState or /tf) or --poses FILE")
    if options.pose_topic is not None and poses is not None:
        raise click.UsageError("give --pose-topic or --poses, not both")
    if poses is not None:
        for flag in ("--joints", "--joint-signs", "--wall-frame", "--camera-frame"):
            if flag in options.given():
                raise click.UsageError(f"{flag} goes with --pose-topic, not --poses")
    if options.joint_signs is not None and options.joints is None:
        raise click.UsageError("--joint-signs goes with --joints PAN,TILT")
    if options.camera_frame is not None and options.wall_frame is None:
        raise click.UsageError("--camera-frame goes with --wall-frame (the /tf chain from "
                               "the wall frame to the camera's optical frame)")


def rectify_bag(inputs: tuple[str, ...], outdir: Path | Location, options: BagOptions,
                poses: str | None, time_mode: str, max_gap: float, codec: str,
                settings: Settings, table: Any, table_given: bool, run: Any,
                view_kwargs: dict[str, Any], steady: bool = False) -> None:
    """Check, run and end a bag run (the command's exit status and last line)."""
    if len(inputs) != 1:
        raise click.UsageError(f"--topic takes one bag as INPUT, got "
                               f"{' '.join(map(quote, inputs))}")
    text = inputs[0]
    if isinstance(outdir, Location):
        raise InputError(f"-o {outdir}: bags are rectified to a local directory only")
    check_max_pose_gap(max_gap)
    check_bag_options(options, poses)
    bag = Path(text)
    if not bag.exists():
        raise InputError(f"{text}: no such file or directory")
    try:
        topics = bags.bag_topics(bag)
    except bags.BagError as error:
        raise InputError(f"{text}: {error}" if bags.INSTALL_HINT in str(error)
                         else str(error)) from None
    image_topics = [name for name, kind in topics.items()
                    if kind in (bags.IMAGE, bags.COMPRESSED_IMAGE)]
    if options.topic is None:
        raise click.UsageError(f"{text}: a bag needs --topic, its image topic (the bag's "
                               f"image topics: {_listed(image_topics)})")
    if options.topic not in image_topics:
        found = (f"is {topics[options.topic]}, not an image topic" if options.topic in topics
                 else "is not in the bag")
        raise InputError(f"--topic {quote(options.topic)}: {found} (the bag's image topics: "
                         f"{_listed(image_topics)})")
    check_codec(codec, settings)
    fallback = view_fallback(view_kwargs)
    camera = _camera(bag, text, options, fallback)
    if options.pose_topic is not None:
        samples = _pose_samples(bag, text, options, topics)
        frame_poses: LogPoses | TopicPoses = TopicPoses(samples, options.pose_topic, max_gap,
                                                        fallback, camera)
        pose_words = (f"pose_topic={options.pose_topic}"
                      + (f" joints={options.joints}" if options.joints else "")
                      + (f" joint_signs={options.joint_signs}" if options.joint_signs else "")
                      + (f" wall_frame={options.wall_frame} camera_frame={options.camera_frame}"
                         if options.camera_frame else ""))
        given = {file_identity(bag)}
    else:
        assert poses is not None
        log = read_pose_log(poses, max_gap)
        frame_poses = LogPoses(log, time_mode, max_gap, fallback, camera)
        pose_words = f"poses=sha256:{log.digest} time={time_mode}"
        given = {file_identity(bag), file_identity(Path(poses))}
    try:
        first = bags.image_frames(bag, options.topic)
        next(first, None)
        first.close()
    except bags.BagError as error:
        raise InputError(f"--topic {quote(options.topic)}: {error}") from None
    output = output_of(bag, outdir, codec)
    words = stream_words(fallback, settings, codec, output) + (
        f" topic={options.topic} {pose_words} max_pose_gap={max_gap:g} codec={codec}"
        + (f" camera_info={options.camera_info_topic}" if options.camera_info_topic else "")
        + (" steady=on" if steady else ""))
    job = StreamJob(bag, output, codec, frame_poses,
                    partial(BagSource, bag, options.topic, settings.max_input_pixels),
                    words.strip(), steady, _output_topic(options.topic))
    run_stream_command(job, outdir, settings, table, table_given, run, given)


def _output_topic(topic: str) -> str:
    """A bag output's image topic: ``gsrwt/image`` in the input topic's namespace
    (``/camera/image_raw`` -> ``/camera/gsrwt/image``, its camera_info
    ``/camera/gsrwt/camera_info``)."""
    namespace = bags.camera_info_topic_of(topic).rsplit("/", 1)[0]
    return f"{namespace}/gsrwt/image"


def _camera(bag: Path, text: str, options: BagOptions, fallback: dict[str, Any]
            ) -> dict[str, Any]:
    """The view values of the image topic's camera_info; none when --camera replaces it,
    or when there is none and the intrinsics are given (--focal, --fx and --fy)."""
    if fallback.get("camera"):
        return {}
    try:
        intrinsics = bags.camera_info(bag, str(options.topic), options.camera_info_topic)
    except bags.NoCameraInfoError as error:
        given = fallback.get("focal") is not None or (
            fallback.get("fx") is not None and fallback.get("fy") is not None)
        if given and options.camera_info_topic is None:
            return {}
        found = (f"its CameraInfo topics: {', '.join(error.found[:10])}" if error.found
                 else "it has no CameraInfo topic")
        raise InputError(
            f"{text}: no camera_info on {quote(error.topic)} for --topic "
            f"{quote(options.topic)} ({found}); name one with --camera-info-topic, or give "
            "the intrinsics (--focal, --camera FILE)") from None
    except bags.BagError as error:
        raise InputError(f"--camera-info-topic: {error}" if options.camera_info_topic
                         else str(error)) from None
    return camera_values(intrinsics)


def _pose_samples(bag: Path, text: str, options: BagOptions,
                  topics: dict[str, str]) -> bags.PoseSamples:
    """The pose topic's samples, its options checked against its message type."""
    topic = str(options.pose_topic)
    kind = topics.get(topic)
    if kind is None:
        pose_topics = [name for name, found in topics.items() if found in bags.POSE_TYPES]
        raise InputError(f"--pose-topic {quote(topic)}: is not in the bag (its pose topics: "
                         f"{_listed(pose_topics)})")
    if kind not in bags.POSE_TYPES:
        raise InputError(f"--pose-topic {quote(topic)}: is {kind}, not PoseStamped, "
                         "QuaternionStamped, Imu, JointState or tf")
    short = kind.rsplit("/", 1)[-1]
    if kind == bags.JOINT_STATE and options.joints is None:
        raise click.UsageError(f"--pose-topic {topic} is a JointState topic: name its pan and "
                               "tilt joints with --joints PAN,TILT")
    if options.joints is not None and kind != bags.JOINT_STATE:
        raise click.UsageError(f"--joints goes with a JointState --pose-topic; {topic} is "
                               f"{short}")
    if kind in bags.TF_MESSAGES:
        if options.wall_frame is None or options.camera_frame is None:
            raise click.UsageError(f"--pose-topic {topic} is a tf topic: name the chain's ends "
                                   "with --wall-frame and --camera-frame (the optical frame)")
    elif options.camera_frame is not None:
        raise click.UsageError(f"--camera-frame goes with a tf --pose-topic; {topic} is {short}")
    elif options.wall_frame is not None and kind not in (bags.POSE_STAMPED,
                                                         bags.QUATERNION_STAMPED):
        raise click.UsageError(f"--wall-frame goes with a tf, PoseStamped or "
                               f"QuaternionStamped --pose-topic; {topic} is {short}")
    joints = _pair(options.joints, "--joints", "two joint names, PAN,TILT") if (
        options.joints) else None
    signs = _signs(options.joint_signs) if options.joint_signs else None
    try:
        return bags.pose_samples(bag, topic, joints, signs, options.wall_frame,
                                 options.camera_frame)
    except bags.BagError as error:
        raise InputError(f"--pose-topic {quote(topic)}: {one_line(str(error), 400)}") from None
