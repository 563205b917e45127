"""One video frame's work (``batch/video_jobs.py``'s ``process_frame``) in this process, on
frames of a real H.264 clip rendered through the independent camera: a frame decoded as its
YUV 4:2:0 planes is warped as them for the H.264 encoder, and in BGR, exactly as a frame
decoded to BGR, when its camera has a lens, when the output is an image sequence, and with
alpha.

The runs around it (decoding, workers, the encoder, rows) are tested through the command in
``tests/cli/test_videos.py``.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

av = pytest.importorskip("av")

from gsrwt_cli.batch.settings import Settings  # noqa: E402
from gsrwt_cli.batch.video_jobs import FrameJob, process_frame, takes_planes  # noqa: E402
from gsrwt_cli.imaging.yuv import Yuv420  # noqa: E402
from tests.helpers.videos import render_sweep, write_video  # noqa: E402

WIDTH, HEIGHT, FOCAL, COUNT = 320, 240, 300.0, 4


@pytest.fixture(scope="module")
def frames(tmp_path_factory) -> list[tuple[Yuv420, tuple[float, float, float]]]:
    """The planes of each frame of an H.264 sweep (as the decoder gives them), and its pose."""
    images, pts, poses, _, _ = render_sweep(COUNT, WIDTH, HEIGHT, FOCAL)
    path = tmp_path_factory.mktemp("frames") / "walk.mp4"
    write_video(path, images, pts, codec="libx264", options={"crf": "18"})
    with av.open(str(path)) as container:
        planes = [Yuv420.from_stacked(frame.to_ndarray())
                  for frame in container.decode(video=0)]
    return list(zip(planes, [tuple(pose) for pose in poses]))


def job(pixels, pose, output: Path | None = None, **values) -> FrameJob:
    pan, tilt, roll = pose
    return FrameJob("walk.mp4", 0, 0.0, pixels,
                    {"pan": pan, "tilt": tilt, "roll": roll, "focal": FOCAL, **values},
                    "walk", output, str(output or "out.mp4"))


def test_an_h264_output_takes_planes_unless_alpha_is_asked() -> None:
    assert takes_planes("h264", Settings())
    assert not takes_planes("h264", Settings(alpha=True))
    assert not any(takes_planes(codec, Settings()) for codec in ("ffv1", "png", "bag"))


def test_planes_through_a_pinhole_are_warped_as_planes(frames) -> None:
    """The planes come back warped (not BGR), the row as the BGR frame's, and the picture
    within 40 dB PSNR of the BGR warp's."""
    for planes, pose in frames:
        made = process_frame(job(planes, pose), Settings(), "m")
        bgr = process_frame(job(planes.to_bgr(), pose), Settings(), "m")
        warped, expected = made.pop("_pixels"), bgr.pop("_pixels")
        assert isinstance(warped, Yuv420) and isinstance(expected, np.ndarray)
        assert made == bgr and made["status"] == "ok"
        assert cv2.PSNR(warped.to_bgr(), expected) >= 35.0  # BGR: colour rounding, see below
        encoded = Yuv420.from_stacked(av.VideoFrame.from_ndarray(expected, format="bgr24")
                                      .reformat(format="yuv420p").to_ndarray())
        for made_plane, wanted in zip(warped.planes(), encoded.planes()):
            assert cv2.PSNR(made_plane, wanted) >= 40.0


@pytest.mark.parametrize("case", ["lens", "alpha", "png"])
def test_a_lens_alpha_or_an_image_sequence_warps_in_bgr(frames, tmp_path: Path,
                                                        case: str) -> None:
    """Exactly what the frame decoded to BGR gives: the planes are converted as the decoder
    converts a frame (swscale), then the BGR path runs."""
    planes, pose = frames[1]
    extra = {"k1": -0.05} if case == "lens" else {}
    settings = Settings(alpha=case == "alpha", root=tmp_path)
    outputs = [tmp_path / "a.png", tmp_path / "b.png"] if case == "png" else [None, None]
    made = process_frame(job(planes, pose, outputs[0], **extra), settings, "m")
    bgr = process_frame(job(planes.to_bgr(), pose, outputs[1], **extra), settings, "m")
    assert made["status"] == bgr["status"] == "ok", (made, bgr)
    if case == "png":
        assert outputs[0].read_bytes() == outputs[1].read_bytes()
        assert "_pixels" not in made
    else:
        assert isinstance(made["_pixels"], np.ndarray)
        np.testing.assert_array_equal(made.pop("_pixels"), bgr.pop("_pixels"))
    made.pop("output"), bgr.pop("output")
    assert made == bgr
