"""Parameters resolved in one place: sources, their order, the typed result, its callers."""

from __future__ import annotations

from pathlib import Path, PurePosixPath

import cv2
import numpy as np
import pytest

from gsrwt_cli.batch.canonical_views import CanonicalView, canonical_views
from gsrwt_cli.batch.rectify_jobs import plan_jobs
from gsrwt_cli.inputs.parameters import (
    Found,
    NotFound,
    Origin,
    Problem,
    adjacent_yaml,
    resolve_parameters,
)
from gsrwt_cli.inputs.records import RecordError
from gsrwt_cli.inputs.sidecar import load_sidecar
from gsrwt_cli.inputs.sources import Source
from tests.helpers.cli import run_gsrwt
from tests.helpers.images import smooth_texture
from tests.helpers.tables import read_table

OPTIONS = {"pan": 5.0, "tilt": 6.0, "focal": 280.0}


def image(folder: Path, name: str) -> Path:
    """A small real PNG (canonical_views reads it)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    assert cv2.imwrite(str(path), smooth_texture(40, 60))
    return path


def resolve(path: Path, sidecar=None, fallback=None, relative: str | None = None):
    return resolve_parameters(path, PurePosixPath(relative or path.name), sidecar,
                              fallback if fallback is not None else {})


def test_a_sidecar_row_wins_and_options_fill_what_it_leaves_out(tmp_path):
    photo = image(tmp_path / "in", "a.png")
    (tmp_path / "in" / "a.yaml").write_text("pan: 40\ntilt: 40\nfocal: 100\n")
    sidecar_path = tmp_path / "v.csv"
    sidecar_path.write_text("image,pan,tilt,focal\nb.png,1,1,1\na.png,10,20,\n")
    found = resolve(photo, load_sidecar(sidecar_path), {"focal": 300.0, "distance": 2.0})
    assert found == Found({"focal": 300.0, "distance": 2.0, "pan": "10", "tilt": "20"},
                          f"{sidecar_path} line 3", Origin.SIDECAR)
    view = found.view()
    assert (view.pan, view.tilt, view.focal, view.distance) == (10, 20, 300, 2)


def test_the_yaml_beside_the_image_comes_before_the_options(tmp_path):
    photo = image(tmp_path, "a.png")
    beside = tmp_path / "a.png.yml"
    beside.write_text("Pan: 12\ntilt: 7\nnote: ~\n")
    found = resolve(photo, None, OPTIONS)
    assert found == Found({"pan": 12, "tilt": 7, "focal": 280.0}, str(beside),
                          Origin.ADJACENT_YAML)
    assert resolve(image(tmp_path, "b.png"), None, OPTIONS) == Found(
        OPTIONS, "options", Origin.OPTIONS
    )


def test_adjacent_yaml_names_in_their_order(tmp_path):
    photo = image(tmp_path, "a.png")
    assert adjacent_yaml(photo) is None
    order = ["a.yaml", "a.png.yaml", "a.yml", "a.png.yml"]
    for name in reversed(order):
        (tmp_path / name).write_text("pan: 1\n")
        assert adjacent_yaml(photo) == tmp_path / name
    (tmp_path / "a.yaml").unlink()
    (tmp_path / "a.yaml").mkdir()  # a directory is not a parameter file
    assert adjacent_yaml(photo) == tmp_path / "a.png.yaml"


def test_an_adjacent_sidecar_mapping_is_looked_up_by_file_name(tmp_path):
    photo = image(tmp_path, "view.png")
    beside = tmp_path / "view.yaml"
    beside.write_text("defaults: {focal: 280}\nview.png: {pan: 15, tilt: 30}\n")
    found = resolve(photo)
    assert found == Found({"focal": 280, "pan": 15, "tilt": 30}, f"{beside} record 'view.png'",
                          Origin.ADJACENT_YAML)
    beside.write_text("other.png: {pan: 15, tilt: 30, focal: 280}\n")
    assert resolve(photo) == Problem(f"{beside}: no record for view.png", str(beside))


def test_nothing_found_lists_the_places_looked(tmp_path):
    photo = image(tmp_path, "a.png")
    sidecar_path = tmp_path / "v.csv"
    sidecar_path.write_text("image,pan,tilt,focal\nb.png,1,1,1\n")
    missing = resolve(photo, load_sidecar(sidecar_path), {"pan": 1.0, "focal": 2.0})
    assert isinstance(missing, NotFound)
    assert missing.message == (
        f"no parameters: not in {sidecar_path}, no a.yaml beside it, no --pan/--tilt; add it "
        f"to {sidecar_path}, or estimate the pose with --auto"
    )
    assert resolve(photo).message == (
        "no parameters: no a.yaml beside it, no --pan/--tilt; give them in a --sidecar, or "
        "estimate the pose with --auto")


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("[1, 2]\n", "a.yaml: expected a mapping of field to value"),
        ("", "a.yaml: expected a mapping of field to value"),
        ("pan: 1\ntilt: 2\npan: 3\n", "a.yaml line 3: key 'pan' given twice (first on line 1)"),
        ("pan: 1\nPan: 3\n", "a.yaml: field 'pan' given twice"),
        (f"pan: {'1' * 5000}\n", "a.yaml line 1: an integer of 5000 characters is too long"),
        ("x: &x [a, a, a, a, a, a, a, a, a, a]\n"
         + "".join(f"x{i}: &x{i} [{', '.join([f'*x{i - 1}' if i else '*x'] * 10)}]\n"
                   for i in range(5)) + "pan: *x4\n",
         "aliases expand the document beyond"),
        ("pan: [1\n", "a.yaml line 2"),
    ],
)
def test_an_adjacent_yaml_goes_through_the_bounded_loader(tmp_path, text, words):
    photo = image(tmp_path, "a.png")
    (tmp_path / "a.yaml").write_text(text)
    problem = resolve(photo, None, OPTIONS)
    assert isinstance(problem, Problem)
    assert problem.where == str(tmp_path / "a.yaml")
    assert words in problem.message
    assert "\n" not in problem.message and len(problem.message) < 400


def test_an_unreadable_adjacent_yaml_is_a_problem(tmp_path):
    photo = image(tmp_path, "a.png")
    (tmp_path / "a.yaml").write_bytes(b"pan: \xff\n")
    problem = resolve(photo, None, OPTIONS)
    assert problem == Problem(f"{tmp_path / 'a.yaml'}: not UTF-8 text (invalid start byte)",
                              str(tmp_path / "a.yaml"))


def test_an_ambiguous_sidecar_match_is_a_problem_of_the_sidecar(tmp_path):
    photo = image(tmp_path / "in" / "c", "x.png")
    sidecar_path = tmp_path / "v.csv"
    sidecar_path.write_text("image,pan,tilt,focal\na/x.png,1,2,3\nb/x.png,1,2,3\n")
    problem = resolve(photo, load_sidecar(sidecar_path), OPTIONS, relative="c/x.png")
    assert problem == Problem(
        f"{sidecar_path}: x.png matches several rows by file name (a/x.png, b/x.png); give "
        "the image's relative path",
        str(sidecar_path),
    )


def test_found_values_are_validated_by_view_naming_their_place(tmp_path):
    photo = image(tmp_path, "a.png")
    (tmp_path / "a.yaml").write_text("pan: 1\ntilt: 2\nfocal: 1e300\n")
    found = resolve(photo)
    with pytest.raises(RecordError) as caught:
        found.view()
    assert str(caught.value).startswith(f"{tmp_path / 'a.yaml'}, field 'focal': ")


def test_plan_jobs_takes_each_kind_of_result(tmp_path):
    folder = tmp_path / "in"
    good, bad, none = (image(folder, name) for name in ("good.png", "bad.png", "none.png"))
    (folder / "good.yaml").write_text("pan: 1\ntilt: 2\nfocal: 3\n")
    (folder / "bad.yaml").write_text("pan: 1\ntilt: 2\nfocal: 3\nfocal: 4\n")
    sources = [Source(path, PurePosixPath(path.name)) for path in (good, bad, none)]
    jobs = plan_jobs(sources, tmp_path / "out", None, {}, None)
    assert [(job.values, job.where) for job in jobs] == [
        ({"pan": 1, "tilt": 2, "focal": 3}, str(folder / "good.yaml")),
        (None, str(folder / "bad.yaml")),
        (None, ""),
    ]
    assert jobs[0].error is None
    assert jobs[1].error == (
        f"{folder / 'bad.yaml'} line 4: key 'focal' given twice (first on line 3)"
    )
    assert jobs[2].error == ("no parameters: no none.yaml beside it, no --pan/--tilt; give them "
                             "in a --sidecar, or estimate the pose with --auto")


def test_canonical_views_take_each_kind_of_result(tmp_path):
    folder = tmp_path / "in"
    good, bad, none = (image(folder, name) for name in ("good.png", "bad.png", "none.png"))
    (folder / "good.yaml").write_text("pan: 10\ntilt: 5\nfocal: 300\n")
    (folder / "bad.yaml").write_text("- not a mapping\n")
    results = list(canonical_views([good, bad, none], None, {}))
    assert isinstance(results[0], CanonicalView) and results[0].pixel_map is not None
    assert results[1] == (bad, f"{folder / 'bad.yaml'}: expected a mapping of field to value")
    assert isinstance(results[2], CanonicalView) and results[2].pixel_map is None
    assert np.array_equal(results[2].pixels, cv2.imread(str(none), cv2.IMREAD_UNCHANGED))


def test_rectify_reports_a_hostile_adjacent_yaml_as_that_images_row(tmp_path):
    folder = tmp_path / "in"
    image(folder, "bomb.png")
    image(folder, "good.png")
    lines = ["l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, 9)]
    (folder / "bomb.yaml").write_text("\n".join(lines) + "\npan: *l8\ntilt: 1\nfocal: 300\n")
    out = tmp_path / "out"
    result = run_gsrwt("rectify", str(folder), "--pan", "0", "--tilt", "0", "--focal", "300",
                       "-o", str(out), "-j", "1")
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    (line,) = [line for line in result.stderr.splitlines() if "bomb" in line]
    assert f"{folder / 'bomb.yaml'} line 5: aliases expand the document beyond" in line
    assert len(line) < 500
    table = {row["image"]: row for row in read_table(out / "gsrwt.csv")}
    assert table[str(folder / "bomb.png")]["status"] == "error"
    assert table[str(folder / "good.png")]["status"] == "ok"
    assert sorted(p.name for p in out.iterdir()) == ["good.png", "gsrwt.csv"]
