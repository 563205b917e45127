"""Start-up: each command imports only what it uses (issue: speed where users feel it).

Timing is the benchmark's business (``benchmarks/bench_startup.py``); these tests check the
cause, in real subprocesses: which heavy libraries a command line imports.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys

import click
import pytest

from gsrwt_cli.cli import BLAS_THREAD_VARIABLES, COMMANDS, main
from tests.helpers.cli import run_gsrwt

HEAVY = ("numpy", "cv2", "yaml", "tqdm", "PIL", "imagesize")


def imported_top_level_modules(*arguments: str) -> set[str]:
    """The top-level modules ``gsrwt ARGUMENTS`` imports (from ``python -X importtime``)."""
    result = subprocess.run([sys.executable, "-X", "importtime", "-m", "gsrwt_cli", *arguments],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    names = set()
    for line in result.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            names.add(line.rsplit("|", 1)[1].strip().split(".")[0])
    assert "click" in names  # the parse worked
    return names


@pytest.mark.parametrize("arguments", [("--version",), ("--help",)])
def test_version_and_help_import_no_heavy_library(arguments):
    assert imported_top_level_modules(*arguments) & set(HEAVY) == set()


def test_one_plain_params_view_imports_no_heavy_library():
    imported = imported_top_level_modules("params", "--pan", "10", "--tilt", "20",
                                          "--focal", "500", "--width", "640", "--height", "480")
    assert imported & set(HEAVY) == set()


def test_a_params_view_beyond_a_plain_pinhole_takes_the_views_way():
    imported = imported_top_level_modules("params", "--pan", "10", "--tilt", "20",
                                          "--focal", "500", "--roll", "3")
    assert imported & set(HEAVY) == {"numpy"}


def test_a_command_still_gets_what_it_needs():
    assert {"numpy", "cv2"} <= imported_top_level_modules("rectify", "--help")


def test_a_video_run_imports_only_what_its_frames_need(tmp_path):
    """``rectify VIDEO --poses FILE`` off a terminal (the benchmark's run,
    ``benchmarks/bench_video.py``): PyAV, OpenCV and numpy, and none of the libraries of
    other inputs and outputs: no progress bar (tqdm, imported only to draw one on a
    terminal), no image headers (imagesize), no YAML (a CSV pose log and no calibration
    file), no EXIF (PIL), no bags (rosbags), no cluster (dask), no stores (fsspec)."""
    av = pytest.importorskip("av")
    import numpy as np

    clip, log = tmp_path / "clip.mp4", tmp_path / "poses.csv"
    with av.open(str(clip), mode="w") as container:
        stream = container.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        for index in range(3):
            frame = av.VideoFrame.from_ndarray(np.full((48, 64, 3), 40 * index, np.uint8),
                                               format="bgr24")
            frame.pts = index
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    log.write_text("time,pan,tilt\n0,0,10\n1,5,12\n")
    imported = imported_top_level_modules("rectify", str(clip), "--poses", str(log), "--focal",
                                          "60", "--codec", "h264", "-o", str(tmp_path / "out"),
                                          "-q")
    assert (tmp_path / "out" / "clip.mp4").is_file()
    assert {"av", "cv2", "numpy"} <= imported
    assert imported & {"tqdm", "imagesize", "yaml", "PIL", "rosbags", "dask", "distributed",
                       "fsspec", "scipy"} == set()


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_group_help_of_each_command_is_its_docstrings(name):
    """``gsrwt --help`` lists the commands from :data:`COMMANDS` without loading them: each
    line is the one click would make from the command's own docstring."""
    command = main.get_command(None, name)
    module, first_paragraph = COMMANDS[name]
    assert command.callback.__module__ == f"gsrwt_cli.cli.{module}"
    for limit in (30, 45, 80, 300):
        assert (click.Command(name, help=first_paragraph).get_short_help_str(limit)
                == command.get_short_help_str(limit))


def test_the_group_help_lists_every_command():
    result = run_gsrwt("--help")
    assert result.returncode == 0, result.stderr
    listed = [line.split()[0] for line in result.stdout.split("Commands:", 1)[1].splitlines()
              if line.strip()]
    assert listed == sorted(COMMANDS)


BLAS_THREADS = """
import os, sys
if sys.argv[1] == "command":
    sys.argv = ["gsrwt", "--version"]
    from gsrwt_cli.cli import run
    try:
        run()
    except SystemExit:
        pass
import numpy
print(len(os.listdir("/proc/self/task")))
"""


@pytest.mark.skipif(not os.path.isdir("/proc/self/task") or (os.cpu_count() or 1) < 2,
                    reason="counts a process's threads in /proc; needs 2 or more cores")
def test_the_command_gives_numpy_one_blas_thread_unless_the_user_set_theirs():
    """The ``gsrwt`` command runs a worker process per core, and OpenBLAS would start a
    thread per core in each (threads that spin after every small product, doubling the CPU
    time of ``estimate``): under the command numpy loads with one; a user's own
    ``OPENBLAS_NUM_THREADS`` is kept, and a plain ``import numpy`` has its usual threads."""
    def threads(mode: str, **environment: str) -> int:
        env = {name: value for name, value in os.environ.items()  # OMP_, GOTO_ too
               if name not in BLAS_THREAD_VARIABLES and not name.endswith("_NUM_THREADS")}
        result = subprocess.run([sys.executable, "-c", BLAS_THREADS, mode], capture_output=True,
                                text=True, check=True, env={**env, **environment})
        return int(result.stdout.split()[-1])

    assert threads("command") == 1
    assert threads("command", OPENBLAS_NUM_THREADS="2") == 2
    assert threads("library") == min(os.cpu_count() or 1, 64)


def test_the_package_exports_the_library_lazily():
    """``import gsrwt_cli`` loads no heavy library; each name a library user needs
    (``gsrwt_cli.View``, ``rectify_image``, ``estimate_pose``, ...) resolves on first use to
    the object its layer defines."""
    code = ("import sys, gsrwt_cli\n"
            f"heavy = {HEAVY!r}\n"
            "print(sorted(name for name in heavy if name in sys.modules))\n"
            "for name in gsrwt_cli.__all__:\n"
            "    value = getattr(gsrwt_cli, name)\n"
            "    assert name == '__version__' or value.__name__ == name, name\n"
            "print(sorted(gsrwt_cli.__all__))\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    loaded, exported = result.stdout.splitlines()
    assert loaded == "[]"
    assert {"View", "Intrinsics", "Pose", "rectify_image", "plan_image", "estimate_pose",
            "read_image", "render_view", "load_camera"} <= set(ast.literal_eval(exported))
