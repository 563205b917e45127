"""``gsrwt render``: the views it writes and the sidecar that ``gsrwt rectify`` reads back."""

from __future__ import annotations

import cv2
import numpy as np
import yaml

from gsrwt_cli.inputs.sidecar import load_sidecar
from tests.helpers.cli import run_gsrwt
from tests.helpers.images import psnr, smooth_texture

TEXTURE = smooth_texture(900, 1200, seed=5)


def test_render_writes_a_sidecar_that_rectify_reads_back(tmp_path):
    cv2.imwrite(str(tmp_path / "wall.png"), TEXTURE)
    rendered = run_gsrwt("render", str(tmp_path / "wall.png"), "--pan", "20", "--tilt", "-15",
                         "--focal", "400", "--width", "480", "--height", "360", "-o",
                         str(tmp_path / "view.png"))
    assert rendered.returncode == 0, rendered.stderr
    record = yaml.safe_load((tmp_path / "view.yaml").read_text())["view.png"]
    assert record == {"pan": 20.0, "tilt": -15.0, "focal": 400.0, "cx": 239.5, "cy": 179.5,
                      "width": 480, "height": 360}
    again = run_gsrwt("render", str(tmp_path / "wall.png"), "--pan", "20", "--tilt", "-15",
                      "--focal", "400", "-o", str(tmp_path / "view.png"))
    assert again.returncode == 2 and "exists; use --overwrite" in again.stderr
    rectified = run_gsrwt("rectify", str(tmp_path / "view.png"), "-o", str(tmp_path / "out"),
                          "-j", "1")
    assert rectified.returncode == 0, rectified.stderr
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
    result = run_gsrwt("render", str(tmp_path / "wall.png"), "--sidecar",
                       str(tmp_path / "views.csv"), "-o", str(tmp_path / "r"), "--out-sidecar",
                       str(tmp_path / "r" / "views.yaml"))
    assert result.returncode == 1
    assert "views.csv line 3, field 'tilt': tilt must be strictly between" in result.stderr
    assert sorted(p.name for p in (tmp_path / "r").iterdir()) == ["a.png", "c.jpg",
                                                                   "views.yaml"]
    records = {r.image: r.view() for r in load_sidecar(tmp_path / "r" / "views.yaml").records}
    assert records["c.jpg"].pan == -30 and records["c.jpg"].width == 640
    assert cv2.imread(str(tmp_path / "r" / "c.jpg")).shape == (480, 640, 3)
