"""A frame's YUV 4:2:0 planes (``imaging/yuv.py``): converted to BGR as the decoder converts
its frames, and warped plane by plane to what the BGR warp hands the H.264 encoder, on a
real H.264 clip rendered through the independent camera."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

av = pytest.importorskip("av")

from gsrwt_cli.api.rectify import plan_image  # noqa: E402
from gsrwt_cli.geometry.framing import Framing  # noqa: E402
from gsrwt_cli.geometry.pixelmap import PixelMap  # noqa: E402
from gsrwt_cli.imaging.images import INTERPOLATIONS, Working, warp_working  # noqa: E402
from gsrwt_cli.imaging.yuv import Yuv420, chroma_map, warp_yuv420  # noqa: E402
from gsrwt_cli.inputs.records import view_from_values  # noqa: E402
from tests.helpers.videos import render_sweep, write_video  # noqa: E402

WIDTH, HEIGHT, FOCAL, COUNT = 320, 240, 300.0, 8


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> tuple[list, np.ndarray]:
    """The decoded frames (PyAV's) of an H.264 sweep, and each frame's pose."""
    frames, pts, poses, _, _ = render_sweep(COUNT, WIDTH, HEIGHT, FOCAL)
    path = tmp_path_factory.mktemp("yuv") / "walk.mp4"
    write_video(path, frames, pts, codec="libx264", options={"crf": "18"})
    with av.open(str(path)) as container:
        decoded = list(container.decode(video=0))
    return decoded, poses


def bgr_warp_as_encoded(frame: Yuv420, pixel_map: PixelMap, fill: float) -> Yuv420:
    """The BGR path: the frame as BGR, warped, converted to ``yuv420p`` for the encoder."""
    warped = warp_working(Working(frame.to_bgr()), pixel_map, "linear", fill, False,
                          antialias=True).pixels
    return Yuv420.from_stacked(av.VideoFrame.from_ndarray(warped, format="bgr24")
                               .reformat(format="yuv420p").to_ndarray())


def test_planes_turn_to_bgr_as_the_decoder_turns_its_frames(clip) -> None:
    decoded, _ = clip
    for frame in decoded:
        assert frame.format.name == "yuv420p"
        planes = Yuv420.from_stacked(frame.to_ndarray())
        assert planes.shape == (HEIGHT, WIDTH)
        np.testing.assert_array_equal(planes.to_bgr(), frame.to_ndarray(format="bgr24"))


@pytest.mark.parametrize(("fill", "scale"), [(0.0, 1.0), (200.0, 1.0), (0.0, 0.4)])
def test_planes_warped_match_the_bgr_warp_the_encoder_would_get(clip, fill: float,
                                                                scale: float) -> None:
    """Each plane within 40 dB PSNR of the BGR path's (converted for the encoder as it
    converts it), at every pose of the sweep, the fill and the horizon's edge included;
    ``scale`` 0.4: an output that shrinks the input, antialiased."""
    decoded, poses = clip
    for frame, (pan, tilt, roll) in zip(decoded, poses):
        view = view_from_values({"pan": pan, "tilt": tilt, "roll": roll, "focal": FOCAL}, "x")
        pixel_map = plan_image(view, WIDTH, HEIGHT, Framing(scale=scale)).pixel_map
        assert pixel_map.filters((WIDTH, HEIGHT)) == (scale < 1)
        planes = Yuv420.from_stacked(frame.to_ndarray())
        warped = warp_yuv420(planes, pixel_map, INTERPOLATIONS["linear"], fill, True)
        expected = bgr_warp_as_encoded(planes, pixel_map, fill)
        assert warped.shape == expected.shape == tuple(reversed(pixel_map.size))
        for made, wanted in zip(warped.planes(), expected.planes()):
            assert cv2.PSNR(made, wanted) >= 40.0


def test_the_chroma_map_is_the_luma_map_on_half_size_pixels() -> None:
    """Points mapped by the chroma map land where the luma map sends them, each side seen
    in chroma pixels (``x_c = (x + 0.5) / 2 - 0.5 + siting``), and it keeps the luma map's
    local shrink (what the antialiasing filters by)."""
    from gsrwt_cli.imaging.yuv import CHROMA_SITING

    homography = np.array([[1.3, 0.2, 10.0], [-0.1, 0.9, 4.0], [1e-4, 2e-4, 1.0]])
    luma = PixelMap(homography, (200, 120))
    chroma = chroma_map(luma)
    assert chroma.size == (100, 60)
    points = np.array([[3.0, 7.0], [150.0, 90.0], [60.5, 33.25]])

    def to_chroma(p: np.ndarray) -> np.ndarray:
        return (p + 0.5) / 2 - 0.5 + np.array(CHROMA_SITING)

    np.testing.assert_allclose(chroma.to_output(to_chroma(points)),
                               to_chroma(luma.to_output(points)), atol=1e-9)
    # grid points half a luma row apart (the vertical siting): the shrink varies that little
    np.testing.assert_allclose(chroma.shrink(10), luma.shrink(20), rtol=1e-3)


def test_planes_need_an_even_size() -> None:
    with pytest.raises(ValueError, match="even size"):
        Yuv420(np.zeros(16 * 9 * 3 // 2, np.uint8), 16, 9)
    with pytest.raises(ValueError, match="not the yuv420p planes of a 16x10"):
        Yuv420(np.zeros(16 * 10, np.uint8), 16, 10)


def test_planes_are_warped_through_a_pinhole_only() -> None:
    from gsrwt_cli.geometry.lens import LensDistortion

    lens = LensDistortion(((100.0, 0, 50), (0, 100.0, 40), (0, 0, 1)), (-0.1, 0, 0, 0, 0))
    with pytest.raises(ValueError, match="pinhole"):
        warp_yuv420(Yuv420.empty(100, 80), PixelMap(np.eye(3), (100, 80), lens),
                    cv2.INTER_LINEAR, 0.0, False)
