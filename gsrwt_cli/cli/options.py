"""Options and errors shared by several commands, defined once."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path, PurePosixPath
from typing import Any, TypeVar

import click

from ..messages import one_line
from ..outputs import OutsideOutputError, check_inside
from ..sidecar import RecordError
from ..tables import FORMATS

F = TypeVar("F", bound=Callable[..., Any])


class InputError(click.ClickException):
    """Bad input from the user (file, row, option): one line on stderr, exit code 2."""

    exit_code = 2

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


def report_error(message: str) -> None:
    """One ``Error: ...`` line on stderr: control characters escaped, length bounded."""
    click.echo("Error: " + one_line(message), err=True)


def _is_inside(real_root: str, real_path: str) -> bool:
    return real_path == real_root or real_path.startswith(real_root.rstrip(os.sep) + os.sep)


def output_target(root: Path, relative: PurePosixPath | str) -> Path:
    """``root / relative``, a file a command may write, checked against the output rule.

    ``relative`` must already be a checked relative name
    (:func:`~gsrwt_cli.outputs.relative_output`, or a plain file name). Raises
    :class:`~gsrwt_cli.outputs.OutsideOutputError` when writing there would leave ``root``:
    a directory on the way is a symbolic link leading out of it, or the file itself is a
    symbolic link to a file outside it (which we refuse rather than silently replace the link).
    ``root`` should exist: nothing inside a missing directory can be a link.
    """
    target = root / relative
    if not os.path.lexists(root):
        return target
    check_inside(root, target)
    if os.path.islink(target):
        pointed_to = os.path.realpath(target)
        if not _is_inside(os.path.realpath(root), pointed_to):
            raise OutsideOutputError(
                f"is a symbolic link to {pointed_to}, outside the output {root}"
            )
    return target


def make_output_directory(option: str, directory: Path) -> None:
    """Create the output directory the user named, or stop with one line saying why not."""
    if directory.exists() and not directory.is_dir():
        raise InputError(f"{option} {directory}: exists and is not a directory")
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"{option} {directory}: cannot create it "
                         f"({error.strerror or error})") from None


def format_option(func: F) -> F:
    """``--format``: table on a terminal, csv when stdout is a pipe."""
    return click.option(
        "--format",
        "-f",
        "fmt",
        type=click.Choice(FORMATS),
        default=None,
        help="Output format [default: table on a terminal, csv in a pipe].",
    )(func)


def resolve_format(fmt: str | None) -> str:
    """The chosen format, or the default for where stdout goes."""
    if fmt is not None:
        return fmt
    return "table" if sys.stdout.isatty() else "csv"


def view_options(func: F) -> F:
    """``--pan --tilt --focal --cx --cy --width --height --distance`` (one view, or defaults)."""
    options = [
        click.option("--pan", type=float, help="Pan in degrees, positive turns left."),
        click.option("--tilt", type=float, help="Tilt in degrees, positive tilts up."),
        click.option("--focal", type=float, help="Focal length in pixels."),
        click.option("--cx", type=float, help="Principal point column [default: image centre]."),
        click.option("--cy", type=float, help="Principal point row [default: image centre]."),
        click.option("--width", type=int, help="Image width in pixels."),
        click.option("--height", type=int, help="Image height in pixels."),
        click.option("--distance", type=float, help="Camera-to-wall distance (your unit)."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


VIEW_OPTION_NAMES = ("pan", "tilt", "focal", "cx", "cy", "width", "height", "distance")


def option_message(error: RecordError) -> str:
    """A record error about values given as options, phrased in terms of the options."""
    if error.field is None:
        return error.reason.replace("missing field '", "missing option --").replace("'", "", 1)
    return f"option --{error.field}: {error.reason}"


def view_defaults(kwargs: dict[str, Any]) -> dict[str, Any]:
    """The view options the user gave, as fallback values for sidecar records."""
    return {name: kwargs[name] for name in VIEW_OPTION_NAMES if kwargs.get(name) is not None}
