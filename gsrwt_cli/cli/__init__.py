"""The ``gsrwt`` command group: wires the commands and turns errors into one-line messages."""

from __future__ import annotations

import contextlib
import errno
import importlib
import os
import select
import sys
import warnings
from typing import Any, NoReturn

import click

from .. import __version__
from ..base.messages import escape_controls, one_line, shorten

#: Exit status of a command whose standard output was closed by its reader: 128 + SIGPIPE,
#: what a shell reports for ``cat`` killed by SIGPIPE in ``cat big | head -1``.
CLOSED_STDOUT_STATUS = 128 + 13
#: Characters of an unexpected exception's text quoted in the "internal error" line.
INTERNAL_ERROR_LIMIT = 300


class ClosedOutputError(Exception):
    """Standard output (or error) was closed by its reader; carried past click to :func:`run`.

    Not an ``OSError``: click's own handler turns an EPIPE ``OSError`` into exit status 1.
    """


def is_broken_pipe(error: BaseException) -> bool:
    """True for a write to a pipe or socket whose reader has gone (EPIPE)."""
    return isinstance(error, OSError) and (
        isinstance(error, BrokenPipeError) or error.errno == errno.EPIPE
    )


def _reader_gone(stream: Any) -> bool:
    """True if ``stream`` is a pipe or socket whose reading end is closed.

    ``poll`` reports POLLERR (Linux) or POLLHUP (BSD, macOS) on the writing end of a pipe whose
    reader has gone. Where that cannot be asked (no ``poll``, no descriptor), assume it is.
    """
    try:
        descriptor = stream.fileno()
        poller = select.poll()
    except (AttributeError, OSError, ValueError):
        return True
    poller.register(descriptor, select.POLLOUT)
    events = sum(event for _, event in poller.poll(0))
    return bool(events & (select.POLLERR | select.POLLHUP))


def _standard_stream_closed() -> bool:
    """True if standard output or standard error has lost its reader."""
    return any(stream is not None and _reader_gone(stream) for stream in (sys.stdout, sys.stderr))


def internal_error_message(error: BaseException) -> str:
    """The one bounded line for an exception nobody expected."""
    text = shorten(escape_controls(str(error)), INTERNAL_ERROR_LIMIT)
    return one_line(f"internal error: {type(error).__name__}: {text} "
                    "(rerun with --debug for details)")


#: Each command: the module of this package that defines it, and the first paragraph of its
#: help (for ``gsrwt --help``; a test checks it against the command's docstring). A command's
#: module, and what it imports, is loaded only when that command is used, so that
#: ``gsrwt --version``, ``gsrwt --help`` and the light commands start fast.
COMMANDS: dict[str, tuple[str, str]] = {
    "estimate": ("estimate", "Estimate pan, tilt and roll of each image from its straight lines "
                             "(thesis future work 1)."),
    "gaze": ("gaze", "Pan and tilt that centre a target seen on the canonical view, or, with "
                     "no target, the wall point the camera looks at."),
    "lines": ("landmarks", "Straight segments (door boundaries) by the Hough transform on frontal "
                           "views (Sec. 5.2.2)."),
    "match": ("landmarks", "Find objects (door knob, peek window) with the Generalized Hough "
                           "Transform (Sec. 5.2.2)."),
    "params": ("params", "Print the GS-RWT parameters (theta, delta, a, gamma, vanishing point "
                         "and line)."),
    "rectify": ("rectify", "Rectify images into canonical frontal views of the wall they show "
                           "(GS-RWT)."),
    "render": ("render", "Render the view of a camera at --pan/--tilt of a wall covered by "
                         "TEXTURE."),
    "tables": ("tables", "Work with the tables gsrwt writes: merge the tables of --shard "
                         "runs."),
    "track": ("gaze", "Pan and tilt that keep an object centred as the robot drives along the "
                      "wall."),
}


