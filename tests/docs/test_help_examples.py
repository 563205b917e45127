"""Every ``--help`` example works as printed, from the project root (issue 9, item 16).

The examples are read from the real ``gsrwt ... --help`` output. Every file or directory an
example reads must exist relative to the project root; every file it writes must be a
relative name inside the directory it runs in. Then each example runs as a shell command in
a copy of ``sample_data`` (so whatever it writes lands in the test's temporary directory)
and must succeed.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path, PurePosixPath

import click
import pytest

from gsrwt_cli.cli import main
from tests.helpers.cli import run_gsrwt
from tests.helpers.paths import ROOT

#: Slow (out of the quick loop, ``pytest -m "not slow"``): every test runs the installed
#: command in a subprocess.
pytestmark = pytest.mark.slow

#: Parameters that name what a command writes (the rest of the paths are read).
OUTPUT_PARAMETERS = {"output", "outdir", "draw", "out_sidecar", "table_path"}
#: Parameters that name what a command reads but are not ``click.Path`` typed.
INPUT_PARAMETERS = {"inputs"}
#: Programs other than gsrwt that examples may pipe from, and how to find their paths.
OTHER_PROGRAMS = {"find"}



def help_examples(command: str | None) -> list[str]:
    """The example command lines of ``gsrwt [COMMAND] --help``, continuations joined."""
    result = run_gsrwt(*([command] if command else []), "--help")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    starts = [i for i, line in enumerate(lines) if re.fullmatch(r"\s*Examples?:\s*", line)]
    assert len(starts) == 1, f"gsrwt {command} --help has no single Example(s) block"
    examples: list[str] = []
    pending = ""
    for line in lines[starts[0] + 1:]:
        if not line.strip():
            break
        text = pending + line.strip()
        if text.endswith("\\"):
            pending = text[:-1].rstrip() + " "
            continue
        examples.append(text)
        pending = ""
    assert examples and not pending
    return examples


def pipeline(example: str) -> list[list[str]]:
    """The commands of a shell pipeline, each as its words."""
    words = shlex.split(example)
    commands: list[list[str]] = [[]]
    for word in words:
        if word == "|":
            commands.append([])
        else:
            commands[-1].append(word)
    return commands


def gsrwt_paths(words: list[str]) -> tuple[list[str], list[str]]:
    """What a gsrwt command line reads and writes: (input paths, output paths)."""
    assert words[0] == "gsrwt"
    command: click.Command = main
    arguments = words[1:]
    if arguments and arguments[0] in main.list_commands(None):
        command, arguments = main.get_command(None, arguments[0]), arguments[1:]
    context = command.make_context(command.name, list(arguments), resilient_parsing=True)
    reads: list[str] = []
    writes: list[str] = []
    for parameter in command.params:
        value = context.params.get(parameter.name)
        if value is None or parameter.name == "help":
            continue
        values = [str(v) for v in value] if isinstance(value, (tuple, list)) else [str(value)]
        if parameter.name in OUTPUT_PARAMETERS:
            writes += [v for v in values if v != "-"]
        elif parameter.name in INPUT_PARAMETERS or isinstance(parameter.type, click.Path):
            reads += [v for v in values if v != "-"]
    return reads, writes


def example_paths(example: str) -> tuple[list[str], list[str]]:
    """Every path an example reads and writes, over all the commands of its pipeline."""
    reads: list[str] = []
    writes: list[str] = []
    for words in pipeline(example):
        if words[0] == "gsrwt":
            more_reads, more_writes = gsrwt_paths(words)
            reads += more_reads
            writes += more_writes
        elif words[0] == "find":
            reads += [word for word in words[1:] if not word.startswith("-")][:1]
        else:
            pytest.fail(f"teach this test the paths of {words[0]!r} (in {example!r})")
    return reads, writes


COMMANDS = [None, *main.list_commands(None)]


def command_id(command: str | None) -> str:
    return command or "gsrwt"


PARAMETERS = [pytest.param(c, id=command_id(c)) for c in COMMANDS]


@pytest.mark.parametrize("command", PARAMETERS)
def test_help_examples_name_files_that_exist_from_the_project_root(command):
    for example in help_examples(command):
        reads, writes = example_paths(example)
        for path in reads:
            assert (ROOT / path).exists(), f"{example!r}: {path} does not exist from the root"
        for path in writes:
            pure = PurePosixPath(path)
            assert not pure.is_absolute() and ".." not in pure.parts, (
                f"{example!r}: writes {path}, not a relative name inside where it runs")


@pytest.mark.parametrize("command", PARAMETERS)
def test_help_examples_run(tmp_path, command):
    """Each example, as printed, in a copy of the sample data: exit 0, its outputs made."""
    shutil.copytree(ROOT / "sample_data", tmp_path / "sample_data")
    environment = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
                   f"{os.environ.get('PATH', '')}"}
    for example in help_examples(command):
        _, writes = example_paths(example)
        result = subprocess.run(["bash", "-o", "pipefail", "-c", example], cwd=tmp_path,
                                env=environment, capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, f"{example}\n{result.stderr}"
        assert "Traceback" not in result.stderr and "Error" not in result.stderr, example
        for path in writes:
            assert (tmp_path / path).exists(), f"{example!r} did not write {path}"
