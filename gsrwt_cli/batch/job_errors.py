"""The one line of a job that failed, in the table of every batch (rectify, estimate)."""

from __future__ import annotations

from ..base.messages import one_line
from ..imaging.images import ImageError
from ..inputs.records import RecordError
from ..io.outputs import OutsideOutputError
from .settings import Describe

#: Characters of a failure's line, at most: room for the longest of gsrwt's own reasons (a
#: confidence refused with every one of its reasons and the remedy, about 480) whole.
FAILURE_LIMIT = 1000


class JobError(Exception):
    """A job that cannot be done, for the reason its text gives."""


def error_text(error: BaseException, describe: Describe | None = None) -> str:
    """One line for a failure: the reason for expected errors, the type for unexpected ones.

    ``describe`` may word an error in the caller's terms (a command's option names).
    """
    described = describe(error) if describe is not None else None
    if described is not None:
        text = described
    elif isinstance(error, OSError) and error.strerror:
        text = error.strerror + (f": {error.filename}" if error.filename else "")
    elif isinstance(error, (JobError, ImageError, OutsideOutputError, RecordError, ValueError)):
        text = str(error)
    else:
        text = f"internal error: {type(error).__name__}: {error}"
    return one_line(" ".join(text.split()), FAILURE_LIMIT)
