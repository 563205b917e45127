"""``gsrwt render``: the forward model, checked against the independent pinhole camera."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from conftest import psnr, render_view, smooth_texture

from gsrwt_cli import View
from gsrwt_cli.batch.render_jobs import plan_one_view, plan_views, render_views, write_views_sidecar
from gsrwt_cli.batch.render_jobs import render_view as gsrwt_render_view
from gsrwt_cli.cli import main
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.io.targets import DirectoryTargetError, ExistingOutputError, InputOverwriteError

TEXTURE = smooth_texture(900, 1200, seed=5)


@pytest.mark.parametrize(
    ("pan", "tilt", "focal", "width", "height", "cx", "cy"),
    [(15, 30, 280, 320, 240, None, None), (-30, 20, 800, 640, 480, 300.0, 260.0),
     (40, -25, 500, 480, 360, None, None), (0, 0, 300, 400, 300, None, None)],
)
def test_render_matches_the_independent_pinhole_camera(pan, tilt, focal, width, height, cx, cy):
    view = View(pan, tilt, focal, cx=cx, cy=cy, width=width, height=height)
    ours = gsrwt_render_view(TEXTURE, view)
    theirs, seen, _ = render_view(TEXTURE, pan, tilt, focal, width, height, view.cx, view.cy,
                                  centre=np.array([0.0, 0.0]))
    inner = cv2.erode(seen.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    assert inner.mean() > 0.3
    assert psnr(ours, theirs, inner) > 50
    assert (ours[~cv2.dilate(seen.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)]
            == 0).all()


def test_render_writes_a_sidecar_that_rectify_reads_back(tmp_path):
    cv2.imwrite(str(tmp_path / "wall.png"), TEXTURE)
    runner = CliRunner()
    rendered = runner.invoke(main, ["render", str(tmp_path / "wall.png"), "--pan", "20",
                                    "--tilt", "-15", "--focal", "400", "--width", "480",
                                    "--height", "360", "-o", str(tmp_path / "view.png")])
    assert rendered.exit_code == 0, rendered.output
    record = yaml.safe_load((tmp_path / "view.yaml").read_text())["view.png"]
    assert record == {"pan": 20.0, "tilt": -15.0, "focal": 400.0, "cx": 239.5, "cy": 179.5,
                      "width": 480, "height": 360}
    again = runner.invoke(main, ["render", str(tmp_path / "wall.png"), "--pan", "20",
                                 "--tilt", "-15", "--focal", "400", "-o",
                                 str(tmp_path / "view.png")])
    assert again.exit_code == 2 and "exists; use --overwrite" in again.stderr
    rectified = runner.invoke(main, ["rectify", str(tmp_path / "view.png"), "-o",
                                     str(tmp_path / "out"), "-j", "1"])
    assert rectified.exit_code == 0, rectified.output
    output = cv2.imread(str(tmp_path / "out" / "view.png"))
    # The rectified render is the texture, shifted so the optical axis lands on the centre.
    axis_col = 599.5 - 400 * np.tan(np.radians(20))
    axis_row = 449.5 - 400 * np.tan(np.radians(-15)) / np.cos(np.radians(20))
    shift = np.float32([[1, 0, axis_col - 239.5], [0, 1, axis_row - 179.5]])
    expected = cv2.warpAffine(TEXTURE, shift, (480, 360), flags=cv2.INTER_LINEAR | (
        cv2.WARP_INVERSE_MAP))
    centre = np.zeros((360, 480), bool)
    centre[60:300, 80:400] = True
    assert psnr(output, expected, centre) >= 30


def test_render_many_views_from_a_sidecar(tmp_path):
    cv2.imwrite(str(tmp_path / "wall.png"), TEXTURE)
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal,width,height\n"
        "a.png,10,20,300,400,300\nb.jpg,-20,95,300,400,300\nc.jpg,-30,-10,500,640,480\n"
    )
    result = CliRunner().invoke(main, ["render", str(tmp_path / "wall.png"), "--sidecar",
                                       str(tmp_path / "views.csv"), "-o", str(tmp_path / "r"),
                                       "--out-sidecar", str(tmp_path / "r" / "views.yaml")])
    assert result.exit_code == 1
    assert "views.csv line 3, field 'tilt': tilt must be strictly between" in result.stderr
    assert sorted(p.name for p in (tmp_path / "r").iterdir()) == ["a.png", "c.jpg",
                                                                   "views.yaml"]
    records = {r.image: r.view() for r in load_sidecar(tmp_path / "r" / "views.yaml").records}
    assert records["c.jpg"].pan == -30 and records["c.jpg"].width == 640
    assert cv2.imread(str(tmp_path / "r" / "c.jpg")).shape == (480, 640, 3)


def test_the_core_plans_checks_and_renders_views_without_naming_options(tmp_path):
    """The library's render batch: typed errors carrying the path, no command-line words."""
    texture = TEXTURE[:300, :400]
    values = {"pan": 10, "tilt": 5, "focal": 200, "width": 80, "height": 60}
    plan = plan_one_view(values, tmp_path / "v.png")
    assert plan.sidecar == tmp_path / "v.yaml" and plan.root is None
    (tmp_path / "v.png").write_bytes(b"old")
    with pytest.raises(ExistingOutputError) as existing:
        render_views(texture, plan)
    assert existing.value.path == tmp_path / "v.png" and "--" not in str(existing.value)
    with pytest.raises(InputOverwriteError):
        render_views(texture, plan, inputs=[tmp_path / "v.png"], overwrite=True)
    (result,) = render_views(texture, plan, overwrite=True)
    assert result.error is None and cv2.imread(str(tmp_path / "v.png")).shape == (60, 80, 3)
    write_views_sidecar(plan.sidecar, [result.job])
    (record,) = load_sidecar(plan.sidecar).records
    assert record.view() == result.job.view
    with pytest.raises(DirectoryTargetError):
        plan_one_view(values, tmp_path)

    records = load_sidecar(_sidecar(tmp_path, "image,pan,tilt,focal\nok.png,1,2,200\n"
                                              "../out.png,1,2,200\nbad.png,1,95,200\n")).records
    many = plan_views(records, tmp_path / "many", {"width": 80, "height": 60})
    assert [job.name for job in many.jobs] == ["ok.png"]
    assert [(error.field, "--" in str(error)) for error in many.errors] == [("image", False),
                                                                             ("tilt", False)]
    (result,) = render_views(texture, many)
    assert result.error is None and (tmp_path / "many" / "ok.png").is_file()


def _sidecar(directory, text):
    path = directory / "views.csv"
    path.write_text(text)
    return path
