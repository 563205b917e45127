"""Hostile calibration files named by ``--camera`` or a sidecar's ``camera`` column (issue 21,
items 4, 11 and 12): sizes OpenCV's parser would crash on, files whose content must not be
echoed, FIFOs and devices that must not hang a batch, and a fuzz test of mutated real files.

Every case is caused for real: files written in ``tmp_path``, a real FIFO, real ``gsrwt``
processes whose exit code is checked (never negative: no signal).
"""

from __future__ import annotations

import csv
import json
import os
import random
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from gsrwt_cli.base.messages import TOKEN_LIMIT
from gsrwt_cli.geometry.camera import Intrinsics
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.inputs.calibration import (
    CalibrationError,
    load_camera,
    write_opencv_xml,
    write_opencv_yaml,
    write_ros_yaml,
)
from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import DATA
from tests.helpers.tables import read_table

#: A camera of the 80x60 test images.
CAMERA = Intrinsics(fx=100.0, fy=100.0, cx=39.5, cy=29.5, width=80, height=60)
_K = "[ 100., 0., 39.5, 0., 100., 29.5, 0., 0., 1. ]"


def _opencv_yaml(distortion: str) -> str:
    return ("%YAML:1.0\n---\nimage_width: 80\nimage_height: 60\n"
            f"camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: {_K}\n"
            f"distortion_coefficients: {distortion}\n")


def _opencv_xml(distortion: str) -> str:
    return ('<?xml version="1.0"?>\n<opencv_storage>\n<image_width>80</image_width>\n'
            '<image_height>60</image_height>\n<camera_matrix type_id="opencv-matrix">\n'
            "  <rows>3</rows>\n  <cols>3</cols>\n  <dt>d</dt>\n"
            "  <data>100. 0. 39.5 0. 100. 29.5 0. 0. 1.</data></camera_matrix>\n"
            f"{distortion}\n</opencv_storage>\n")


def _opencv_json(distortion: dict) -> str:
    return json.dumps({
        "image_width": 80, "image_height": 60,
        "camera_matrix": {"type_id": "opencv-matrix", "rows": 3, "cols": 3, "dt": "d",
                          "data": [100.0, 0.0, 39.5, 0.0, 100.0, 29.5, 0.0, 0.0, 1.0]},
        "distortion_coefficients": distortion,
    }, indent=4)


_FIVE = "[ -0.2, 0.05, 0., 0., 0. ]"
#: Files OpenCV's parser crashed on (SIGSEGV), each with the key at fault.
HOSTILE = {
    "yaml-nd-sizes-1-5": (".yml", _opencv_yaml(
        f"!!opencv-nd-matrix\n   sizes: [ -1, -5 ]\n   dt: d\n   data: {_FIVE}")),
    "yaml-nd-sizes-2-2": (".yml", _opencv_yaml(
        "!!opencv-nd-matrix\n   sizes: [ -2, -2 ]\n   dt: d\n   data: [ 1., 2., 3., 4. ]")),
    "yaml-nd-dt-u": (".yml", _opencv_yaml(
        f"!!opencv-nd-matrix\n   sizes: [ -1, -5 ]\n   dt: u\n   data: {_FIVE}")),
    "yaml-matrix-rows-1-5": (".yml", _opencv_yaml(
        f"!!opencv-matrix\n   rows: -1\n   cols: -5\n   dt: d\n   data: {_FIVE}")),
    "xml-nd-sizes-1-5": (".xml", _opencv_xml(
        '<distortion_coefficients type_id="opencv-nd-matrix">\n  <sizes>-1 -5</sizes>\n'
        "  <dt>d</dt>\n  <data>-0.2 0.05 0. 0. 0.</data></distortion_coefficients>")),
    "xml-matrix-rows-2-2": (".xml", _opencv_xml(
        '<distortion_coefficients type_id="opencv-matrix">\n  <rows>-2</rows>\n'
        "  <cols>-2</cols>\n  <dt>u</dt>\n  <data>1 2 3 4</data></distortion_coefficients>")),
    "json-nd-sizes-1-5": (".json", _opencv_json(
        {"type_id": "opencv-nd-matrix", "sizes": [-1, -5], "dt": "d",
         "data": [-0.2, 0.05, 0.0, 0.0, 0.0]})),
    "json-nd-sizes-2-2-u": (".json", _opencv_json(
        {"type_id": "opencv-nd-matrix", "sizes": [-2, -2], "dt": "u", "data": [1, 2, 3, 4]})),
}


