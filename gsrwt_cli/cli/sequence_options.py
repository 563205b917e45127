"""The options of ``params``, ``estimate``, ``lines``, ``match`` and ``track`` on a video
(``--poses``, ``--time``, ``--max-pose-gap``), defined once and light: importing this module
loads no numpy (``gsrwt params`` starts without it).

The words and values are ``gsrwt rectify``'s (``tests/cli/test_sequences.py`` checks that
:data:`TIME_MODES` and :data:`DEFAULT_MAX_POSE_GAP` are
:mod:`~gsrwt_cli.batch.video_jobs`'s).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import click

from ..base.messages import quote
from ..base.numerals import parse_whole
from .options import Number

F = TypeVar("F", bound=Callable[..., Any])

#: ``--time``: the pose file's ``time`` counts from the first frame, or is on the video's
#: own clock (``pts * time_base``).
TIME_MODES = ("relative", "absolute")
#: ``--max-pose-gap``'s default, in seconds.
DEFAULT_MAX_POSE_GAP = 0.5


def video_argument(func: F) -> F:
    """``[VIDEO]``: an optional video file (``params``, ``track``)."""
    return click.argument("video", required=False, metavar="[VIDEO]")(func)


def pose_file_options(what: str) -> Callable[[F], F]:
    """``--poses FILE``, ``--time`` and ``--max-pose-gap``; ``what``: what the poses do for
    the command (``the frame's parameters``, ``each frame is rectified with``...)."""
    def decorate(func: F) -> F:
        func = click.option(
            "--max-pose-gap", type=Number(min=0), default=DEFAULT_MAX_POSE_GAP,
            show_default=True,
            help="With --poses: a frame further than this many seconds from every pose is "
                 "an error row.")(func)
        func = click.option(
            "--time", "time_mode", type=click.Choice(TIME_MODES), default="relative",
            show_default=True,
            help="With --poses: the time column counts seconds from the first frame, or is "
                 "on the video's own clock (absolute: pts x time_base).")(func)
        return click.option(
            "--poses", default=None, type=click.Path(dir_okay=False),
            help="A video's poses: a CSV or YAML file of a time and a pose per row, as "
                 f"'gsrwt rectify --poses' reads it, interpolated to each frame: {what}.")(func)
    return decorate


#: ``--frames``: which frames, as (start, stop or None, step).
FrameRange = tuple[int, int | None, int]


def _frame_range(ctx: click.Context, param: click.Parameter, text: str | None
                 ) -> FrameRange | None:
    """``START:STOP[:STEP]`` as a Python slice of frame indices (each part may be left out)."""
    if text is None:
        return None
    parts = text.split(":")
    try:
        if len(parts) not in (2, 3):
            raise ValueError
        start, stop, *step = (parse_whole(part) if part.strip() else None for part in parts)
        every = step[0] if step and step[0] is not None else 1
        if every < 1 or (start or 0) < 0 or (stop is not None and stop < 0):
            raise ValueError
    except ValueError:
        raise click.BadParameter(f"expected START:STOP or START:STOP:STEP (frame indices from "
                                 f"0, STEP >= 1, each may be left out), got {quote(text)}"
                                 ) from None
    return start or 0, stop, every


def frames_option(func: F) -> F:
    """``--frames START:STOP[:STEP]``: a video's frames to work on."""
    return click.option(
        "--frames", "frame_range", default=None, metavar="START:STOP[:STEP]",
        callback=_frame_range,
        help="With a video: only these frames, a Python slice of their indices (0:300, "
             "100:, ::10); decoding stops at STOP.")(func)
