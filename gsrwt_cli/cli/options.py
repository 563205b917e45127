"""Options and errors shared by several commands, defined once."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any, TypeVar

import click

from ..sidecar import RecordError
from ..tables import FORMATS

F = TypeVar("F", bound=Callable[..., Any])


class InputError(click.ClickException):
    """Bad input from the user (file, row, option): one line on stderr, exit code 2."""

    exit_code = 2


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
