"""Real videos for the tests: frames rendered through the independent camera
(:mod:`tests.helpers.camera`) with known poses, encoded by PyAV's own encoders.

A pan-tilt sweep is given by key poses; the pose of every frame between them is scipy's
slerp of their rotations (``Rotation.from_euler("XYZ", (pan, tilt, roll))`` is
``Rx(pan) Ry(tilt) Rz(roll)``, the ``world_from_camera`` of docs/POSES.md), independent of
the package's own interpolation.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from tests.helpers.camera import render_view
from tests.helpers.images import smooth_texture

#: Milliseconds: Matroska's own time base, so the timestamps written are the ones read back.
TIME_BASE = Fraction(1, 1000)


def frame_pts(count: int, rate: int = 30) -> list[int]:
    """The pts (milliseconds) of ``count`` frames at ``rate`` frames per second."""
    return [round(index * 1000 / rate) for index in range(count)]


def sweep_key_poses(times: np.ndarray) -> np.ndarray:
    """(pan, tilt, roll) in degrees at ``times`` (seconds): a pan-tilt sweep, fast enough
    that a pose a few frames off rectifies visibly differently."""
    pan = 25 * np.sin(2 * np.pi * times / 1.2)
    tilt = 12 + 14 * times
    return np.column_stack([pan, tilt, np.zeros_like(times)])


def slerped_poses(key_times: np.ndarray, key_poses: np.ndarray, times: np.ndarray
                  ) -> np.ndarray:
    """scipy's slerp of the key poses at ``times``, as (pan, tilt, roll) degrees."""
    keys = Rotation.from_euler("XYZ", key_poses, degrees=True)
    return Slerp(key_times, keys)(times).as_euler("XYZ", degrees=True)


def write_video(path: Path, frames: list[np.ndarray], pts: list[int], codec: str = "ffv1",
                time_base: Fraction = TIME_BASE, rate: int = 30,
                options: dict[str, str] | None = None, pix_fmt: str | None = None) -> None:
    """Encode BGR ``frames`` at ``pts`` with PyAV (``ffv1``: lossless ``bgr0``; ``libx264``:
    ``yuv420p``, or ``pix_fmt``) into ``path`` (its extension picks the container)."""
    import av

    height, width = frames[0].shape[:2]
    with av.open(str(path), mode="w") as container:
        stream = container.add_stream(codec, rate=rate, options=options or {})
        stream.width, stream.height = width, height
        stream.pix_fmt = pix_fmt or ("bgr0" if codec == "ffv1" else "yuv420p")
        stream.time_base = time_base
        for image, stamp in zip(frames, pts):
            frame = av.VideoFrame.from_ndarray(image, format="bgr24")
            frame.pts, frame.time_base = stamp, time_base
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


def read_video(path: Path) -> tuple[list[np.ndarray], list[float]]:
    """Every frame of ``path`` (BGR) and its time in seconds, decoded by PyAV."""
    import av

    frames, times = [], []
    with av.open(str(path)) as container:
        for frame in container.decode(video=0):
            frames.append(frame.to_ndarray(format="bgr24"))
            times.append(float(frame.pts * frame.time_base))
    return frames, times


def render_sweep(count: int, width: int, height: int, focal: float, rate: int = 30,
                 key_every: int = 4) -> tuple[list[np.ndarray], list[int], np.ndarray,
                                              np.ndarray, np.ndarray]:
    """A sweep of ``count`` frames rendered at the slerp of key poses taken every
    ``key_every`` frames: the frames, their pts (ms), each frame's pose, and the key
    times and poses (the pose log)."""
    pts = frame_pts(count, rate)
    times = np.array(pts, dtype=float) / 1000
    key_times = times[::key_every]
    if key_times[-1] != times[-1]:
        key_times = np.append(key_times, times[-1])
    key_poses = sweep_key_poses(key_times)
    poses = slerped_poses(key_times, key_poses, times)
    texture = smooth_texture(1400, 1800, seed=7)
    frames = []
    for pan, tilt, roll in poses:
        image, _, _ = render_view(texture, pan, tilt, focal, width, height, width / 2,
                                  height / 2, centre=(0.0, 0.0), roll=roll)
        frames.append(image)
    return frames, pts, poses, key_times, key_poses


def write_pose_log(path: Path, times: np.ndarray, poses: np.ndarray,
                   order: list[int] | None = None) -> None:
    """A CSV pose log ``time,pan,tilt,roll`` (rows in ``order``, default as given)."""
    rows = ["time,pan,tilt,roll"]
    for index in order if order is not None else range(len(times)):
        pan, tilt, roll = poses[index]
        rows.append(f"{float(times[index])!r},{float(pan)!r},{float(tilt)!r},{float(roll)!r}")
    path.write_text("\n".join(rows) + "\n")
