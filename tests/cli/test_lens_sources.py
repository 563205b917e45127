"""Where ``gsrwt rectify`` takes an image's lens from (the table's ``lens_source``): lens
columns (``sidecar``), a calibration file (``camera``), lensfun's database (``lensfun``) or
nowhere (``none``); and without the extra ``gsrwt[lenses]`` a photo whose camera lensfun
knows is rectified as before, with no error.

Runs with or without lensfunpy: its absence is made real in the command's process by a
``sitecustomize`` that marks the module missing (``sys.modules["lensfunpy"] = None``: what
``importlib`` reports for a module that is not installed).
"""

from __future__ import annotations

import importlib.util
import io

import cv2
import numpy as np
import pytest
from PIL import Image

from tests.helpers.cli import run_gsrwt
from tests.helpers.images import smooth_texture
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

OLYMPUS = ("OLYMPUS IMAGING CORP.", "E-M10", "M.Zuiko Digital ED 14-42mm f/3.5-5.6", 14.0)


def write_photo(path, tags=OLYMPUS, size=(640, 480)) -> None:
    """A JPEG whose EXIF names a camera and lens that lensfun's database has."""
    exif = Image.Exif()
    if tags is not None:
        exif[0x010F], exif[0x0110] = tags[0], tags[1]
        ifd = exif.get_ifd(0x8769)
        ifd[0xA434], ifd[0x920A] = tags[2], tags[3]
    pixels = smooth_texture(size[1], size[0], 3)[..., ::-1]
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels)).save(buffer, "JPEG", quality=95, exif=exif)
    path.write_bytes(buffer.getvalue())


def rectify(folder, *options, env=None):
    result = run_gsrwt("rectify", str(folder), "-o", str(folder / "out"), "--table",
                       str(folder / "table.csv"), "-q", *options, env=env)
    assert result.returncode == 0, result.stderr
    return {row["image"].rsplit("/", 1)[-1]: row for row in read_table(folder / "table.csv")}


def test_each_source_of_a_lens_is_named(tmp_path):
    for name in ("lens.jpg", "declared.jpg", "camera.jpg", "exif.jpg"):
        write_photo(tmp_path / name)
    write_photo(tmp_path / "plain.jpg", tags=None)
    camera = DATA / "right_camera.yml"
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal,k1,distortion_model,camera\n"
        "lens.jpg,10,5,500,-0.1,,\n"
        "declared.jpg,10,5,500,,plumb_bob,\n"  # a pinhole declared: no profile looked for
        f"camera.jpg,10,5,,,,{camera}\n"
        "exif.jpg,10,5,500,,,\n"
        "plain.jpg,10,5,500,,,\n")
    rows = rectify(tmp_path, "--sidecar", str(tmp_path / "views.csv"))
    installed = importlib.util.find_spec("lensfunpy") is not None
    expected = {"lens.jpg": "sidecar", "declared.jpg": "sidecar", "camera.jpg": "camera",
                "exif.jpg": "lensfun" if installed else "none", "plain.jpg": "none"}
    assert {name: row["lens_source"] for name, row in rows.items()} == expected
    assert all(row["status"] == "ok" for row in rows.values())
    named = {name for name, row in rows.items() if row["lens_profile"]}
    assert named == ({"exif.jpg"} if installed else set())


def test_without_the_extra_a_known_camera_is_rectified_as_before(tmp_path):
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text('import sys\nsys.modules["lensfunpy"] = None\n')
    photos = tmp_path / "photos"
    photos.mkdir()
    write_photo(photos / "known.jpg")
    write_photo(photos / "plain.jpg", tags=None)
    rows = rectify(photos, "--pan", "15", "--tilt", "5", "--focal", "450",
                   env={"PYTHONPATH": str(hide)})
    assert {name: (row["lens_source"], row["lens_profile"], row["status"])
            for name, row in rows.items()} == {"known.jpg": ("none", "", "ok"),
                                               "plain.jpg": ("none", "", "ok")}
    # The same pixels (the outputs' metadata differ: known.jpg's EXIF is kept).
    assert np.array_equal(cv2.imread(str(photos / "out" / "known.jpg")),
                          cv2.imread(str(photos / "out" / "plain.jpg")))


