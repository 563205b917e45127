"""Previews that cost little (``imaging/images.py``): a JPEG decoded 2, 4 or 8 times smaller in
the DCT (libjpeg-turbo's scaled decoding) when the output shrinks it that much, warped through
the map turned onto the reduced pixels. Checked against the full decode followed by the same
antialiased warp, and against an area-averaged reference (the full decode warped at 8x the
output's size without filtering, then averaged over 8x8 blocks), on a real photo: EXIF
orientations, a lens, odd sizes, grey, progressive and CMYK JPEGs, alpha, 16-bit PNGs."""

from __future__ import annotations

import io
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from gsrwt_cli.api.rectify import plan_image
from gsrwt_cli.geometry.camera import View
from gsrwt_cli.geometry.framing import Framing
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.geometry.orientation import displayed_size
from gsrwt_cli.imaging.images import (
    Scratch,
    decode_image,
    from_working,
    jpeg_reduction,
    preview_reduction,
    reduced_size,
)
from tests.helpers.images import phase_shift, psnr

PHOTO = Path(__file__).resolve().parents[1] / "data" / "facade" / "building.jpg"
ORIENTATION = 0x0112


def photo(width: int = 868, height: int = 600) -> np.ndarray:
    """The real facade photo (868x600), cut to ``width x height``."""
    return cv2.imread(str(PHOTO))[:height, :width]


def write_jpeg(path: Path, image: np.ndarray, orientation: int = 1, **options) -> Path:
    """``image`` (BGR or grey) as a JPEG by Pillow, quality 95, with an EXIF orientation."""
    exif = Image.Exif()
    exif[ORIENTATION] = orientation
    rgb = image[..., ::-1] if image.ndim == 3 else image
    Image.fromarray(np.ascontiguousarray(rgb)).save(path, quality=95, exif=exif.tobytes(),
                                                     **options)
    return path


def both(path: Path, pixel_map, orientation: int = 1, alpha: bool = False
         ) -> tuple[np.ndarray, np.ndarray, int]:
    """The preview (reduced decode), the full path's output and the reduction used."""
    scratch = Scratch()
    scratch.read(path, orientation=orientation, preview=pixel_map)
    reduction = scratch.reduction
    preview = from_working(scratch.warp(pixel_map, alpha=alpha, antialias=True)).copy()
    scratch.read(path, orientation=orientation)
    assert scratch.reduction == 1
    full = from_working(scratch.warp(pixel_map, alpha=alpha, antialias=True)).copy()
    return preview, full, reduction


def reference(path: Path, pixel_map, orientation: int = 1) -> np.ndarray:
    """The area-averaged reference: the full decode warped at 8x the output's size (no
    filter: nothing shrinks there), then each 8x8 block averaged."""
    width, height = pixel_map.size
    fine = pixel_map.then(np.array([[8.0, 0, 3.5], [0, 8.0, 3.5], [0, 0, 1]]),
                          (8 * width, 8 * height))
    scratch = Scratch()
    scratch.read(path, orientation=orientation)
    big = from_working(scratch.warp(fine))
    return cv2.resize(big, (width, height), interpolation=cv2.INTER_AREA)


def sampled(path: Path, pixel_map, orientation: int = 1, border: int = 2) -> np.ndarray:
    """Output pixels whose source lies inside the input, ``border`` input-pixel-sized steps
    away from its edges (where the reduced image's part pixels and the fill meet)."""
    width, height = pixel_map.size
    cols, rows = np.meshgrid(np.arange(width, dtype=float), np.arange(height, dtype=float))
    sources = pixel_map.to_input(np.column_stack([cols.ravel(), rows.ravel()]))
    with Image.open(path) as image:
        size = displayed_size(orientation, *image.size)
    margin = border * 8
    with np.errstate(invalid="ignore"):
        inside = np.all((sources >= margin) & (sources <= np.array(size) - 1 - margin), axis=1)
    return inside.reshape(height, width)


