"""The forward model (``batch/render_jobs.py``): renders checked against the independent pinhole
camera, and the render batch's plans, checks and typed errors."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gsrwt_cli import View
from gsrwt_cli.batch.render_jobs import plan_one_view, plan_views, render_views, write_views_sidecar
from gsrwt_cli.batch.render_jobs import render_view as gsrwt_render_view
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.io.targets import DirectoryTargetError, ExistingOutputError, InputOverwriteError
from tests.helpers.camera import render_view
from tests.helpers.images import psnr, smooth_texture

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