def test_a_rerun_notices_a_profile_found_since(tmp_path):
    """A profile is found in the photo's EXIF, not in the values ``made_with`` records: a
    rerun after installing the extra names the change instead of keeping the pinhole output
    (and one without the extra keeps it)."""
    pytest.importorskip("lensfunpy")
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text('import sys\nsys.modules["lensfunpy"] = None\n')
    photos = tmp_path / "photos"
    photos.mkdir()
    write_photo(photos / "known.jpg")
    write_photo(photos / "plain.jpg", tags=None)

    def run(env=None):
        result = run_gsrwt("rectify", str(photos), "--pan", "15", "--tilt", "5", "--focal",
                           "450", "-o", str(photos / "out"), "-q", env=env)
        rows = {row["image"].rsplit("/", 1)[-1]: row
                for row in read_table(photos / "out" / "gsrwt.csv")}
        return result.returncode, {name: (row["status"], row["error"])
                                   for name, row in rows.items()}

    hidden = {"PYTHONPATH": str(hide)}
    assert run(hidden) == (0, {"known.jpg": ("ok", ""), "plain.jpg": ("ok", "")})
    assert run(hidden) == (0, {"known.jpg": ("skipped", ""), "plain.jpg": ("skipped", "")})
    code, rows = run()
    assert code == 1 and rows["plain.jpg"] == ("skipped", "")
    assert rows["known.jpg"][0] == "error"
    assert "(lens_source none -> lensfun); use --overwrite" in rows["known.jpg"][1]
    done = run_gsrwt("rectify", str(photos), "--pan", "15", "--tilt", "5", "--focal", "450",
                     "-o", str(photos / "out"), "-q", "--overwrite")
    assert done.returncode == 0, done.stderr
    assert run() == (0, {"known.jpg": ("skipped", ""), "plain.jpg": ("skipped", "")})


def test_lens_profile_off_and_lensfun_asked_for(tmp_path):
    """``--lens-profile off``: a pinhole for every photo whose lens is given nowhere (and
    ``made_with`` says so); ``--lens-profile lensfun`` without the extra: a usage error."""
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text('import sys\nsys.modules["lensfunpy"] = None\n')
    photos = tmp_path / "photos"
    photos.mkdir()
    write_photo(photos / "known.jpg")
    write_photo(photos / "plain.jpg", tags=None)
    rows = rectify(photos, "--pan", "15", "--tilt", "5", "--focal", "450", "--lens-profile",
                   "off")
    assert {name: row["lens_source"] for name, row in rows.items()} == {"known.jpg": "none",
                                                                         "plain.jpg": "none"}
    assert all(" lens_profile=off " in row["made_with"] for row in rows.values())
    # The same pixels (the outputs' metadata differ: known.jpg's EXIF is kept).
    assert np.array_equal(cv2.imread(str(photos / "out" / "known.jpg")),
                          cv2.imread(str(photos / "out" / "plain.jpg")))
    for command in (("rectify", str(photos), "-o", str(tmp_path / "out2"), "--pan", "15",
                     "--tilt", "5"), ("estimate", str(photos))):
        refused = run_gsrwt(*command, "--focal", "450", "--lens-profile", "lensfun",
                            env={"PYTHONPATH": str(hide)})
        assert refused.returncode == 2, refused.stderr
        assert refused.stderr.strip().splitlines()[-1] == (
            "Error: Invalid value for '--lens-profile': lensfun needs the extra: pip install "
            "'gsrwt[lenses]'"), refused.stderr
        assert "Traceback" not in refused.stderr


def test_the_options_choices_are_the_modes():
    from gsrwt_cli.cli.options import LENS_PROFILE_CHOICES
    from gsrwt_cli.inputs.lensfun import LENS_PROFILE_MODES

    assert LENS_PROFILE_CHOICES == LENS_PROFILE_MODES
