"""Numbers typed by people: what the options and the tables read, in one place.

Python's ``int`` and ``float`` take more than a person means by a number: ``1_0`` is 10,
Arabic-Indic ``٣`` is 3, ``int('+2')`` and ``int(' 2 ')`` work, and a 23-digit integer is
fine by them. Every number gsrwt reads from an option or a table goes through here instead:
ASCII digits only, no underscores or spaces, bounded. (Sidecar fields are read the same way
by :mod:`~gsrwt_cli.inputs.records`.)
"""

from __future__ import annotations

import math
import re

#: A whole number: ASCII digits, a minus sign at most (no ``+``, no ``_``, no spaces).
WHOLE = re.compile(r"-?[0-9]+")
#: A decimal number: ``-12``, ``+3.5``, ``.5``, ``1e-3``, in ASCII digits.
DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
#: What ``float`` takes for a value that is not finite.
NOT_FINITE = re.compile(r"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)
#: Digits of a whole number at most: beyond every bound gsrwt has, and far from Python's
#: limit on converting long strings.
MAX_WHOLE_DIGITS = 18


def parse_whole(text: str) -> int:
    """``text`` as an int if it is a :data:`WHOLE` number of at most
    :data:`MAX_WHOLE_DIGITS` digits; otherwise ``ValueError`` saying what is wrong (without
    ``text``, which the caller quotes)."""
    if not WHOLE.fullmatch(text):
        raise ValueError("expected a whole number in ASCII digits")
    if len(text.lstrip("-")) > MAX_WHOLE_DIGITS:
        raise ValueError(f"out of range (over {MAX_WHOLE_DIGITS} digits)")
    return int(text)


def parse_decimal(text: str) -> float:
    """``text`` as a finite float if it is a :data:`DECIMAL` number; otherwise (``nan``,
    ``inf`` and ``1e400`` included) ``ValueError`` saying what is wrong, as
    :func:`parse_whole`."""
    if NOT_FINITE.fullmatch(text):
        raise ValueError("must be finite")
    if not DECIMAL.fullmatch(text):
        raise ValueError("expected a finite decimal number in ASCII digits, such as -2.5 or 1e3")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError("beyond floating point")
    return value