def test_a_reduced_decode_is_the_area_average_of_the_full_one(tmp_path):
    """libjpeg-turbo's scaled decoding as the map assumes it: reduced pixel ``k`` is the
    average of input pixels ``r k .. r (k + 1) - 1`` (centre ``(x + 0.5) / r - 0.5``), for
    sides ``r`` does not divide too (the last, part pixel counted whole), for baseline,
    progressive, grey, 4:4:4, 4:2:2 and restart-marked JPEGs: within 40 dB of
    ``cv2.INTER_AREA`` of the full decode (measured: 42-54 dB), where a shift of a quarter of
    a reduced pixel costs 10 dB or more."""
    image = photo(861, 597)  # neither side a multiple of 8 (nor of 2)
    samples = {name: write_jpeg(tmp_path / f"{name}.jpg", source, **options).read_bytes()
               for name, source, options in [
                   ("baseline", image, {}), ("progressive", image, {"progressive": True}),
                   ("grey", cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), {})]}
    for name, params in {"444": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR,
                                 cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444],
                         "422": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR,
                                 cv2.IMWRITE_JPEG_SAMPLING_FACTOR_422],
                         "restarts": [cv2.IMWRITE_JPEG_RST_INTERVAL, 2]}.items():
        samples[name] = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95, *params]
                                     )[1].tobytes()
    for name, data in samples.items():
        full = decode_image(data)
        for reduction in (2, 4, 8):
            assert jpeg_reduction(data, reduction) == reduction
            small = decode_image(data, reduction=reduction)
            width, height = reduced_size(861, 597, reduction)
            assert small.shape[:2] == (height, width)
            inner = (slice(2, height - 2), slice(2, width - 2))  # part pixels off
            # INTER_AREA of the whole pixels the reduced image covers
            whole = full[:(height - 1) * reduction, :(width - 1) * reduction]
            area = cv2.resize(whole, (width - 1, height - 1), interpolation=cv2.INTER_AREA)
            mask = np.ones(area.shape[:2], bool)[inner[0], inner[1]]
            crop = small[:height - 1, :width - 1]
            assert psnr(crop[inner], area[inner], mask) > 40, (name, reduction)
            shift = np.array([[1.0, 0, 0.25], [0, 1.0, 0.25]])
            shifted = cv2.warpAffine(area, shift, area.shape[1::-1],
                                     borderMode=cv2.BORDER_REPLICATE)
            assert psnr(crop[inner], shifted[inner], mask) < 32, (name, reduction)


@pytest.mark.parametrize(("scale", "expected"), [(2.0, 1), (1.0, 1), (0.75, 1), (0.5, 2),
                                                 (0.3, 2), (0.25, 4), (0.2, 4), (0.125, 8),
                                                 (0.05, 8)])
def test_the_reduction_is_the_largest_that_every_sampled_pixel_spans(scale, expected):
    """A frontal view: every output pixel spans ``1 / scale`` input pixels, so the reduction
    is the largest of 2, 4, 8 up to that, 1 below 2; a tilted view at the same scale shrinks
    its near side less, and its reduction follows the least shrink there."""
    frontal = plan_image(View(0, 0, 3200), 4000, 3000, Framing(scale=scale)).pixel_map
    assert preview_reduction(frontal, (4000, 3000)) == expected
    tilted = plan_image(View(15, 30, 3200), 4000, 3000, Framing(scale=scale)).pixel_map
    least = tilted.least_shrink((4000, 3000))
    assert least < 0.9 / scale  # the near side shrinks less than the frontal scale says
    chosen = preview_reduction(tilted, (4000, 3000))
    assert chosen == max([1] + [r for r in (2, 4, 8) if r <= least])


