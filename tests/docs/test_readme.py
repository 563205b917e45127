"""The README and the pages of docs/ tell the truth: every command and option is documented,
every command they show runs, every promise names its test."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import click
import cv2
import pytest

from gsrwt_cli import __version__
from gsrwt_cli.cli import main
from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import ROOT
from tests.helpers.tables import read_table

README = (ROOT / "README.md").read_text()
DOCS = ROOT / "docs"
#: The pages written by hand, README first: what documents the commands (docs/CLI.md, the
#: commands' own --help, would document every option trivially, so it does not count).
PAGES = {"README.md": README, **{f"docs/{page.name}": page.read_text()
                                 for page in sorted(DOCS.glob("*.md")) if page.name != "CLI.md"}}
DOCUMENTED = "\n".join(PAGES.values())


def sh_blocks(text: str) -> list[list[str]]:
    return [block.strip().splitlines() for block in re.findall(r"```sh\n(.*?)```", text, re.S)]


def gsrwt_commands(text: str) -> list[str]:
    """Every gsrwt command line in the sh blocks of ``text`` (the part after `pip ... &&`);
    the development commands are run by :func:`test_development_commands_run`."""
    commands = []
    for block in sh_blocks(text):
        for line in block:
            command = line.split(" && ", 1)[1] if line.startswith("pip ") else line
            if re.match(r"(gsrwt |find .*\| gsrwt )", command):
                commands.append(command)
    return commands


def readme_commands() -> list[str]:
    """The gsrwt command lines of the README, then of the docs pages (by name), each once, in
    the order a reader meets them: an example may use what an earlier one made."""
    return list(dict.fromkeys(command for text in PAGES.values()
                              for command in gsrwt_commands(text)))


def test_quick_start_is_one_sh_block_of_two_lines():
    section = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    (block,) = sh_blocks(section)
    assert len(block) == 2
    assert block[0].startswith("pip install . && gsrwt rectify sample_data")
    assert block[1] == "pip install '.[test]' && python -m pytest -q"
    ci = (ROOT / ".ci" / "run").read_text()
    assert "sed -n 2p" in ci  # CI runs that very line


@pytest.mark.parametrize("name", main.list_commands(None))
def test_every_command_and_option_is_documented(name):
    """Each command has its section in docs/COMMANDS.md (``gsrwt tables`` as ``gsrwt tables
    merge``), and each option of it and of its subcommands is in a page of the docs."""
    commands = PAGES["docs/COMMANDS.md"]
    assert re.search(rf"^## .*`gsrwt {name}[` ]", commands, re.M), name
    command = main.get_command(None, name)
    subcommands = [command.get_command(None, sub) for sub in command.list_commands(None)] if (
        isinstance(command, click.Group)) else []
    for each in (command, *subcommands):
        for parameter in each.params:
            for option in parameter.opts:
                if option.startswith("--") and option != "--help":
                    assert option in DOCUMENTED, f"gsrwt {name} {option} is in no page of the docs"


@pytest.mark.parametrize("name", main.list_commands(None))
def test_the_readme_shows_every_command_once_at_least(name):
    assert any(command.startswith(f"gsrwt {name} ") for command in gsrwt_commands(README)), name


@pytest.mark.parametrize("name", main.list_commands(None))
def test_every_command_has_help_with_an_example(name):
    result = run_gsrwt(name, "--help")
    assert result.returncode == 0
    assert "Example" in result.stdout and f"gsrwt {name}" in result.stdout


def test_version():
    result = run_gsrwt("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"gsrwt, version {__version__}"


@pytest.mark.slow
def test_every_readme_command_runs(tmp_path):
    """Run them all (the README's, then the docs pages'), in order, in a copy of the sample
    data and the real photos, as a user would from the root."""
    shutil.copytree(ROOT / "sample_data", tmp_path / "sample_data")
    shutil.copytree(ROOT / "tests" / "data" / "real", tmp_path / "tests" / "data" / "real")
    environment = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
                   f"{os.environ.get('PATH', '')}"}
    commands = readme_commands()
    assert len(commands) >= 12
    outputs: dict[str, subprocess.CompletedProcess] = {}
    for command in commands:
        result = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=tmp_path,
                                env=environment, capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, f"{command}\n{result.stderr}"
        assert "Error" not in result.stderr and "Traceback" not in result.stderr, command
        outputs.setdefault(command, result)  # the first run of a command shown twice
    quick = commands[0]
    assert "9 ok, 0 skipped, 0 failed" in outputs[quick].stderr
    assert len(list((tmp_path / "rectified").glob("*.png"))) == 5
    json_params = next(c for c in commands if "params" in c and "json" in c)
    (row,) = read_table(outputs[json_params].stdout, "json")
    assert round(row["delta_deg"], 1) == 28.2 and round(row["a_px"], 1) == 427.5
    track = next(c for c in commands if c.startswith("gsrwt track"))
    pans = [round(float(line.split(",")[1]), 1)
            for line in outputs[track].stdout.splitlines()[1:]]
    assert pans == [52.9, 40.0, 31.0]
    assert (tmp_path / "view.yaml").is_file()
    assert (tmp_path / "view-rectified" / "view.png").is_file()
    assert len(list((tmp_path / "from-stdin" / "sample_data" / "views").glob("*.png"))) == 4


@pytest.mark.slow
def test_development_commands_run(tmp_path):
    """docs/DEVELOPMENT.md's block: benchmarks (small), sample regeneration, lint."""
    (block,) = [b for b in sh_blocks(PAGES["docs/DEVELOPMENT.md"])
                if any("make_samples" in line for line in b)]
    copy = tmp_path / "repo"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns(".git", "rectified", ".venv",
                                                              "__pycache__", "*.egg-info"))
    environment = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
                   f"{os.environ.get('PATH', '')}"}
    for line in block:
        # The same scripts, on two images once.
        command = line.replace("--images 64 --repeat 3", "--images 2 --repeat 1")
        command = command.replace("bench_startup.py", "bench_startup.py --rows 2000 --repeat 1")
        command = command.replace("python ", f"{sys.executable} ", 1)
        result = subprocess.run(["bash", "-c", command], cwd=copy, env=environment,
                                capture_output=True, text=True, timeout=600)
        assert result.returncode == 0, f"{command}\n{result.stdout}\n{result.stderr}"
        if "bench_rectify" in command:
            assert "gsrwt time / OpenCV floor time:" in result.stdout
            assert "gsrwt worker peak memory:" in result.stdout
        if "bench_match" in command:
            assert "both templates on one 640x480 view:" in result.stdout
        if "bench_startup" in command:
            assert "output byte-identical to the floor's: True" in result.stdout
    # Regenerating the sample data gives the committed files back.
    for name in ("corridor_wall.json", "views/views.csv", "views/views.yaml"):
        assert (copy / "sample_data" / name).read_bytes() == (
            ROOT / "sample_data" / name).read_bytes(), name
    for name in ("corridor_wall.png", "templates/knob.png", "templates/window.png"):
        made = cv2.imread(str(copy / "sample_data" / name)).astype(int)
        committed = cv2.imread(str(ROOT / "sample_data" / name)).astype(int)
        # OpenCV's releases draw antialiased shapes and text a little differently (5.1 against
        # 5.0: 0.013 % of the texture's values, measured); another drawing would differ widely.
        assert made.shape == committed.shape and (made != committed).mean() < 1e-3, name


