"""Numbers typed as options, and the hints of the messages that refuse something.

Every number an option takes is ASCII digits, bounded: Python's ``int`` and ``float`` would
take ``1_0``, Arabic-Indic digits, ``+1`` and `` 2``. Every hint names a remedy that is not
already in use and does not leave out the real one. Each case runs the installed ``gsrwt``.
"""

from __future__ import annotations

from pathlib import Path

import click
import pytest

from gsrwt_cli.cli import COMMANDS, main
from gsrwt_cli.cli.options import MAX_JOBS, Integer, Number
from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import SAMPLE_VIEWS as SAMPLES

FRONTAL = str(SAMPLES / "corridor_p0_t30.png")  # 320x240
RECTIFY = ("rectify", FRONTAL, "--pan", "0", "--tilt", "0", "--focal", "300", "-o", "out")
ARABIC_INDIC_ONE = "\u0661"


@pytest.mark.parametrize(("args", "option", "value", "problem"), [
    (RECTIFY, "--jobs", "1_0", "expected a whole number in ASCII digits"),
    (RECTIFY, "--jobs", ARABIC_INDIC_ONE, "expected a whole number in ASCII digits"),
    (RECTIFY, "--jobs", "+1", "expected a whole number in ASCII digits"),
    (RECTIFY, "--jobs", " 2", "expected a whole number in ASCII digits"),
    (RECTIFY, "--jobs", "99999999999999999999999", "out of range"),
    (RECTIFY, "--jobs", str(MAX_JOBS + 1), f"is not in the range 1<=x<={MAX_JOBS}"),
    (RECTIFY, "--quality", "9_0", "expected a whole number in ASCII digits"),
    (RECTIFY, "--retries", "+1", "expected a whole number in ASCII digits"),
    (RECTIFY, "--width", "3_20", "expected a whole number in ASCII digits"),
    (RECTIFY, "--max-size", "1_920x1080", "expected WIDTHxHEIGHT"),
    (RECTIFY, "--max-size", "+1920x1080", "expected WIDTHxHEIGHT"),
    (RECTIFY, "--max-size", f"{ARABIC_INDIC_ONE}920x1080", "expected WIDTHxHEIGHT"),
    (RECTIFY, "--max-pixels", "5_0M", "expected a pixel count"),
    (RECTIFY, "--max-pixels", f"{ARABIC_INDIC_ONE}M", "expected a pixel count"),
    (RECTIFY, "--max-input-pixels", "3_00M", "expected a pixel count"),
    (RECTIFY, "--scale", "1_0", "expected a finite decimal number in ASCII digits"),
    (RECTIFY, "--roll", ARABIC_INDIC_ONE, "expected a finite decimal number in ASCII digits"),
    (RECTIFY, "--fill", "nan", "must be finite"),
    (RECTIFY, "--scale", "1e400", "beyond floating point"),
    (RECTIFY, "--bbox", "0,0,1_0,10", "expected frontal, full, crop or X0,Y0,X1,Y1"),
    (RECTIFY, "--min-confidence", "nan", "must be finite"),
    (("estimate", FRONTAL), "--jobs", "1_0", "expected a whole number in ASCII digits"),
    (("estimate", FRONTAL), "--focal", "3_00", "expected a finite decimal number"),
    (("params", "--tilt", "3", "--focal", "300"), "--pan", "1_5",
     "expected a finite decimal number"),
    (("track", "--distance", "25", "--object", "33"), "--positions", "1_0,2",
     "expected numbers separated by commas"),
    (("track", "--object", "33", "--positions", "0"), "--distance", "2_5",
     "expected a finite decimal number"),
    (("gaze", "--pan", "3", "--tilt", "3", "--focal", "300"), "--to-pixel", "4_0,20",
     "expected two numbers A,B"),
    (("match", FRONTAL, "--template", FRONTAL), "--scales", "0.5,1_0", "expected MIN,MAX"),
    (("lines", FRONTAL), "--min-votes", "1_0", "expected a whole number in ASCII digits"),
    (("lines", FRONTAL), "--max-gap", "inf", "must be finite"),
])
def test_a_number_option_takes_ascii_digits_only(tmp_path, args, option, value, problem):
    result = run_gsrwt(*args, option, value, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    last = result.stderr.splitlines()[-1]
    assert last.startswith("Error: Invalid value for ") and option in last
    assert problem in last
    assert "Traceback" not in result.stderr
    assert list(tmp_path.iterdir()) == []  # refused before any work


def test_every_number_option_of_every_command_is_read_as_ascii_digits():
    """No option takes Python's own int() or float() of what is typed (Integer and Number
    read ASCII digits); a new option with ``type=int`` or ``type=float`` fails here."""
    context = click.Context(main)
    plain = []
    for name in COMMANDS:
        for param in main.get_command(context, name).params:
            if isinstance(param.type, click.types._NumberParamTypeBase) and not isinstance(
                    param.type, Integer | Number):
                plain.append(f"{name} {param.opts[-1]}")
    assert plain == []


def test_valid_numbers_still_work(tmp_path):
    result = run_gsrwt(*RECTIFY, "-j", "1", "--quality", "90", "--roll", "+0.0",
                       "--scale", ".5", "--max-size", "1920x1080", "--max-pixels", "2.5e6",
                       "--table", "-", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out" / "corridor_p0_t30.png").is_file()


def error_line(result) -> str:
    """The one ``Error:`` line of an image's failure in a batch."""
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert len(errors) == 1, result.stderr
    return errors[0]


def test_nothing_within_max_stretch_of_a_frontal_view_names_no_vanishing_line(tmp_path):
    result = run_gsrwt(*RECTIFY, "--bbox", "full", "--max-stretch", "0.5", cwd=tmp_path)
    assert result.returncode == 1
    assert error_line(result) == (
        f"Error: {FRONTAL}: no part of the image is within --max-stretch 0.5 (every visible "
        "pixel is magnified more than 0.5 times as much as the principal point); raise "
        "--max-stretch (below 1, the principal point itself is beyond it), or use --bbox "
        "frontal")


def test_nothing_within_max_stretch_beyond_the_vanishing_line_says_so(tmp_path):
    # The principal point far right of the image, the horizon between it and the image:
    # every pixel of the image is beyond the vanishing line.
    result = run_gsrwt("rectify", FRONTAL, "--pan", "40", "--tilt", "0", "--focal", "300",
                       "--cx", "2000", "--cy", "120", "--bbox", "full", "-o", "out",
                       cwd=tmp_path)
    assert result.returncode == 1
    assert error_line(result) == (
        f"Error: {FRONTAL}: no part of the image is in front of the vanishing line; check the "
        "pose and the principal point")


def test_a_crop_with_no_rectangle_within_max_stretch_says_so(tmp_path):
    # At pan 60 a stretch of 0.2704-0.2710 keeps a sliver of the near edge, too thin to
    # hold one cell of the crop's lattice.
    result = run_gsrwt("rectify", FRONTAL, "--pan", "60", "--tilt", "0", "--focal", "300",
                       "--bbox", "crop", "--max-stretch", "0.2707", "-o", "out", cwd=tmp_path)
    assert result.returncode == 1
    assert error_line(result) == (
        f"Error: {FRONTAL}: --bbox crop finds no rectangle without fill within --max-stretch "
        "0.2707; raise --max-stretch, or use --bbox full")


@pytest.mark.parametrize(("options", "remedies"), [
    (("--bbox", "0,0,1000,1", "--max-size", "1x1"), "the output would be empty (1x0 pixels); "
                                                    "use a larger --scale, a larger "
                                                    "--max-size or a larger --bbox"),
    (("--scale", "0.001"), "the output would be empty (0x0 pixels); use a larger --scale"),
])
def test_an_empty_output_names_what_makes_it_larger(tmp_path, options, remedies):
    result = run_gsrwt(*RECTIFY, *options, cwd=tmp_path)
    assert result.returncode == 1
    assert error_line(result) == f"Error: {FRONTAL}: {remedies}"


@pytest.mark.parametrize(("options", "remedies"), [
    ((), "--max-size WxH, a smaller --scale or a higher --max-pixels"),
    (("--bbox", "full"), "--max-size WxH, a smaller --scale, a lower --max-stretch, "
                         "--bbox frontal or a higher --max-pixels"),
    (("--max-size", "100x100"), "a smaller --max-size, a smaller --scale or a higher "
                                "--max-pixels"),
    (("--px-per-unit", "100", "--distance", "3"), "--max-size WxH, a smaller --px-per-unit or "
                                                  "a higher --max-pixels"),
])
def test_an_output_too_large_suggests_only_what_is_not_in_use(tmp_path, options, remedies):
    result = run_gsrwt(*RECTIFY, "--max-pixels", "1000", *options, cwd=tmp_path)
    assert result.returncode == 1
    line = error_line(result)
    assert line.startswith(f"Error: {FRONTAL}: the output would be ")
    assert line.endswith(f"above --max-pixels 0.001 megapixels; use {remedies}")


def test_an_output_too_large_gives_its_size_in_digits_that_show_it(tmp_path):
    result = run_gsrwt(*RECTIFY, "--max-pixels", "1000", "--max-size", "100x100",
                       cwd=tmp_path)
    assert "the output would be 100x75 = 0.0075 megapixels, above --max-pixels 0.001 " \
           "megapixels" in error_line(result)


def test_no_parameters_names_the_sidecar_and_auto(tmp_path):
    alone = run_gsrwt("rectify", FRONTAL, "-o", "out", cwd=tmp_path)
    assert alone.returncode == 1
    assert error_line(alone) == (
        f"Error: {FRONTAL}: no parameters: no corridor_p0_t30.yaml beside it, no --pan/--tilt; "
        "give them in a --sidecar, or estimate the pose with --auto")
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\nother.png,1,2,300\n")
    listed = run_gsrwt("rectify", FRONTAL, "--sidecar", str(sidecar), "-o", "out",
                       cwd=tmp_path)
    assert listed.returncode == 1
    assert error_line(listed) == (
        f"Error: {FRONTAL}: no parameters: not in {sidecar}, no corridor_p0_t30.yaml beside "
        f"it, no --pan/--tilt; add it to {sidecar}, or estimate the pose with --auto")


def test_px_per_unit_without_a_distance_says_how_to_give_one(tmp_path):
    result = run_gsrwt(*RECTIFY, "--px-per-unit", "3", cwd=tmp_path)
    assert result.returncode == 1
    assert error_line(result) == (
        f"Error: {FRONTAL}: --px-per-unit needs the camera-to-wall 'distance' of the image; "
        "give it (--distance or a 'distance' column) or use --scale")


def test_a_pixel_target_with_half_an_image_size_asks_for_the_other_half(tmp_path):
    result = run_gsrwt("gaze", "--pan", "3", "--tilt", "3", "--focal", "300", "--width", "320",
                       "--to-pixel", "3,4", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip() == (
        "Error: --to-pixel needs --height too (the image size), or --cx --cy")


FRAMED_OUT = "no pixel of the frontal frame (--bbox frontal, around where the optical axis "


@pytest.mark.parametrize(("options", "message"), [
    # The whole image beyond the horizon: no frame can see it.
    (("--cx", "2000", "--cy", "120"), "no part of the image is in front of the vanishing line; "
                                      "check the pose and the principal point"),
    # The image sees the wall, but not where the default frame lies.
    (("--cx", "600", "--cy", "120"), FRAMED_OUT + "meets the wall) has a source in the "
     "image; check the pose and the principal point, or frame what it sees with --bbox full"),
    (("--camera", "lens.yaml"), FRAMED_OUT + "meets the wall) has a source in the image; "
     "check the pose and the principal point, or frame what it sees with --bbox full"),
    (("--bbox", "5000,5000,5100,5100"), "no pixel of --bbox has a source in the image: the box "
     "lies where the image does not see the wall; choose one within --bbox full's frame"),
])
def test_a_frame_with_no_source_is_an_error_never_an_all_fill_ok(tmp_path, options, message):
    """An output whose every pixel would be fill is refused with the reason (it was ``ok``,
    all black, at pan 40 with the principal point right of the image); through a lens too
    (a calibration file with the principal point at (600, 120) and k1 = -0.05)."""
    from gsrwt_cli.geometry.camera import Intrinsics
    from gsrwt_cli.geometry.lens import Lens
    from gsrwt_cli.inputs.calibration import write_opencv_yaml

    write_opencv_yaml(tmp_path / "lens.yaml", Intrinsics(
        300.0, 300.0, 600.0, 120.0, width=320, height=240,
        lens=Lens("plumb_bob", (("k1", -0.05),))))
    result = run_gsrwt("rectify", FRONTAL, "--pan", "40", "--tilt", "0", "--focal", "300",
                       *options, "-o", "out", cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    assert error_line(result) == f"Error: {FRONTAL}: {message}"
    assert not (tmp_path / "out" / Path(FRONTAL).name).exists()


def test_a_box_that_reaches_the_image_by_a_sliver_is_framed_exactly(tmp_path):
    """Whether a frame sees the image is decided exactly (the output rectangle clipped by the
    horizon and the image's edges), not by samples: at pan 20 the image's right edge lies at
    x = 311.7404 in the default frame (pixel edges), so a box from x = 311.5 keeps a sliver a
    quarter of a pixel wide, and one from 311.8 none."""
    import cv2
    import numpy as np

    view = ("--pan", "20", "--tilt", "0", "--focal", "300")
    inside = run_gsrwt("rectify", FRONTAL, *view, "--bbox", "311.5,0,411.5,240", "--alpha",
                       "--ext", "png", "-o", "in", cwd=tmp_path)
    assert inside.returncode == 0, inside.stderr
    output = cv2.imread(str(tmp_path / "in" / Path(FRONTAL).name), cv2.IMREAD_UNCHANGED)
    assert np.count_nonzero(output[..., 3]) > 0  # some pixels have a source
    outside = run_gsrwt("rectify", FRONTAL, *view, "--bbox", "311.8,0,411.8,240", "-o", "out",
                        cwd=tmp_path)
    assert outside.returncode == 1
    assert "no pixel of --bbox has a source in the image" in error_line(outside)