def test_a_preview_matches_the_full_decode_and_the_reference(tmp_path):
    """A real photo (colour, and grey) at a fifth and a tenth of its size: decoded 4 and 8
    times smaller, the preview is close to the area-averaged reference (measured: 33.4 and
    29.7 dB), no further from it than the full path's output is, less 1 dB (measured: 6.2-6.6
    dB nearer), and within 20 dB of that output (measured: 28.2 and 24.9 dB; they differ in
    their filter, the DCT's box against the warp's Gaussian pyramid, which blurs more)."""
    colour = write_jpeg(tmp_path / "facade.jpg", photo())
    grey = write_jpeg(tmp_path / "grey.jpg", cv2.cvtColor(photo(), cv2.COLOR_BGR2GRAY))
    for path, scale, expected in [(colour, 0.2, 4), (colour, 0.1, 8), (grey, 0.2, 4)]:
        pixel_map = plan_image(View(8, 4, 900), 868, 600, Framing(scale=scale)).pixel_map
        preview, full, reduction = both(path, pixel_map)
        assert reduction == expected
        mask = sampled(path, pixel_map)
        assert mask.mean() > 0.5
        assert psnr(preview, full, mask) > 20, scale
        truth = reference(path, pixel_map)
        assert psnr(preview, truth, mask) > 28, scale
        assert psnr(preview, truth, mask) >= psnr(full, truth, mask) - 1, scale


@pytest.mark.parametrize(("pan", "tilt", "focal", "scale"),
                         [(8, 4, 900, 0.3), (-20, 10, 700, 0.3), (15, 30, 700, 0.25)])
def test_a_reduced_decode_antialiased_again_is_not_shifted(tmp_path, pan, tilt, focal, scale):
    """Where the reduced decode meets the pyramid: decoded 2 times smaller (a box average,
    its pixels centred at ``(x + 0.5) / 2 - 0.5``), the reduced image still shrinks by more
    than 1.5 on its far side and is antialiased through ``cv2.pyrDown``'s levels (centred on
    every ``2^l``-th reduced pixel). The preview is under 0.05 output pixels off the
    area-averaged reference by phase correlation (measured: 0.009-0.015; 0.13-0.23 with the
    levels placed as a box average's pixels)."""
    path = write_jpeg(tmp_path / "facade.jpg", photo())
    pixel_map = plan_image(View(pan, tilt, focal), 868, 600, Framing(scale=scale)).pixel_map
    preview, _, reduction = both(path, pixel_map)
    assert reduction == 2
    assert pixel_map.reduced(2).shrink(8, (434, 300)).max() > 1.5
    truth = reference(path, pixel_map)

    def grey(image: np.ndarray) -> np.ndarray:
        return cv2.cvtColor(image[..., :3], cv2.COLOR_BGR2GRAY)

    assert phase_shift(grey(truth), grey(preview)) < 0.05


@pytest.mark.parametrize("orientation", range(1, 9))
def test_every_exif_orientation_of_an_odd_sized_jpeg(tmp_path, orientation):
    """A phone-style JPEG stored turned (EXIF orientations 1-8), its sides not multiples of 4
    (part pixels at the reduced image's end, which a mirrored axis puts at its start): the
    preview decoded 4 times smaller is within 30 dB of the reference (measured: 32.1-32.4;
    18-22 dB without the shift of the mirrored axes), as near to it as the full path's output
    is, less 1 dB, and within 20 dB of that output (measured: 28.6-29.5)."""
    stored = photo(861, 597)
    path = write_jpeg(tmp_path / "turned.jpg", stored, orientation)
    width, height = displayed_size(orientation, 861, 597)
    pixel_map = plan_image(View(10, -6, 1000), width, height, Framing(scale=0.22)).pixel_map
    preview, full, reduction = both(path, pixel_map, orientation)
    assert reduction == 4
    mask = sampled(path, pixel_map, orientation)
    assert psnr(preview, full, mask) > 20
    truth = reference(path, pixel_map, orientation)
    assert psnr(preview, truth, mask) > 30
    assert psnr(preview, truth, mask) >= psnr(full, truth, mask) - 1


