"""The ``gsrwt`` command group: wires the commands and turns errors into one-line messages."""

from __future__ import annotations

import contextlib
import errno
import os
import select
import sys
import warnings
from typing import Any, NoReturn

import click

from .. import __version__
from ..imaging import silence_opencv_logging
from ..messages import escape_controls, one_line, shorten
from .estimate import estimate
from .gaze import gaze, track
from .landmarks import lines, match
from .params import params
from .rectify import rectify
from .render import render

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


class GsrwtGroup(click.Group):
    """A group that reports every error in one bounded line (tracebacks only with ``--debug``).

    An EPIPE write to standard output or error leaves as :class:`ClosedOutputError`, for
    :func:`run` to end the process quietly.
    """

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


main.add_command(params)
main.add_command(rectify)
main.add_command(estimate)
main.add_command(render)
main.add_command(gaze)
main.add_command(track)
main.add_command(lines)
main.add_command(match)


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