class GsrwtGroup(click.Group):
    """A group that reports every error in one bounded line (tracebacks only with ``--debug``)
    and loads each of its :data:`COMMANDS` when it is used.

    An EPIPE write to standard output or error leaves as :class:`ClosedOutputError`, for
    :func:`run` to end the process quietly.
    """

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*COMMANDS, *self.commands})

    def get_command(self, ctx: click.Context | None, name: str) -> click.Command | None:
        if name in self.commands or name not in COMMANDS:
            return self.commands.get(name)
        module = importlib.import_module(f"{__name__}.{COMMANDS[name][0]}")
        return getattr(module, name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The commands and their one-line help, as click writes them, without loading them."""
        names = self.list_commands(ctx)
        limit = formatter.width - 6 - max(len(name) for name in names)
        stand_ins = {name: click.Command(name, help=text) for name, (_, text) in COMMANDS.items()}
        rows = [(name, {**stand_ins, **self.commands}[name].get_short_help_str(limit))
                for name in names]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def make_context(self, info_name: str | None, args: list[str],
                     parent: click.Context | None = None, **extra: Any) -> click.Context:
        try:
            return super().make_context(info_name, args, parent=parent, **extra)
        except click.exceptions.ClickException as error:
            error.message = one_line(error.message)
            raise
        except OSError as error:
            if is_broken_pipe(error):
                raise ClosedOutputError() from error
            raise

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except click.exceptions.ClickException as error:
            error.message = one_line(error.message)
            raise
        except (click.exceptions.Exit, click.exceptions.Abort):
            raise
        except KeyboardInterrupt:
            raise click.exceptions.Exit(130) from None
        except Exception as error:
            if is_broken_pipe(error) and _standard_stream_closed():
                raise ClosedOutputError() from error
            if ctx.meta.get("gsrwt.debug"):
                raise
            raise click.ClickException(internal_error_message(error)) from None


@click.group(cls=GsrwtGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", "-V", prog_name="gsrwt")
@click.option("--debug", is_flag=True, help="Show Python tracebacks for errors.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """Rectify photos of walls, doors and signs taken by a pan-tilt camera into frontal views.

    Uses the Generalized Shifted Reciprocal-Wedge Transform (GS-RWT).

    \b
    Example:
      gsrwt params --pan 15 --tilt 30 --focal 280
    """
    ctx.meta["gsrwt.debug"] = debug
    if not debug and not sys.warnoptions:
        # Problems are reported as one-line errors; a library's warning (with its source
        # path) would break that promise. The code checks what warnings would flag (values
        # that are not finite); --debug or python -W shows them.
        warnings.simplefilter("ignore")


def _end_for_closed_stdout() -> NoReturn:
    """Leave quietly with :data:`CLOSED_STDOUT_STATUS` after the reader of our output left.

    Why so: ``gsrwt params --sidecar big.csv | head -1`` is a normal thing to type, and its
    reader leaving is not our error, so no message. The status is what ``cat`` gets in the
    same pipeline (killed by SIGPIPE, 128 + 13), so ``set -o pipefail`` scripts see the usual
    value. We do not restore SIGPIPE's default action instead (which would give that status
    by dying): dying mid-write would leave temporary files and skip the cleanup of a batch.
    Standard output (and error, if it is closed too) is pointed at the null device, so that
    the flush at interpreter shutdown has somewhere to put what is still buffered, instead
    of printing "Exception ignored ... BrokenPipeError".
    """
    for stream in (sys.stdout, sys.stderr):
        if stream is None or not _reader_gone(stream):
            continue
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, stream.fileno())
            os.close(null)
        except (AttributeError, OSError, ValueError):
            pass
    sys.exit(CLOSED_STDOUT_STATUS)


#: The environment variables that set numpy's BLAS threads (OpenBLAS, as numpy's wheels
#: have it, and MKL), set to 1 by :func:`run` where the user has not set them.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """Give numpy one BLAS thread per process (:data:`BLAS_THREAD_VARIABLES`), unless the
    user set their own; OpenBLAS and MKL read these when numpy loads, so call it first.

    gsrwt's parallelism is a worker process per core (``-j``). numpy's BLAS would add a
    thread per core to each, and those threads spin after every small matrix product: twice
    the CPU for the same work, and ``estimate -j 2`` took 1.9 times as long."""
    for variable in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(variable, "1")


class CommandProcess:
    """The context object of a process the ``gsrwt`` command started (not a library user's
    or a test's): there the batch may fork its workers from the main process, which has run
    no OpenCV code."""

    fork_workers = True


def run() -> None:
    """The ``gsrwt`` console script: :data:`main` in a process of its own.

    Every command ends here; a closed standard output ends it quietly with status 141
    (:func:`_end_for_closed_stdout`), whether the pipe broke while a command wrote, while
    click printed help or an error, or at the final flush of what was still buffered.
    """
    # OpenCV's own log lines would break the one-line-per-problem promise; what gsrwt needs
    # from the codecs it collects itself. OpenCV reads this when it is first imported.
    os.environ["OPENCV_LOG_LEVEL"] = "SILENT"
    one_blas_thread()
    if "cv2" in sys.modules:
        from ..imaging.images import silence_opencv_logging

        silence_opencv_logging()
    # File names are bytes on POSIX; Python gives a name that is not valid UTF-8 to us with
    # its odd bytes as lone surrogates. Write those back as the very bytes they stand for,
    # so the image column names the real file, instead of failing to encode the row.
    with contextlib.suppress(AttributeError, ValueError):
        sys.stdout.reconfigure(errors="surrogateescape")
    try:
        try:
            main(prog_name="gsrwt", obj=CommandProcess())
        except SystemExit:
            # The last rows may still sit in the buffer: flush them now, where a closed
            # pipe can be handled, not during interpreter shutdown.
            if sys.stdout is not None:
                sys.stdout.flush()
            raise
    except ClosedOutputError:
        _end_for_closed_stdout()
    except OSError as error:
        if is_broken_pipe(error):
            _end_for_closed_stdout()
        raise