def test_python_api_example_runs(capsys, monkeypatch):
    """docs/PYTHON_API.md's example, through the names ``gsrwt_cli`` exports."""
    (block,) = re.findall(r"```python\n(.*?)```", PAGES["docs/PYTHON_API.md"], re.S)
    monkeypatch.chdir(ROOT)
    exec(compile(block, "docs/PYTHON_API.md", "exec"), {})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("(320, 240)")
    assert "20 10 0" in printed and "plumb_bob" in printed
    delta, shift, gamma = (float(v) for v in printed[-1].split())
    assert (round(delta, 2), round(shift, 2), round(gamma, 2)) == (28.19, 427.46, -24.15)


def test_the_readmes_python_example_runs(capsys, monkeypatch):
    (block,) = re.findall(r"```python\n(.*?)```", README, re.S)
    monkeypatch.chdir(ROOT)
    exec(compile(block, "README.md", "exec"), {})
    shape, delta = capsys.readouterr().out.rsplit(")", 1)
    assert shape == "(240, 320, 3" and round(float(delta), 2) == 28.19


def test_every_guarantee_names_tests_that_exist():
    """Each row of the Guarantees table (docs/GUARANTEES.md) names tests (``layer/file.py::name``
    under tests/, or ``::name`` for the file named last) that are defined in that file, so the
    promise has a test behind it."""
    section = PAGES["docs/GUARANTEES.md"].split("# Guarantees", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and "::" in line]
    assert len(rows) >= 10
    for row in rows:
        held_by = row.rstrip(" |").rsplit(" | ", 1)[1]
        current = None
        for file_name, test_name in re.findall(r"`((?:\w+/)*test_\w+\.py)?::(\w+)`", held_by):
            current = file_name or current
            assert current, row
            source = (ROOT / "tests" / current).read_text()
            assert re.search(rf"^def {test_name}\(", source, re.M), f"{current}::{test_name}"
        for whole_file in re.findall(r"`((?:\w+/)*test_\w+\.py)`", held_by):
            assert (ROOT / "tests" / whole_file).is_file(), whole_file
