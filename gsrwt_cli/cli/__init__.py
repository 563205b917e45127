"""The ``gsrwt`` command group: wires the commands and turns errors into one-line messages."""

from __future__ import annotations

import click

from .. import __version__
from .gaze import gaze, track
from .landmarks import lines, match
from .params import params
from .rectify import rectify
from .render import render


class GsrwtGroup(click.Group):
    """A group that reports unexpected errors in one line unless ``--debug`` is given."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
            raise
        except KeyboardInterrupt:
            raise click.exceptions.Exit(130) from None
        except Exception as error:
            if ctx.meta.get("gsrwt.debug"):
                raise
            raise click.ClickException(
                f"internal error: {type(error).__name__}: {error} (rerun with --debug for details)"
            ) from None


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


main.add_command(params)
main.add_command(rectify)
main.add_command(render)
main.add_command(gaze)
main.add_command(track)
main.add_command(lines)
main.add_command(match)


def run() -> None:
    """The ``gsrwt`` console script: :data:`main` in a process of its own."""
    global started_as_command
    started_as_command = True
    main(prog_name="gsrwt")


#: True in a process the ``gsrwt`` command started (not in a library user's or a test's):
#: there the batch may fork its workers from the main process, which has run no OpenCV code.
started_as_command = False