def _one_line_error(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr[-2000:]
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr[-2000:]
    return lines[0]


@pytest.mark.slow
@pytest.mark.parametrize("case", list(HOSTILE), ids=list(HOSTILE))
def test_sizes_that_crashed_opencv_are_a_usage_error_naming_file_and_key(tmp_path, case):
    suffix, text = HOSTILE[case]
    path = tmp_path / f"camera{suffix}"
    path.write_text(text, encoding="utf-8")
    done = run_gsrwt("params", "--pan", "10", "--tilt", "5", "--camera", str(path))
    assert done.returncode == 2, (done.returncode, done.stderr[-2000:])
    line = _one_line_error(done.stderr)
    assert f"{path}: key 'distortion_coefficients" in line, line


# --------------------------------------------------------------------------------------------
# A batch: a bad calibration file costs its image, never the batch


def _image(path: Path) -> Path:
    pixels = (np.random.default_rng(5).random((60, 80, 3)) * 255).astype(np.uint8)
    cv2.imwrite(str(path), pixels)
    return path


def _batch(tmp_path: Path, cameras: list[str], *extra: str) -> tuple[subprocess.CompletedProcess,
                                                                      list[dict[str, str]]]:
    """``gsrwt rectify`` of one image per camera column value, in order; the run and its
    table's rows (none if there is no table)."""
    sidecar = tmp_path / "views.csv"
    names = []
    with open(sidecar, "w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file)
        writer.writerow(["image", "pan", "tilt", "camera"])
        for index, camera in enumerate(cameras):
            names.append(str(_image(tmp_path / f"img{index}.png")))
            writer.writerow([f"img{index}.png", 10, 5, camera])
    done = run_gsrwt("rectify", *names, "--sidecar", str(sidecar), "-o", str(tmp_path / "out"),
                     *extra, timeout=120)  # a guard against a hang, no assertion
    table = tmp_path / "out" / "gsrwt.csv"
    rows = read_table(table) if table.exists() else []
    return done, rows


@pytest.mark.slow
@pytest.mark.parametrize("case", ["yaml-nd-sizes-1-5", "xml-nd-sizes-1-5", "json-nd-sizes-1-5"])
def test_a_hostile_camera_between_good_ones_costs_its_image_only(tmp_path, case):
    write_opencv_yaml(tmp_path / "good.yml", CAMERA)
    suffix, text = HOSTILE[case]
    (tmp_path / f"hostile{suffix}").write_text(text, encoding="utf-8")
    done, rows = _batch(tmp_path, ["good.yml", f"hostile{suffix}", "good.yml"])
    assert done.returncode == 1, (done.returncode, done.stderr[-2000:])
    assert "Traceback" not in done.stderr
    assert [row["status"] for row in rows] == ["ok", "error", "ok"], rows
    error = rows[1]["error"]
    assert f"hostile{suffix}: key 'distortion_coefficients" in error, error
    assert "\n" not in error
    assert (tmp_path / "out" / "img0.png").is_file() and (tmp_path / "out" / "img2.png").is_file()
    assert not (tmp_path / "out" / "img1.png").exists()


# --------------------------------------------------------------------------------------------
# Item 11: the content of a file a sidecar names is never echoed

SECRET = "hunter2-the-password-nobody-may-see"


@pytest.mark.slow
def test_a_camera_column_naming_a_secret_or_passwd_never_echoes_its_content(tmp_path):
    (tmp_path / "secret.txt").write_text(
        f"root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1::/usr/sbin/nologin\n{SECRET}\n")
    (tmp_path / "yaml_secret.txt").write_text(f"camera_matrix: {SECRET}\n")
    (tmp_path / "model_secret.yml").write_text(
        "image_width: 80\nimage_height: 60\n"
        "camera_matrix: {rows: 3, cols: 3, data: [100, 0, 39.5, 0, 100, 29.5, 0, 0, 1]}\n"
        f"distortion_model: {SECRET}\n"
        "distortion_coefficients: {rows: 1, cols: 4, data: [0.1, 0, 0, 0]}\n")
    work = tmp_path / "work"
    work.mkdir()
    cameras = ["../secret.txt", "../yaml_secret.txt", "../model_secret.yml"]
    if Path("/etc/passwd").is_file():
        cameras.append("/etc/passwd")
    done, rows = _batch(work, cameras)
    assert done.returncode == 1, (done.returncode, done.stderr[-2000:])
    assert [row["status"] for row in rows] == ["error"] * len(cameras)
    table = (work / "out" / "gsrwt.csv").read_text(encoding="utf-8")
    for text in (done.stdout, done.stderr, table):
        assert SECRET not in text and "/bin/bash" not in text and "nologin" not in text
    for row in rows[:1] + rows[3:]:  # a whole file's text: nothing of it quoted
        assert "root:" not in row["error"] and "hunter2" not in row["error"], row["error"]
    for row, name in zip(rows, ("secret.txt", "yaml_secret.txt", "model_secret.yml",
                                "/etc/passwd")):
        assert name in row["error"], row["error"]
        for quoted in re.findall(r"'([^']*)'", row["error"].split(name, 1)[1]):
            assert len(quoted) <= TOKEN_LIMIT + 30, row["error"]  # a token, its length told
    assert "key 'camera_matrix'" in rows[1]["error"] and "key 'distortion_model'" in rows[2][
        "error"]
    # gsrwt params names the row and the file the same way
    params = run_gsrwt("params", "--sidecar", str(work / "views.csv"))
    assert params.returncode == 2 and "Traceback" not in params.stderr
    assert SECRET not in params.stderr and "/bin/bash" not in params.stderr


def test_the_message_quotes_a_short_token_of_a_value(tmp_path):
    path = tmp_path / "camera.yaml"
    path.write_text(f"camera_matrix: {SECRET * 10}\n")
    with pytest.raises(CalibrationError) as caught:
        load_camera(path)
    assert caught.value.key == "camera_matrix"
    assert SECRET * 2 not in str(caught.value)
    assert f"'{SECRET[:TOKEN_LIMIT]}... ({len(SECRET) * 10} characters)'" in str(caught.value)
    path.write_text("just words and more words that go on for a long while " * 20)
    with pytest.raises(CalibrationError) as caught:
        load_camera(path)
    assert "words" not in str(caught.value), str(caught.value)
    assert re.search(r"got a string of \d+ characters$", str(caught.value)), str(caught.value)


# --------------------------------------------------------------------------------------------
# Item 12: FIFOs and devices named by a sidecar (or --camera) are refused, never read


@pytest.mark.slow
def test_a_fifo_or_a_device_in_the_camera_column_is_that_images_error(tmp_path):
    write_opencv_yaml(tmp_path / "good.yml", CAMERA)
    os.mkfifo(tmp_path / "camera.fifo")  # no writer: opening it for reading would block
    done, rows = _batch(tmp_path, ["good.yml", "camera.fifo", "/dev/zero", "good.yml"])
    assert done.returncode == 1, (done.returncode, done.stderr[-2000:])
    assert "Traceback" not in done.stderr
    assert [row["status"] for row in rows] == ["ok", "error", "error", "ok"], rows
    assert "camera.fifo: is a FIFO, not a regular file" in rows[1]["error"], rows[1]["error"]
    assert "/dev/zero: is a character device, not a regular file" in rows[2]["error"]


@pytest.mark.slow
def test_a_fifo_given_as_camera_is_a_usage_error(tmp_path):
    fifo = tmp_path / "camera.fifo"
    os.mkfifo(fifo)
    done = run_gsrwt("params", "--pan", "10", "--tilt", "5", "--camera", str(fifo), timeout=120)
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert _one_line_error(done.stderr).endswith(f"{fifo}: is a FIFO, not a regular file")


# --------------------------------------------------------------------------------------------
# Fuzz: mutated real calibration files, through a subprocess, never a signal

#: Values a mutation puts where a number was: negative, zero, huge, fractional, not finite,
#: not a number, nested.
_HOSTILE_NUMBERS = ["-1", "-5", "-2", "0", "1", "15", "2147483648", "-2147483649",
                    "9223372036854775808", "1e300", "-1e308", "1e400", "1.5", "-0.", ".Inf",
                    ".Nan", "nan", "x", "[]", "[ 1, 2 ]", "{}", "[ [ [ 1 ] ] ]", "\"5\"",
                    "1" * 500]
_DTS = ["u", "c", "w", "s", "i", "f", "d", "h", "2d", "3f", "r", "U", "", "dd", "ud", "q", "1d"]
_SIZE_LISTS = ["[ -1, -5 ]", "[ -2, -2 ]", "[ 0 ]", "[ 1, 2, 3 ]", "[]", "[ [ 5 ] ]",
               "[ 100000, 100000 ]", "[ 5, -1 ]", "[ 2147483647 ]", "-5", "[ 1e300 ]"]


#: A matrix of rows and cols in each form: (before the rows, rows, between, cols).
_MATRICES = {
    "yaml": re.compile(r"!!opencv-matrix(\s*)rows: (\d+)(\s*)cols: (\d+)"),
    "json": re.compile(r'"type_id": "opencv-matrix",(\s*)"rows": (\d+),(\s*)"cols": (\d+)'),
    "xml": re.compile(r'type_id="opencv-matrix">(\s*)<rows>(\d+)</rows>(\s*)<cols>(\d+)</cols>'),
}
#: An nd-matrix's sizes in each form (its one size is group 2).
_ND_SIZES = {
    "yaml": re.compile(r"(sizes: )(\[ (\d+) \])"),
    "json": re.compile(r'("sizes": )(\[ (\d+) \])'),
    "xml": re.compile(r"(<sizes>\s*)((\d+))(?=</sizes>)"),
}


def _form(text: str) -> str:
    start = text.lstrip()[:1]
    return "xml" if start == "<" else "json" if start == "{" else "yaml"


def _sizes(rows: int, cols: int, rng: random.Random) -> list[int | str]:
    """Sizes to give a matrix of ``rows x cols`` values: mostly negative ones whose product is
    still its count (what crashed OpenCV), else any of :data:`_SIZE_LISTS`."""
    count = rows * cols
    choices: list[list[int | str]] = [[-rows, -cols], [-cols, -rows], [-1, -count], [-count, -1],
                                      [-count], [rows, -cols], [0, count]]
    if rng.random() < 0.7:
        return rng.choice(choices)
    return [item.strip() for item in rng.choice(_SIZE_LISTS).strip("[]").split(",")]


def _nd_sizes(text: str, rng: random.Random) -> str:
    """One matrix turned into an nd-matrix, or an nd-matrix's sizes changed, to sizes of
    :func:`_sizes`."""
    form = _form(text)
    matrices = list(_MATRICES[form].finditer(text))
    nds = list(_ND_SIZES[form].finditer(text))
    if not matrices and not nds:
        return text
    pick = rng.randrange(len(matrices) + len(nds))
    if pick < len(matrices):
        match = matrices[pick]
        sizes = _sizes(int(match.group(2)), int(match.group(4)), rng)
        space = match.group(1)
        replacement = {
            "yaml": f"!!opencv-nd-matrix{space}sizes: [ {', '.join(map(str, sizes))} ]",
            "json": f'"type_id": "opencv-nd-matrix",{space}"sizes": '
                    f"[ {', '.join(map(str, sizes))} ]",
            "xml": f'type_id="opencv-nd-matrix">{space}<sizes>{" ".join(map(str, sizes))}'
                   "</sizes>",
        }[form]
        return text[:match.start()] + replacement + text[match.end():]
    match = nds[pick - len(matrices)]
    sizes = _sizes(1, int(match.group(3)), rng)
    value = " ".join(map(str, sizes)) if form == "xml" else f"[ {', '.join(map(str, sizes))} ]"
    return text[:match.start(2)] + value + text[match.end(2):]


def _mutate(text: str, rng: random.Random) -> str:
    """``text`` with one structural mutation: sizes, a ``dt``, a number, a tag, a line, a
    nesting, the data or a truncation."""
    if len(text) < 2:  # truncated to nothing by an earlier mutation
        return text
    kind = rng.randrange(10)
    xml = _form(text) == "xml"
    if kind in (0, 1):  # negative sizes of the right product, and other sizes
        return _nd_sizes(text, rng)
    if kind == 2:  # a size (rows, cols, sizes)
        pattern = (r"(<(?:rows|cols|sizes)>\s*)([^<]*)" if xml
                   else r"(\"?(?:rows|cols)\"?\s*:\s*)(-?[0-9.e+]+)")
        value = rng.choice(_HOSTILE_NUMBERS)
        if xml:
            value = value.strip("[]{}").replace(",", " ")
    elif kind == 3:  # the element type
        pattern = r"(<dt>)([^<]*)" if xml else r"(\"?dt\"?\s*:\s*\"?)([A-Za-z0-9]*)"
        value = rng.choice(_DTS)
    elif kind == 4:  # a number anywhere
        pattern, value = r"(^|[\s\[,>])(-?[0-9][0-9.]*(?:e[+-]?[0-9]+)?)", rng.choice(
            _HOSTILE_NUMBERS)
        if xml:
            value = value.strip("[]{}").replace(",", " ")
    elif kind == 5:  # the matrix tag or type swapped, or removed
        old = rng.choice(["opencv-matrix", "opencv-nd-matrix"])
        return text.replace(old, rng.choice(["opencv-nd-matrix", "opencv-matrix", "str",
                                             "binary", "opencv-x"]), rng.randint(1, 3))
    elif kind == 6:  # a line deleted or doubled
        lines = text.splitlines(keepends=True)
        index = rng.randrange(len(lines))
        if rng.random() < 0.5:
            del lines[index]
        else:
            lines.insert(index, lines[index])
        return "".join(lines)
    elif kind == 7:  # truncated
        return text[:rng.randrange(len(text))]
    elif kind == 8:  # a value nested
        depth = rng.randint(1, 80)
        if xml:
            pattern, value = r"(<data>)([^<]*)", "<_>" * depth + "1" + "</_>" * depth
        else:
            pattern = r"(\"?data\"?\s*:\s*)(\[[^\]]*\])"
            value = "[" * depth + "1" + "]" * depth
    else:  # a matrix's data emptied, cut or grown
        pattern = r"(<data>)([^<]*)" if xml else r"(\"?data\"?\s*:\s*)(\[[^\]]*\])"
        value = rng.choice(["", "1", "1 2 3 4 5 6 7 8 9 10 11 12 13 14 15"]) if xml else (
            rng.choice(["", "[]", "[ 1 ]", "{ a: 1 }", "[ 1, 2, 3, 4, 5, 6, 7, 8, 9, 10 ]"]))
    matches = list(re.finditer(pattern, text, flags=re.MULTILINE))
    if not matches:
        return text[:rng.randrange(len(text))]
    match = rng.choice(matches)
    return text[:match.start(2)] + value + text[match.end(2):]


def _seed_files(folder: Path) -> list[tuple[str, str]]:
    """Real calibration files: the writers' (OpenCV YAML and XML, ROS) of several lenses,
    OpenCV's own FileStorage (YAML, XML, JSON, 1-D arrays as nd-matrices, and an interactive
    calibration's cameraResolution), and the committed ones."""
    seeds: list[tuple[str, str]] = []
    lenses = [None, Lens("plumb_bob", (("k1", -0.2), ("k2", 0.05), ("p1", 0.001))),
              Lens("rational_polynomial", (("k1", 0.1), ("k6", 0.01))),
              Lens("equidistant", (("k1", 0.1), ("k4", -0.01)))]
    for lens in lenses:
        camera = Intrinsics(fx=500.0, fy=490.0, cx=319.5, cy=239.5, width=640, height=480,
                            lens=lens)
        for suffix, writer in ((".yml", write_opencv_yaml), (".xml", write_opencv_xml),
                               (".yaml", write_ros_yaml)):
            path = folder / f"seed{suffix}"
            writer(path, camera)
            seeds.append((suffix, path.read_text(encoding="utf-8")))
            path.unlink()
    for suffix in (".yml", ".xml", ".json"):
        storage = cv2.FileStorage(f"c{suffix}", cv2.FILE_STORAGE_WRITE | cv2.FILE_STORAGE_MEMORY)
        storage.write("cameraResolution", (640, 480))
        storage.write("cameraMatrix", np.array([[500.0, 0, 319.5], [0, 500, 239.5], [0, 0, 1]]))
        storage.write("dist_coeffs", np.array([-0.2, 0.05, 0.0, 0.0, 0.01]))  # 1-D: nd-matrix
        storage.write("per_view_errors", np.zeros((3, 1), np.float32))
        seeds.append((suffix, storage.releaseAndGetString()))
    for name in ("right_camera.yml", "right_camera.xml", "right_camera_ros.yaml",
                 "opencv4_left_intrinsics.yml"):
        seeds.append((Path(name).suffix, (DATA / name).read_text(encoding="utf-8")))
    return seeds


_FUZZ = """
import sys
from gsrwt_cli.inputs.calibration import CalibrationError, load_camera
read = refused = 0
for path in sys.argv[1:]:
    print("loading", path, flush=True)
    try:
        load_camera(path)
        read += 1
    except CalibrationError as error:
        refused += 1
        message = str(error)
        assert "\\n" not in message and len(message) < 600, message
    except BaseException as error:
        print("INTERNAL", path, type(error).__name__, str(error)[:300], flush=True)
print("done", read, refused)
"""

#: Mutated files, and how many mutations each (1 to 3) has.
FUZZ_FILES = 400


@pytest.mark.slow
def test_mutated_calibration_files_never_crash_a_process(tmp_path):
    rng = random.Random(21)
    seeds = _seed_files(tmp_path)
    paths = []
    for index in range(FUZZ_FILES):
        suffix, text = seeds[index % len(seeds)]
        for _ in range(rng.randint(1, 3)):
            text = _mutate(text, rng)
        path = tmp_path / f"m{index:03d}{suffix}"
        path.write_text(text, encoding="utf-8")
        paths.append(path)
    done = subprocess.run([sys.executable, "-c", _FUZZ, *map(str, paths)], capture_output=True,
                          text=True, timeout=300)
    last = done.stdout.strip().splitlines()[-1:]
    assert done.returncode == 0, (done.returncode, last, done.stderr[-2000:])
    assert "INTERNAL" not in done.stdout, [line for line in done.stdout.splitlines()
                                           if "INTERNAL" in line][:5]
    read, refused = map(int, done.stdout.split()[-2:])
    assert read + refused == FUZZ_FILES and read > 20 and refused > 100, (read, refused)
    # The same files named by a sidecar's camera column, through the command
    sidecar = tmp_path / "views.csv"
    with open(sidecar, "w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file)
        writer.writerow(["image", "pan", "tilt", "camera"])
        writer.writerows([f"v{index}.png", 10, 5, path.name] for index, path in enumerate(paths))
    params = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert params.returncode in (0, 2), (params.returncode, params.stderr[-2000:])
    assert "Traceback" not in params.stderr and "internal error" not in params.stderr
    lines = params.stderr.splitlines()
    assert len(lines) >= refused and all(line.startswith(f"Error: {sidecar} line ")
                                         for line in lines), lines[:5]
