"""``gsrwt rectify``: exact frontal views, and safe, resumable batches on bad input."""

from __future__ import annotations

import hashlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.helpers.camera import expected_rectified, render_view
from tests.helpers.cli import GSRWT, run_gsrwt
from tests.helpers.images import psnr, smooth_texture
from tests.helpers.tables import by_image_name, read_table

TEXTURE = smooth_texture(1400, 1800, seed=1)
DISTANCE = 10.0

# pan, tilt, focal, width, height, cx, cy: both signs, several focal lengths and principal points
VIEWS = [
    (15, 30, 280, 320, 240, 159.5, 119.5),
    (-20, 25, 500, 640, 480, 300.0, 260.0),
    (30, -15, 800, 640, 480, 319.5, 239.5),
    (-35, -20, 400, 480, 360, 250.0, 170.0),
    (40, 35, 600, 640, 480, 330.0, 220.0),
    (0, 30, 280, 320, 240, 159.5, 119.5),
    (25, 0, 1000, 800, 600, 420.0, 280.0),
]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def snapshot(directory: Path) -> dict[str, str]:
    """Every file under ``directory`` and its hash: to prove inputs are unchanged."""
    return {str(p.relative_to(directory)): digest(p) for p in sorted(directory.rglob("*"))
            if p.is_file()}


def write_image(path: Path, image: np.ndarray) -> Path:
    ok, data = cv2.imencode(path.suffix, image)
    assert ok
    path.write_bytes(data.tobytes())
    return path


def read_image(path: Path) -> np.ndarray:
    return cv2.imdecode(np.fromfile(str(path), np.uint8), cv2.IMREAD_UNCHANGED)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """Views of the texture rendered by the independent pinhole model, and their sidecar."""
    folder = tmp_path_factory.mktemp("views")
    lines = ["image,pan,tilt,focal,cx,cy"]
    truth = {}
    for index, (pan, tilt, focal, width, height, cx, cy) in enumerate(VIEWS):
        image, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
        name = f"view{index}_{pan}_{tilt}.{'jpg' if index == 0 else 'png'}"
        write_image(folder / name, image)
        lines.append(f"{name},{pan},{tilt},{focal},{cx},{cy}")
        truth[name] = (pan, tilt, focal, width, height, cx, cy, centre)
    (folder / "views.csv").write_text("\n".join(lines) + "\n")
    return folder, truth


