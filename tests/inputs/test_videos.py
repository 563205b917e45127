"""Video inputs (``inputs/videos.py``): frames with their index and times, a file cut
short, a packet the decoder refuses, what is not a video."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

av = pytest.importorskip("av")

from gsrwt_cli.inputs.videos import (  # noqa: E402  (needs PyAV, checked above)
    FrameFailure,
    VideoError,
    VideoFrame,
    VideoReader,
    VideoTruncatedError,
    is_video_name,
)
from tests.helpers.images import smooth_texture  # noqa: E402
from tests.helpers.videos import write_video  # noqa: E402

FRAMES = [np.ascontiguousarray(smooth_texture(120, 160, seed=i)) for i in range(12)]
STAMPS = [1000 + round(i * 1000 / 30) for i in range(12)]  # a clock that starts at 1 s


def test_frames_come_with_index_times_and_their_pixels(tmp_path: Path) -> None:
    path = tmp_path / "a.mkv"
    write_video(path, FRAMES, STAMPS)
    with VideoReader(path) as reader:
        frames = list(reader.frames())
    assert [frame.index for frame in frames] == list(range(12))
    assert [frame.absolute for frame in frames] == pytest.approx([s / 1000 for s in STAMPS])
    assert [frame.time for frame in frames] == pytest.approx([(s - 1000) / 1000
                                                              for s in STAMPS])
    assert all(isinstance(frame, VideoFrame) for frame in frames)
    np.testing.assert_array_equal(frames[5].pixels, FRAMES[5])


def test_a_file_cut_short_is_found_after_its_frames(tmp_path: Path) -> None:
    path = tmp_path / "a.mkv"
    write_video(path, FRAMES, STAMPS)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    seen = []
    with VideoReader(path) as reader, pytest.raises(VideoTruncatedError, match="cut short"):
        for frame in reader.frames():
            seen.append(frame.index)
    assert 2 <= len(seen) < 12 and seen == list(range(len(seen)))


def test_a_refused_packet_is_its_frame(tmp_path: Path) -> None:
    path = tmp_path / "a.mp4"
    write_video(path, FRAMES, STAMPS, codec="libx264")
    with av.open(str(path)) as container:
        packets = [(p.pos, p.size, float(p.pts * p.time_base))
                   for p in container.demux(video=0) if p.size]
    position, size, when = packets[6]
    data = bytearray(path.read_bytes())
    data[position + 4: position + size] = b"\xff" * (size - 4)
    path.write_bytes(bytes(data))
    with VideoReader(path) as reader:
        frames = list(reader.frames())
    assert [frame.index for frame in frames] == list(range(12))
    (failure,) = [frame for frame in frames if isinstance(frame, FrameFailure)]
    assert failure.absolute == pytest.approx(when)
    assert sorted(frame.absolute for frame in frames) == [frame.absolute for frame in frames]


def test_what_is_not_a_video(tmp_path: Path) -> None:
    (tmp_path / "a.mp4").write_bytes(b"not a video at all" * 10)
    with pytest.raises(VideoError, match="not a video FFmpeg can read"):
        VideoReader(tmp_path / "a.mp4")
    with pytest.raises(VideoError, match="no such file"):
        VideoReader(tmp_path / "missing.mp4")
    (tmp_path / "empty.mp4").write_bytes(b"")  # said as an image's is, not as FFmpeg's data
    with pytest.raises(VideoError, match="^empty file$"):
        VideoReader(tmp_path / "empty.mp4")
    assert is_video_name("A.MKV") and not is_video_name("a.png")


def test_an_h264_clip_decodes_to_its_planes_only_when_asked(tmp_path: Path) -> None:
    """``frames(planes=True)`` gives an H.264 clip's frames as their YUV 4:2:0 planes, and
    BGR otherwise; a clip whose frames are not 8-bit 4:2:0 (FFV1's ``bgr0``, libx264's
    ``yuv444p``) comes as BGR either way."""
    from gsrwt_cli.imaging.yuv import Yuv420

    h264, ffv1, full = tmp_path / "a.mp4", tmp_path / "b.mkv", tmp_path / "c.mp4"
    write_video(h264, FRAMES[:3], STAMPS[:3], codec="libx264")
    write_video(ffv1, FRAMES[:3], STAMPS[:3], codec="ffv1")
    write_video(full, FRAMES[:3], STAMPS[:3], codec="libx264", pix_fmt="yuv444p")
    for path, planar in ((h264, True), (ffv1, False), (full, False)):
        for planes in (False, True):
            with VideoReader(path) as reader:
                frames = list(reader.frames(planes))
            kinds = {type(frame.pixels) for frame in frames}
            assert kinds == ({Yuv420} if planes and planar else {np.ndarray}), (path, planes)
            assert [frame.index for frame in frames] == [0, 1, 2]
