"""One way to run the ``gsrwt`` command: the installed script, in a real subprocess.

:func:`run_gsrwt` runs it to the end (what a user sees: exit status, stdout, stderr);
:func:`start_gsrwt` starts it for a test that acts while it runs (a signal, a killed worker,
a reader that leaves). Both run the script beside this interpreter, so the tests exercise
what ``pip install`` made, entry point included.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from types import SimpleNamespace

from tests.helpers.tables import read_table

#: The installed console script of this environment.
GSRWT = Path(sys.executable).with_name("gsrwt")

Argument = str | bytes | Path


def _environment(env: Mapping[str, str] | None) -> dict[str, str] | None:
    """This process's environment with ``env``'s variables set on top (None: unchanged)."""
    return None if env is None else {**os.environ, **env}


def run_gsrwt(*args: Argument, stdin: str | bytes | None = None, cwd: Path | None = None,
              env: Mapping[str, str] | None = None, text: bool = True,
              timeout: float = 300) -> subprocess.CompletedProcess:
    """Run ``gsrwt ARGS`` to its end and capture what it printed.

    ``stdin``: what it reads on standard input (nothing: an empty, closed input). ``env``:
    variables set on top of this process's environment. ``text=False`` gives stdout and
    stderr as bytes (names that are not UTF-8); arguments may be bytes either way.
    """
    return subprocess.run([GSRWT, *args], input=stdin, capture_output=True, text=text, cwd=cwd,
                          env=_environment(env), timeout=timeout)


def start_gsrwt(*args: Argument, cwd: Path | None = None, env: Mapping[str, str] | None = None,
                text: bool = True, own_session: bool = False) -> subprocess.Popen:
    """Start ``gsrwt ARGS`` with stdout and stderr piped, and return at once.

    ``own_session``: in a session and process group of its own, which then stands for a
    terminal's (a signal to the group reaches the command and its workers, as Ctrl-C does).
    """
    return subprocess.Popen([GSRWT, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=text, cwd=cwd, env=_environment(env),
                            start_new_session=own_session)


def run_gsrwt_measuring_memory(*args: Argument, cwd: Path | None = None
                               ) -> tuple[subprocess.CompletedProcess, int]:
    """:func:`run_gsrwt`, and the peak resident memory (KiB) of its largest process.

    A small Python parent runs the command and reports ``RUSAGE_CHILDREN``'s ``ru_maxrss``:
    the largest of the command and the workers it waited for, nothing of this process.
    """
    parent = ("import resource, subprocess, sys; "
              "result = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
              "sys.stdout.write(result.stderr); "
              "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr); "
              "sys.exit(result.returncode)")
    run = subprocess.run([sys.executable, "-c", parent, GSRWT, *args], capture_output=True,
                         text=True, cwd=cwd, timeout=300)
    return (subprocess.CompletedProcess([GSRWT, *args], run.returncode, "", run.stdout),
            int(run.stderr.split()[-1]))


def lines_of(*args: str) -> dict[str, list[SimpleNamespace]]:
    """``gsrwt lines ARGS --format csv`` (one real run), its rows per image file name."""
    result = run_gsrwt("lines", *args, "--format", "csv")
    assert result.returncode == 0, result.stderr
    found: dict[str, list[SimpleNamespace]] = {}
    for row in read_table(result.stdout):
        values = {key: float(value) for key, value in row.items() if key != "image" and value}
        found.setdefault(Path(row["image"]).name, []).append(SimpleNamespace(**values))
    return found