@pytest.mark.slow
def test_rectified_views_match_the_frontal_pinhole_view(rendered, tmp_path):
    folder, truth = rendered
    before = snapshot(folder)
    result = run_gsrwt("rectify", str(folder), "--sidecar", str(folder / "views.csv"), "-o",
                       str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    assert "7 ok, 0 skipped, 0 failed" in result.stderr
    table = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    for name, (pan, tilt, focal, width, height, cx, cy, centre) in truth.items():
        output = read_image(tmp_path / "out" / name)
        assert output.shape == (height, width, 3)
        expected, seen = expected_rectified(TEXTURE, pan, tilt, focal, width, height, cx, cy,
                                            DISTANCE, centre)
        assert seen.mean() > 0.9
        assert psnr(output, expected, seen) >= 30, name
        camera_view = read_image(folder / name)
        if (pan, tilt) != (0, 0):  # the unrectified view is far from the frontal one
            assert psnr(camera_view, expected, seen) < 20
        row = table[name]
        assert row["status"] == "ok" and row["error"] == ""
        assert (int(row["out_width"]), int(row["out_height"])) == (width, height)
        homography = np.array([float(v) for v in row["homography"].split()]).reshape(3, 3)
        mapped = homography @ np.array([cx, cy, 1.0])
        np.testing.assert_allclose(mapped[:2] / mapped[2], [cx, cy], atol=1e-6)
    assert snapshot(folder) == before


@pytest.mark.parametrize(
    "image",
    [
        smooth_texture(120, 160, 3),
        smooth_texture(120, 160, 4, channels=1),
        (smooth_texture(120, 160, 5).astype(np.uint16) * 257),
        np.dstack([smooth_texture(120, 160, 6), smooth_texture(120, 160, 7, channels=1)]),
    ],
    ids=["colour", "grey", "16-bit", "rgba"],
)
def test_frontal_view_returns_input_unchanged(image, tmp_path):
    (tmp_path / "in").mkdir()
    write_image(tmp_path / "in" / "x.png", image)
    result = run_gsrwt("rectify", str(tmp_path / "in"), "--pan", "0", "--tilt", "0", "--focal",
                       "300", "-o", str(tmp_path / "out"), "-j", "1")
    assert result.returncode == 0, result.stderr
    np.testing.assert_array_equal(read_image(tmp_path / "out" / "x.png"), image)


@pytest.fixture
def messy(tmp_path):
    """A directory with one good image and every kind of bad one."""
    folder = tmp_path / "in"
    folder.mkdir()
    good, _, _ = render_view(TEXTURE, 15, 30, 280, 320, 240, 159.5, 119.5, DISTANCE)
    write_image(folder / "good.jpg", good)
    (folder / "corrupt.jpg").write_bytes(b"\xff\xd8\xff\xe0" + b"garbage" * 50 + b"\xff\xd9")
    png = cv2.imencode(".png", good)[1].tobytes()
    (folder / "truncated.png").write_bytes(png[: len(png) // 2])
    (folder / "empty.jpg").write_bytes(b"")
    write_image(folder / "noparams.png", good)
    write_image(folder / "tilt95.png", good)
    write_image(folder / "focalneg.png", good)
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal\n"
        "good.jpg,15,30,280\ncorrupt.jpg,15,30,280\ntruncated.png,15,30,280\n"
        "empty.jpg,15,30,280\ntilt95.png,15,95,280\nfocalneg.png,15,30,-3\n"
    )
    return folder


EXPECTED_ERRORS = {
    "corrupt.jpg": "not an image gsrwt can decode",
    "truncated.png": "truncated PNG",
    "empty.jpg": "empty file",
    "noparams.png": "no parameters: not in",
    "tilt95.png": "line 6, field 'tilt': tilt must be strictly between -90 and 90",
    "focalneg.png": "line 7, field 'focal': focal must be positive, got -3",
}


@pytest.mark.parametrize("jobs", [("-j", "1"), ()], ids=["one-worker", "default-workers"])
def test_bad_images_are_reported_and_the_batch_goes_on(messy, tmp_path, jobs):
    before = snapshot(messy)
    result = run_gsrwt("rectify", str(messy), "--sidecar", str(tmp_path / "views.csv"), "-o",
                       str(tmp_path / "out"), *jobs)
    code, stderr = result.returncode, result.stderr
    assert code == 1
    assert "Traceback" not in stderr
    for name, message in EXPECTED_ERRORS.items():
        (line,) = [line for line in stderr.splitlines() if Path(line.split(": ")[1]).name == name]
        assert line.startswith("Error: ") and message in line, line
    assert "1 ok, 0 skipped, 6 failed" in stderr
    table = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    assert table["good.jpg"]["status"] == "ok"
    for name, message in EXPECTED_ERRORS.items():
        assert table[name]["status"] == "error" and message in table[name]["error"]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["good.jpg", "gsrwt.csv"]
    assert snapshot(messy) == before


@pytest.mark.slow
def test_vanishing_line_across_the_image_both_bbox_modes(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    pan, tilt, focal, width, height, cx, cy = 80, 0, 280, 320, 240, 159.5, 119.5
    image, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
    image[:] = np.maximum(image, 20)  # so that the fill value 7 means "no source"
    write_image(folder / "p80.png", image)
    before = snapshot(folder)
    common = ["--pan", "80", "--tilt", "0", "--focal", "280", "--fill", "7", "-j", "1"]
    frontal = run_gsrwt("rectify", str(folder), *common, "-o", str(tmp_path / "frontal"))
    full = run_gsrwt("rectify", str(folder), *common, "--bbox", "full", "--scale", "1", "-o",
                     str(tmp_path / "full"))
    assert frontal.returncode == 0 and full.returncode == 0, frontal.stderr + full.stderr
    for result, name in ((frontal, "frontal"), (full, "full")):
        assert result.stderr == (f"gsrwt: 1 ok, 0 skipped, 0 failed; table: "
                                 f"{tmp_path / name / 'gsrwt.csv'}\n")
    frontal_row = by_image_name(read_table(tmp_path / "frontal" / "gsrwt.csv"))["p80.png"]
    full_row = by_image_name(read_table(tmp_path / "full" / "gsrwt.csv"))["p80.png"]
    assert frontal_row["status"] == full_row["status"] == "ok"
    assert frontal_row["horizon_in_image"] == "true"
    assert (int(frontal_row["out_width"]), int(frontal_row["out_height"])) == (width, height)
    full_size = int(full_row["out_width"]) * int(full_row["out_height"])
    assert width * height < full_size < 50e6
    # Nothing from beyond the horizon is painted in: every output pixel either has a source on
    # the visible side of the vanishing line or is the fill value.
    for folder_name, row in (("frontal", frontal_row), ("full", full_row)):
        output = read_image(tmp_path / folder_name / "p80.png")
        homography = np.array([float(v) for v in row["homography"].split()]).reshape(3, 3)
        rows, cols = np.mgrid[: output.shape[0], : output.shape[1]]
        source = np.linalg.inv(homography) @ np.stack([cols.ravel(), rows.ravel(),
                                                       np.ones(cols.size)])
        behind = (source[2] <= 0).reshape(output.shape[:2])
        assert (output[behind] == 7).all()
        assert (output[~behind] != 7).any(axis=-1).mean() > 0.2
    # The frontal box is the centre of the full one, pixel for pixel.
    full_output = read_image(tmp_path / "full" / "p80.png")
    frontal_output = read_image(tmp_path / "frontal" / "p80.png")
    h_full = np.array([float(v) for v in full_row["homography"].split()]).reshape(3, 3)
    offset = h_full @ np.array([cx, cy, 1.0])
    col0, row0 = np.round(offset[:2] / offset[2] - [cx, cy]).astype(int)
    crop = full_output[row0:row0 + height, col0:col0 + width].astype(int)
    inside = frontal_output != 7
    assert np.abs(crop - frontal_output.astype(int))[inside].mean() < 1
    assert snapshot(folder) == before


def test_a_full_frame_is_at_most_twice_the_inputs_pixels_unless_the_scale_is_asked(tmp_path):
    """At pan 60 the whole visible wall is over four times the photo's pixels at frontal
    resolution; without --scale its scale is lowered until it has at most twice as many,
    the shape kept, and the pixels are those of the frame at scale 1, made smaller."""
    folder = tmp_path / "in"
    folder.mkdir()
    width, height = 320, 240
    image, _, _ = render_view(TEXTURE, 60, 15, 280, width, height, 159.5, 119.5, DISTANCE)
    write_image(folder / "p60.png", image)
    common = ["--pan", "60", "--tilt", "15", "--focal", "280", "--bbox", "full", "-j", "1"]
    assert run_gsrwt("rectify", str(folder), *common, "--scale", "1",
                     "-o", str(tmp_path / "asked")).returncode == 0
    assert run_gsrwt("rectify", str(folder), *common,
                     "-o", str(tmp_path / "capped")).returncode == 0
    asked = by_image_name(read_table(tmp_path / "asked" / "gsrwt.csv"))["p60.png"]
    capped = by_image_name(read_table(tmp_path / "capped" / "gsrwt.csv"))["p60.png"]
    asked_size = int(asked["out_width"]), int(asked["out_height"])
    capped_size = int(capped["out_width"]), int(capped["out_height"])
    assert asked_size[0] * asked_size[1] > 4 * width * height
    assert 1.9 * width * height < capped_size[0] * capped_size[1] <= 2 * width * height
    assert abs(capped_size[0] / capped_size[1] - asked_size[0] / asked_size[1]) < 0.02
    scale = float(capped["scale"])
    assert float(asked["scale"]) == 1 and abs(scale - capped_size[0] / asked_size[0]) < 0.01
    assert "max_area=2" in capped["made_with"]
    smaller = cv2.resize(read_image(tmp_path / "asked" / "p60.png"), capped_size,
                         interpolation=cv2.INTER_AREA)
    output = read_image(tmp_path / "capped" / "p60.png")
    inside = cv2.erode((smaller.max(axis=2) > 0).astype(np.uint8), np.ones((5, 5))) > 0
    assert psnr(output, smaller, inside) > 30


def test_depths_channels_and_unusual_names(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    pan, tilt, focal, width, height, cx, cy = VIEWS[0]
    colour, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
    grey = cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY)
    images = {
        "sixteen bit.png": colour.astype(np.uint16) * 257,
        "grey ü.png": grey,
        "门 rgba.png": np.dstack([colour, np.full((height, width), 200, np.uint8)]),
        "plain.tif": colour,
        "plain.webp": colour,
        "plain.bmp": colour,
    }
    for name, image in images.items():
        write_image(folder / name, image)
    before = snapshot(folder)
    result = run_gsrwt("rectify", str(folder), "--pan", "15", "--tilt", "30", "--focal", "280",
                       "-o", str(tmp_path / "out"), "-j", "1")
    assert result.returncode == 0, result.stderr
    assert "6 ok, 0 skipped, 0 failed" in result.stderr
    table = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    assert sorted(table) == sorted(images) and {r["status"] for r in table.values()} == {"ok"}
    expected, seen = expected_rectified(TEXTURE, pan, tilt, focal, width, height, cx, cy,
                                        DISTANCE, centre)
    for name, image in images.items():
        output = read_image(tmp_path / "out" / name)
        assert output.dtype == image.dtype and output.shape == image.shape, name
        if output.dtype == np.uint16:
            output = (output // 257).astype(np.uint8)
        if output.ndim == 2:
            reference = cv2.cvtColor(expected, cv2.COLOR_BGR2GRAY)
        else:
            reference = expected
            if output.shape[2] == 4:
                assert (output[..., 3][seen] == 200).all()
                output = output[..., :3]
        assert psnr(output, reference, seen) >= 30, name
    assert snapshot(folder) == before


def test_rerun_skips_and_overwrite_replaces(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    image, _, _ = render_view(TEXTURE, 15, 30, 280, 320, 240, 159.5, 119.5, DISTANCE)
    write_image(folder / "a.png", image)
    write_image(folder / "b.png", image[::-1].copy())
    args = [str(folder), "--pan", "15", "--tilt", "30", "--focal", "280", "-o",
            str(tmp_path / "out"), "-j", "1"]
    before = snapshot(folder)
    assert run_gsrwt("rectify", *args).returncode == 0
    output = tmp_path / "out" / "a.png"
    first = digest(output)
    output.write_bytes(b"stale")  # an earlier, different result
    (tmp_path / "out" / "b.png").unlink()  # as if interrupted before b
    again = run_gsrwt("rectify", *args)
    assert again.returncode == 1  # a file that is not its record's is never called done
    assert "1 ok, 0 skipped, 1 failed" in again.stderr
    table = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    assert table["a.png"]["status"] == "error" and table["b.png"]["status"] == "ok"
    assert "not made with these options" in table["a.png"]["error"]
    assert output.read_bytes() == b"stale"
    resumed = run_gsrwt("rectify", *args)  # b's record holds: skipped
    assert resumed.returncode == 1 and "0 ok, 1 skipped, 1 failed" in resumed.stderr
    forced = run_gsrwt("rectify", *args, "--overwrite")
    assert forced.returncode == 0 and "2 ok, 0 skipped" in forced.stderr
    table = by_image_name(read_table(tmp_path / "out" / "gsrwt.csv"))
    assert table["a.png"]["status"] == "ok" and table["b.png"]["status"] == "ok"
    assert digest(output) == first
    assert not list((tmp_path / "out").glob(".*"))  # no temporary files left behind
    assert snapshot(folder) == before


@pytest.mark.parametrize("recursive", [False, True])
def test_output_directory_equal_to_input_is_refused(tmp_path, recursive):
    image = smooth_texture(60, 80, 2)
    write_image(tmp_path / "a.png", image)
    before = snapshot(tmp_path)
    args = ["rectify", str(tmp_path), "-o", str(tmp_path), "--pan", "10", "--tilt", "10",
            "--focal", "100"] + (["-r"] if recursive else [])
    result = run_gsrwt(*args)
    assert result.returncode == 2
    assert len(result.stderr.splitlines()) == 1
    assert "would overwrite the input" in result.stderr or "inside the input" in result.stderr
    assert snapshot(tmp_path) == before


def test_output_inside_input_tree_is_refused_when_recursive(tmp_path):
    write_image(tmp_path / "a.png", smooth_texture(60, 80, 2))
    result = run_gsrwt("rectify", str(tmp_path), "-r", "-o", str(tmp_path / "out"), "--pan", "1",
                       "--tilt", "1", "--focal", "100")
    assert result.returncode == 2 and "inside the input directory" in result.stderr
    assert not (tmp_path / "out").exists()


def test_paths_from_stdin_keep_their_tree(tmp_path):
    for sub in ("a", "a/b"):
        (tmp_path / sub).mkdir(parents=True, exist_ok=True)
        write_image(tmp_path / sub / "x.jpg", smooth_texture(60, 80, 3))
    listing = "./a/x.jpg\n./a/b/x.jpg\n\n./a/missing.jpg\n"
    before = snapshot(tmp_path / "a")
    result = run_gsrwt("rectify", "-", "-o", "out", "--pan", "5", "--tilt", "5", "--focal", "100",
                       stdin=listing, cwd=tmp_path)
    assert result.returncode == 1
    assert "Error: a/missing.jpg: no such file" in result.stderr
    assert (tmp_path / "out/a/x.jpg").is_file() and (tmp_path / "out/a/b/x.jpg").is_file()
    rows = read_table(tmp_path / "out/gsrwt.csv")
    assert [r["status"] for r in rows] == ["ok", "ok", "error"]
    assert rows[2]["error"] == "no such file"
    assert snapshot(tmp_path / "a") == before


def test_recursive_mirrors_the_tree_and_jobs_agree(tmp_path):
    for sub in ("x", "x/y"):
        (tmp_path / "in" / sub).mkdir(parents=True, exist_ok=True)
        write_image(tmp_path / "in" / sub / "p.png", smooth_texture(90, 120, 4))
    args = [str(tmp_path / "in"), "-r", "--pan", "20", "--tilt", "-10", "--focal", "150"]
    one = run_gsrwt("rectify", *args, "-o", str(tmp_path / "one"), "-j", "1")
    two = run_gsrwt("rectify", *args, "-o", str(tmp_path / "two"), "-j", "2")
    assert one.returncode == 0 and two.returncode == 0, one.stderr + two.stderr
    for name in ("x/p.png", "x/y/p.png"):
        assert digest(tmp_path / "one" / name) == digest(tmp_path / "two" / name)


def test_alpha_ext_dry_run_and_table_formats(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    image, _, _ = render_view(TEXTURE, 30, 30, 280, 320, 240, 159.5, 119.5, DISTANCE)
    write_image(folder / "v.jpg", image)
    view = ["--pan", "30", "--tilt", "30", "--focal", "280", "-j", "1"]
    dry = run_gsrwt("rectify", str(folder), *view, "-o", str(tmp_path / "dry"), "--dry-run",
                    "--table", str(tmp_path / "dry.json"))
    assert dry.returncode == 0, dry.stderr
    (row,) = read_table(tmp_path / "dry.json")
    assert row["status"] == "planned" and row["out_width"] == 320
    assert not (tmp_path / "dry").exists()
    result = run_gsrwt("rectify", str(folder), *view, "--alpha", "--ext", "png", "--bbox", "full",
                       "-o", str(tmp_path / "out"), "--table", "-")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout)
    output = read_image(tmp_path / "out" / "v.png")
    assert output.shape[2] == 4
    homography = np.array([float(v) for v in row["homography"].split()]).reshape(3, 3)
    rows, cols = np.mgrid[: output.shape[0], : output.shape[1]]
    source = np.linalg.inv(homography) @ np.stack([cols.ravel(), rows.ravel(), np.ones(cols.size)])
    with np.errstate(divide="ignore", invalid="ignore"):
        src_col, src_row = source[0] / source[2], source[1] / source[2]

    def within(margin: float) -> np.ndarray:
        mask = (source[2] > 0) & (src_col >= margin) & (src_col <= 319 - margin)
        mask &= (src_row >= margin) & (src_row <= 239 - margin)
        return mask.reshape(output.shape[:2]).astype(np.uint8)

    inside, eroded = within(-0.5), within(0.0)
    # Bilinear blending with the transparent border spans an input pixel, which the far side
    # magnifies up to --max-stretch times.
    grown = cv2.dilate(inside, np.ones((15, 15), np.uint8))
    assert (output[..., 3][eroded == 1] == 255).all()
    assert (output[..., 3][grown == 0] == 0).all()
    assert (output[..., 3] == 0).any()
    refused = run_gsrwt("rectify", str(folder), *view, "--alpha", "--ext", "jpg", "-o",
                        str(tmp_path / "x"))
    assert refused.returncode == 2 and "--ext" in refused.stderr and "alpha" in refused.stderr


def test_explicit_box_scale_metric_output_and_pixel_limit(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    image, _, _ = render_view(TEXTURE, 15, 30, 280, 320, 240, 159.5, 119.5, DISTANCE)
    write_image(folder / "v.png", image)
    (folder / "v.yaml").write_text("pan: 15\ntilt: 30\nfocal: 280\ndistance: 2.0\n")
    base = run_gsrwt("rectify", str(folder), "-o", str(tmp_path / "base"), "-j", "1")
    assert base.returncode == 0, base.stderr
    box = run_gsrwt("rectify", str(folder), "-o", str(tmp_path / "box"), "--bbox", "100,50,200,150",
                    "-j", "1")
    assert box.returncode == 0
    crop = read_image(tmp_path / "base" / "v.png")[50:150, 100:200].astype(int)
    # Equal up to OpenCV's 1/32-pixel quantization of sample positions.
    assert np.abs(read_image(tmp_path / "box" / "v.png") - crop).max() <= 1
    # 70 px per unit at Zc = 2, f = 280: scale 0.5, half the size.
    metric = run_gsrwt("rectify", str(folder), "-o", str(tmp_path / "metric"), "--px-per-unit",
                       "70", "-j", "1")
    assert metric.returncode == 0
    assert read_image(tmp_path / "metric" / "v.png").shape[:2] == (120, 160)
    big = run_gsrwt("rectify", str(folder), "-o", str(tmp_path / "big"), "--scale", "20",
                    "--max-pixels", "1M")
    assert big.returncode == 1
    assert "6400x4800 = 30.7 megapixels, above --max-pixels 1 megapixels" in big.stderr
    assert not (tmp_path / "big" / "v.png").exists()


def test_gsrwt_parameters_in_a_row_give_the_same_output(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    image, _, _ = render_view(TEXTURE, 15, 30, 280, 320, 240, 159.5, 119.5, DISTANCE)
    write_image(folder / "v.png", image)
    (tmp_path / "a.csv").write_text("image,pan,tilt,focal\nv.png,15,30,280\n")
    (tmp_path / "b.csv").write_text(
        "image,delta,a,gamma,focal\nv.png,28.186785432,427.462304659,-24.146,280\n"
    )
    for name in ("a", "b"):
        result = run_gsrwt("rectify", str(folder), "--sidecar", str(tmp_path / f"{name}.csv"), "-o",
                           str(tmp_path / name), "-j", "1")
        assert result.returncode == 0, result.stderr
    difference = read_image(tmp_path / "a" / "v.png").astype(int) - read_image(
        tmp_path / "b" / "v.png").astype(int)
    assert np.abs(difference).max() <= 1


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["IN", "-o", "OUT", "--sidecar", "missing.csv"], "missing.csv: no such file"),
        (["nowhere", "-o", "OUT", "--pan", "1", "--tilt", "1", "--focal", "9"],
         "nowhere: no such file or directory"),
        (["IN", "-o", "OUT", "--bogus"], "No such option '--bogus'"),
        (["IN", "-o", "OUT", "--bbox", "1,2,3"], "expected frontal, full, crop or X0,Y0,X1,Y1"),
        (["IN", "-o", "OUT", "--scale", "-2"], "must be a positive number"),
        (["IN", "-o", "OUT", "--ext", "gif"], "cannot write '.gif' files"),
        (["IN", "-o", "OUT", "--table", "t.xlsx"], "must end in .csv, .tsv, .json or .jsonl"),
        (["IN"], "Missing option '-o'"),
    ],
)
def test_usage_errors_exit_2_before_writing(tmp_path, args, message):
    (tmp_path / "IN").mkdir()
    write_image(tmp_path / "IN" / "a.png", smooth_texture(30, 40, 1))
    result = run_gsrwt("rectify", *args, cwd=tmp_path)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "OUT").exists()


def run_on_terminal(args: list[str]) -> str:
    """Run the installed gsrwt with a pseudo-terminal as stdin, stdout and stderr."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 100, 0, 0))
    process = subprocess.Popen([str(GSRWT), *args], stdin=slave, stdout=slave, stderr=slave)
    os.close(slave)
    output = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the terminal closed with the process
            break
        if not chunk:
            break
        output += chunk
    assert process.wait(timeout=120) == 0
    os.close(master)
    return output.decode(errors="replace")


@pytest.mark.slow
def test_progress_bar_only_on_a_terminal_and_not_with_quiet(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for index in range(3):
        write_image(folder / f"{index}.png", smooth_texture(60, 80, index))
    common = [str(folder), "--pan", "10", "--tilt", "10", "--focal", "100", "--overwrite"]
    shown = run_on_terminal(["rectify", *common, "-o", str(tmp_path / "a")])
    assert "3/3 [" in shown and "img/s]" in shown
    assert "gsrwt: 3 ok, 0 skipped, 0 failed" in shown
    quiet = run_on_terminal(["rectify", *common, "-o", str(tmp_path / "b"), "--quiet"])
    assert "3/3" not in quiet and "gsrwt:" not in quiet
    piped = run_gsrwt("rectify", *common, "-o", str(tmp_path / "c"))
    table = tmp_path / "c" / "gsrwt.csv"
    assert piped.stderr == f"gsrwt: 3 ok, 0 skipped, 0 failed; table: {table}\n"


def test_rows_matching_only_by_an_ambiguous_file_name_are_an_error(tmp_path):
    for sub in ("a", "b"):
        (tmp_path / "in" / sub).mkdir(parents=True)
        write_image(tmp_path / "in" / sub / "x.png", smooth_texture(60, 80, 1))
    (tmp_path / "v.csv").write_text("image,pan,tilt,focal\nq/x.png,1,2,100\nr/x.png,3,4,100\n")
    result = run_gsrwt("rectify", str(tmp_path / "in"), "-r", "--sidecar", str(tmp_path / "v.csv"),
                       "-o", str(tmp_path / "out"), "-j", "1")
    assert result.returncode == 1
    assert "x.png matches several rows by file name (q/x.png, r/x.png)" in result.stderr
    (tmp_path / "v.csv").write_text("image,pan,tilt,focal\na/x.png,1,2,100\nb/x.png,3,4,100\n")
    result = run_gsrwt("rectify", str(tmp_path / "in"), "-r", "--sidecar", str(tmp_path / "v.csv"),
                       "-o", str(tmp_path / "out2"), "-j", "1")
    assert result.returncode == 0, result.stderr
    table = read_table(tmp_path / "out2" / "gsrwt.csv")
    assert [float(r["pan_deg"]) for r in table] == [1, 3]




def test_crop_aspect_shapes_the_crop_and_is_recorded(tmp_path):
    """``--bbox crop --crop-aspect original`` keeps the input's shape (to a pixel) and says so
    in ``made_with``; ``--crop-aspect`` without ``--bbox crop``, or a bad shape, is a usage
    error naming the option."""
    photo = Path(__file__).resolve().parents[1] / "data" / "facade" / "building.jpg"
    done = run_gsrwt("rectify", photo, "--pan", "30", "--tilt", "8", "--focal", "1245",
                     "--bbox", "crop", "--crop-aspect", "original", "-o", tmp_path / "out",
                     "-q", "-j", "1")
    assert done.returncode == 0, done.stderr
    [row] = read_table(tmp_path / "out" / "gsrwt.csv")
    width, height = int(row["out_width"]), int(row["out_height"])
    assert abs(width / height - 868 / 600) < 2 / height
    assert "crop_aspect=original" in row["made_with"].split()
    alone = run_gsrwt("rectify", photo, "--pan", "30", "--tilt", "8", "--focal", "1245",
                      "--crop-aspect", "4:3", "-o", tmp_path / "alone")
    assert alone.returncode == 2 and "--crop-aspect goes with --bbox crop" in alone.stderr
    bad = run_gsrwt("rectify", photo, "--pan", "30", "--tilt", "8", "--focal", "1245",
                    "--bbox", "crop", "--crop-aspect", "wide", "-o", tmp_path / "bad")
    assert bad.returncode == 2 and "'--crop-aspect'" in bad.stderr