def test_a_lens_and_alpha_on_the_reduced_path(tmp_path):
    """Through a distorting lens (one remap through the reduced lens's maps) and with an
    alpha channel (transparent where nothing is sampled): decoded 2 times smaller (the lens
    magnifies the corners' pixels), the preview agrees with the full path within 30 dB in
    colour (measured: 38.6), is as near the reference, less 1 dB, and its alpha is the full
    path's but at the edges."""
    path = write_jpeg(tmp_path / "lens.jpg", photo())
    lens = Lens("plumb_bob", (("k1", -0.2), ("k2", 0.05)))
    pixel_map = plan_image(View(12, 5, 900, lens=lens), 868, 600,
                           Framing(bbox="full", scale=0.2)).pixel_map
    preview, full, reduction = both(path, pixel_map, alpha=True)
    assert reduction == 2 and preview.shape[2] == 4
    mask = sampled(path, pixel_map)
    assert mask.mean() > 0.3
    assert psnr(preview[..., :3], full[..., :3], mask) > 30
    truth = reference(path, pixel_map)
    assert psnr(preview[..., :3], truth, mask) >= psnr(full[..., :3], truth, mask) - 1
    def inner(where: np.ndarray) -> np.ndarray:  # 2 pixels off its edges and the frame's
        return cv2.erode(where.astype(np.uint8), np.ones((5, 5), np.uint8),
                         borderType=cv2.BORDER_CONSTANT, borderValue=0)

    opaque, clear = inner(full[..., 3] == 255), inner(full[..., 3] == 0)
    assert opaque.any() and clear.any()
    assert (preview[..., 3][opaque > 0] == 255).all()
    assert (preview[..., 3][clear > 0] == 0).all()


def test_outputs_at_scale_one_and_above_are_the_full_decodes(tmp_path):
    """Where some sampled output pixel spans fewer than 2 input pixels (any scale from 1 up,
    or a tilted view whose near side is magnified) nothing is reduced: the preview path gives
    the full path's output, byte for byte."""
    path = write_jpeg(tmp_path / "facade.jpg", photo())
    for view, framing in [(View(8, 4, 900), Framing()), (View(8, 4, 900), Framing(scale=1.5)),
                          (View(0, 0, 900), Framing(scale=0.6)),
                          (View(35, 25, 500), Framing(scale=0.4))]:
        pixel_map = plan_image(view, 868, 600, framing).pixel_map
        preview, full, reduction = both(path, pixel_map)
        assert reduction == 1
        np.testing.assert_array_equal(preview, full)


def test_cmyk_jpegs_pngs_and_16_bit_images_decode_whole(tmp_path):
    """What libjpeg-turbo does not decode here (a CMYK JPEG: OpenCV's), any other format (a
    16-bit PNG) and images under 64 pixels a side decode whole, as before, whatever the
    map: the output is the full path's, byte for byte."""
    image = photo()
    cmyk = tmp_path / "cmyk.jpg"
    Image.fromarray(image[..., ::-1].copy()).convert("CMYK").save(cmyk, quality=95)
    png = tmp_path / "deep.png"
    cv2.imwrite(str(png), image.astype(np.uint16) * 257)
    tiny = write_jpeg(tmp_path / "tiny.jpg", image[:60, :500])
    assert jpeg_reduction(cmyk.read_bytes(), 8) == 1
    assert jpeg_reduction(png.read_bytes(), 8) == 1
    assert jpeg_reduction(tiny.read_bytes(), 8) == 1
    for path, size in [(cmyk, (868, 600)), (png, (868, 600)), (tiny, (500, 60))]:
        pixel_map = plan_image(View(0, 0, 900), *size, Framing(scale=0.1)).pixel_map
        assert preview_reduction(pixel_map, size) == 8
        preview, full, reduction = both(path, pixel_map)
        assert reduction == 1
        np.testing.assert_array_equal(preview, full)
    with io.BytesIO() as buffer:  # the CMYK JPEG really is CMYK
        buffer.write(cmyk.read_bytes())
        buffer.seek(0)
        assert Image.open(buffer).mode == "CMYK"
