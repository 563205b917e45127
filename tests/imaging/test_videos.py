"""Video outputs (``imaging/videos.py``): the input's timestamps kept, lossless FFV1 pixel
for pixel, sizes and timestamps that cannot be encoded refused."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

av = pytest.importorskip("av")

from gsrwt_cli.imaging.videos import (  # noqa: E402  (needs PyAV, checked above)
    VIDEO_CODECS,
    VideoEncodeError,
    VideoEncoder,
)
from tests.helpers.images import smooth_texture  # noqa: E402
from tests.helpers.videos import read_video  # noqa: E402


@pytest.mark.parametrize("codec", ["ffv1", "h264"])
def test_timestamps_with_a_gap_are_kept(tmp_path: Path, codec: str) -> None:
    frames = [np.ascontiguousarray(smooth_texture(120, 160, seed=i)) for i in range(6)]
    stamps = [0, 33, 67, 133, 167, 200]  # 100 ms missing: a frame left out
    path = tmp_path / f"out{VIDEO_CODECS[codec].extension}"
    with open(path, "wb") as stream:
        encoder = VideoEncoder(stream, VIDEO_CODECS[codec], Fraction(1, 1000), Fraction(30))
        for frame, stamp in zip(frames, stamps):
            encoder.write(frame, stamp)
        encoder.close()
    decoded, times = read_video(path)
    assert times == pytest.approx([stamp / 1000 for stamp in stamps])
    if codec == "ffv1":
        for made, given in zip(decoded, frames):
            np.testing.assert_array_equal(made, given)


def test_what_cannot_be_encoded_is_refused(tmp_path: Path) -> None:
    with open(tmp_path / "a.mp4", "wb") as stream:
        encoder = VideoEncoder(stream, VIDEO_CODECS["h264"], Fraction(1, 1000), None)
        with pytest.raises(VideoEncodeError, match="even width and height"):
            encoder.write(np.zeros((121, 160, 3), np.uint8), 0)
    with open(tmp_path / "b.mkv", "wb") as stream:
        encoder = VideoEncoder(stream, VIDEO_CODECS["ffv1"], Fraction(1, 1000), None)
        encoder.write(np.zeros((120, 160, 3), np.uint8), 10)
        with pytest.raises(VideoEncodeError, match="the frame is 80x60, the video 160x120"):
            encoder.write(np.zeros((60, 80, 3), np.uint8), 20)
        with pytest.raises(VideoEncodeError, match="timestamp 10 does not follow 10"):
            encoder.write(np.zeros((120, 160, 3), np.uint8), 10)
        encoder.abandon()


def test_planes_are_encoded_as_they_are(tmp_path: Path) -> None:
    """H.264 takes a frame's YUV 4:2:0 planes without converting them (the encoder reads
    their memory): decoded again, each plane matches the one given within H.264's loss
    (CRF 18: 35 dB on this detailed texture), at the timestamps given; planes mixed up (U
    for V, rows misread) would not (below 25 dB)."""
    import cv2

    from gsrwt_cli.imaging.yuv import Yuv420

    frames = [np.ascontiguousarray(smooth_texture(120, 160, seed=i)) for i in range(4)]
    planes = [Yuv420.from_stacked(av.VideoFrame.from_ndarray(frame, format="bgr24")
                                  .reformat(format="yuv420p").to_ndarray()) for frame in frames]
    path = tmp_path / "planes.mp4"
    with open(path, "wb") as stream:
        encoder = VideoEncoder(stream, VIDEO_CODECS["h264"], Fraction(1, 1000), None)
        for index, pixels in enumerate(planes):
            encoder.write(pixels, 10 * index)
        encoder.close()
    with av.open(str(path)) as container:
        decoded = [(Yuv420.from_stacked(frame.to_ndarray()), float(frame.time))
                   for frame in container.decode(video=0)]
    assert [time for _, time in decoded] == pytest.approx([0.0, 0.01, 0.02, 0.03])
    for (made, _), given in zip(decoded, planes):
        for made_plane, given_plane in zip(made.planes(), given.planes()):
            assert cv2.PSNR(made_plane, given_plane) >= 30.0
