"""Rectify jobs (``batch/rectify_jobs.py``) in this process: ``plan_jobs`` over a real tree of
images and a sidecar, and one job's work (``process_job``) on a real image rendered by the
camera built from words, its output checked against the frontal view that camera defines.

The batch around them (worker processes, deaths, signals) is tested through the command in
``tests/batch/test_faults.py``; here each function's own contract.
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath

import cv2
import numpy as np
import pytest

from gsrwt_cli.api.rectify import plan_image
from gsrwt_cli.batch.rectify_jobs import (
    NOT_MADE_SO,
    RECTIFY_COLUMNS,
    Job,
    interrupted_row,
    plan_jobs,
    process_job,
)
from gsrwt_cli.batch.settings import Settings
from gsrwt_cli.geometry.camera import View
from gsrwt_cli.geometry.framing import Framing
from gsrwt_cli.imaging.images import Scratch
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.inputs.sources import Source, sources_from_directory
from tests.helpers.camera import expected_rectified, render_view
from tests.helpers.images import psnr, smooth_texture

TEXTURE = smooth_texture(900, 1200, seed=4)
#: pan, tilt, focal, width, height, cx, cy of the rendered photo.
POSE = (25, -15, 400, 320, 240, 159.5, 119.5)
DISTANCE = 10.0


@pytest.fixture(scope="module")
def photo(tmp_path_factory) -> tuple[Path, tuple]:
    """A photo of the textured wall at :data:`POSE` (PNG: lossless), and its reference."""
    folder = tmp_path_factory.mktemp("photo")
    pan, tilt, focal, width, height, cx, cy = POSE
    image, _, centre = render_view(TEXTURE, pan, tilt, focal, width, height, cx, cy, DISTANCE)
    cv2.imwrite(str(folder / "wall.png"), image)
    expected, seen = expected_rectified(TEXTURE, pan, tilt, focal, width, height, cx, cy,
                                        DISTANCE, centre)
    return folder / "wall.png", (expected, seen)


def job_for(photo: Path, out: Path, **changes) -> Job:
    pan, tilt, focal, *_ = POSE
    (job,) = plan_jobs([Source(photo, PurePosixPath(photo.name))], out, None,
                       {"pan": pan, "tilt": tilt, "focal": focal}, None)
    return Job(**{**job.__dict__, **changes})


def test_a_job_writes_the_frontal_view_and_its_row_tells_what_was_done(photo, tmp_path):
    path, (expected, seen) = photo
    job = job_for(path, tmp_path / "out")
    assert job.error is None and job.pose_source == "options" and not job.existed
    row = process_job(job, Settings(root=tmp_path / "out"))
    assert row["status"] == "ok" and row.get("error") is None, row
    assert set(row) <= set(RECTIFY_COLUMNS)
    output = cv2.imread(str(tmp_path / "out" / "wall.png"))
    assert output.shape == (240, 320, 3) and seen.mean() > 0.5
    assert psnr(output, expected, seen) >= 30
    assert (row["pan_deg"], row["tilt_deg"], row["focal_px"]) == (25, -15, 400)
    assert (row["out_width"], row["out_height"], row["scale"]) == (320, 240, 1.0)
    assert row["focal_source"] == "option" and row["pose_source"] == "options"  # TABLES.md
    assert "pan=25" in row["made_with"]
    homography = np.array(row["homography"].split(), dtype=float).reshape(3, 3)
    principal = homography @ [159.5, 119.5, 1.0]
    assert principal[:2] / principal[2] == pytest.approx([159.5, 119.5], abs=1e-9)


def test_the_same_job_again_checks_the_file_and_never_rewrites_it(photo, tmp_path):
    """An output that existed when the run began (no record of it) is made again in memory:
    ``skipped`` if it is what these options make, else an error, the file untouched."""
    path, _ = photo
    out = tmp_path / "out"
    assert process_job(job_for(path, out), Settings(root=out))["status"] == "ok"
    again = process_job(job_for(path, out, existed=True), Settings(root=out))
    assert again["status"] == "skipped"
    (out / "wall.png").write_bytes(b"someone else's file")
    refused = process_job(job_for(path, out, existed=True), Settings(root=out))
    assert refused["status"] == "error" and refused["error"] == NOT_MADE_SO
    assert (out / "wall.png").read_bytes() == b"someone else's file"


def test_a_dry_run_plans_the_row_and_writes_nothing(photo, tmp_path):
    path, _ = photo
    row = process_job(job_for(path, tmp_path / "out"), Settings(root=tmp_path / "out",
                                                                dry_run=True))
    assert row["status"] == "planned" and (row["out_width"], row["out_height"]) == (320, 240)
    assert not (tmp_path / "out").exists()


def test_a_bad_image_is_its_rows_error_never_an_exception(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "broken.png").write_bytes(b"not an image")
    (tmp_path / "in" / "empty.jpg").write_bytes(b"")
    sources = sources_from_directory(tmp_path / "in", recursive=False)
    jobs = plan_jobs(sources, tmp_path / "out", None, {"pan": 10, "tilt": 5, "focal": 300},
                     None)
    rows = [process_job(job, Settings(root=tmp_path / "out")) for job in jobs]
    assert [row["status"] for row in rows] == ["error", "error"]
    assert rows[0]["error"].startswith("not an image gsrwt can decode")
    assert rows[1]["error"] == "empty file"
    assert not (tmp_path / "out").exists()


def test_an_interrupted_job_is_ok_only_if_its_output_was_written_whole(photo, tmp_path):
    path, _ = photo
    out = tmp_path / "out"
    job = job_for(path, out)
    settings = Settings(root=out)
    assert interrupted_row(job, settings)["status"] == "interrupted"
    assert process_job(job, settings)["status"] == "ok"
    row = interrupted_row(job, settings)  # written before the run stopped: done after all
    assert row["status"] == "ok" and row["out_width"] == 320 and row.get("error") is None


def test_plan_jobs_mirrors_the_tree_and_finds_each_images_parameters(tmp_path):
    """One job per image, in order; outputs keep the relative path (with ``--ext``'s
    suffix); the sidecar's row wins over the options; an image no source has is an error
    of its job; an output that exists is marked; two images with one output, and an
    output whose directory is a link out of the output, are errors of their jobs."""
    root = tmp_path / "in"
    for name in ("a.png", "b.jpg", "b.png", "sub/c.png", "escape/d.png"):
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_bytes(b"")
    (root / "views.csv").write_text("image,pan,tilt,focal\nsub/c.png,30,10,500\n")
    out = tmp_path / "out"
    (out / "sub").mkdir(parents=True)
    (out / "sub" / "c.jpg").write_bytes(b"old")
    (tmp_path / "elsewhere").mkdir()
    (out / "escape").symlink_to(tmp_path / "elsewhere")
    sources = sources_from_directory(root, recursive=True)
    with_options = plan_jobs(sources, out, load_sidecar(root / "views.csv"),
                             {"pan": 1, "tilt": 2, "focal": 300}, ".jpg")
    by_name = {str(job.source.relative_to(root)): job for job in with_options}
    assert list(by_name) == ["a.png", "b.jpg", "b.png", "escape/d.png", "sub/c.png"]
    assert by_name["a.png"].output == out / "a.jpg"
    assert by_name["sub/c.png"].values["pan"] in (30, "30")
    assert by_name["sub/c.png"].pose_source == "sidecar" and by_name["sub/c.png"].existed
    assert by_name["a.png"].values["pan"] == 1 and by_name["a.png"].pose_source == "options"
    assert by_name["b.jpg"].error is None
    assert by_name["b.png"].error == f"its output {out / 'b.jpg'} is also the output of " \
                                     f"{root / 'b.jpg'}"
    assert "outside the output" in by_name["escape/d.png"].error
    assert not any(job.existed for name, job in by_name.items() if name != "sub/c.png")
    without = plan_jobs(sources, out, load_sidecar(root / "views.csv"), {}, None)
    errors = {str(job.source.relative_to(root)): job.error for job in without}
    assert errors["sub/c.png"] is None
    assert errors["a.png"].startswith("no parameters: not in ")


@pytest.mark.parametrize(("values", "framing", "antialias", "reduced"), [
    # scale 1, in a corner of the frame where every pixel spans over 2.1 input pixels
    ({"pan": 60, "tilt": 0, "focal": 120}, Framing(bbox=(343, 41, 351, 197)), True, False),
    ({"pan": 25, "tilt": -15, "focal": 400}, Framing(scale=0.2), False, False),
    ({"pan": 25, "tilt": -15, "focal": 400}, Framing(scale=0.2), True, True),
])
def test_previews_decode_reduced_only_below_scale_one_with_antialiasing(
        photo, tmp_path, values, framing, antialias, reduced):
    """A JPEG's output is made from its decode 2-8 times smaller only when it is smaller
    than the input (scale below 1) and antialiased: at scale 1, even where every output pixel
    spans 2 input pixels or more, and without antialiasing, the output file is byte for byte
    the full decode's warp; a preview's is close to it (20 dB: their filters differ)."""
    path = tmp_path / "wall.jpg"
    cv2.imwrite(str(path), cv2.imread(str(photo[0])), [cv2.IMWRITE_JPEG_QUALITY, 95])
    out = tmp_path / "out"
    settings = Settings(root=out, framing=framing, antialias=antialias)
    row = process_job(job_for(path, out, values=values), settings)
    assert row["status"] == "ok", row
    info = plan_image(View(values["pan"], values["tilt"], values["focal"]), 320, 240, framing)
    assert (info.frame.scale < 1) == (framing.scale < 1)
    scratch = Scratch()
    scratch.read(path)
    full = scratch.encode(scratch.warp(info.pixel_map, antialias=antialias), ".jpg")
    made = (out / "wall.jpg").read_bytes()
    assert (made != full) == reduced
    if reduced:
        decoded = [cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
                   for data in (made, full)]
        assert psnr(*decoded, np.ones(decoded[0].shape[:2], bool)) > 20
