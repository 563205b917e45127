"""How user data appears in messages: on one line, escaped, and never longer than a bound;
and how a measured number appears beside the bar it missed.

An error message quotes what it complains about, but a value from a file may be huge (a YAML
alias bomb, a 400-digit number) or carry control characters (a file name with a newline).
:func:`quote` and :func:`one_line` keep every message one readable line.
"""

from __future__ import annotations

import math
import re
import reprlib
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal
from typing import Any

#: Characters of a value quoted in a message, at most.
QUOTE_LIMIT = 80
#: Characters quoted of the content of a file the user did not write or name themselves (a
#: calibration file a sidecar names: ``/etc/passwd``, ``../secret.txt``): a short token.
TOKEN_LIMIT = 24
#: Characters of a whole message line, at most.
LINE_LIMIT = 2000

_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def _escape(match: re.Match[str]) -> str:
    char = match.group(0)
    return {"\n": "\\n", "\r": "\\r", "\t": "\\t"}.get(char, f"\\x{ord(char):02x}")


def escape_controls(text: str) -> str:
    """``text`` with control characters (newlines included) written as escapes."""
    return _CONTROL.sub(_escape, text)


def shorten(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, with an ellipsis and the length it had."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text)} characters)"


def quote(value: Any, limit: int = QUOTE_LIMIT) -> str:
    """``value`` as a message quotes it: ``'text'``, escaped, at most ``limit`` characters."""
    text = value if isinstance(value, str) else _bounded_repr(value, limit)
    return "'" + shorten(escape_controls(text), limit) + "'"


def token(value: Any) -> str:
    """``value`` quoted as a short escaped token (:data:`TOKEN_LIMIT` characters at most, then
    its length): how a message about an untrusted file's content quotes that content."""
    return quote(value, TOKEN_LIMIT)


def _bounded_repr(value: Any, limit: int) -> str:
    if isinstance(value, int) and not isinstance(value, bool):
        digits = len(str(abs(value))) if abs(value) < 10**400 else None
        if digits is None or digits > limit:
            return f"an integer of {'over 400' if digits is None else digits} digits"
    bounded = reprlib.Repr()  # bounded in depth and items: a nested value costs little
    bounded.maxlevel, bounded.maxstring, bounded.maxother = 3, limit, limit
    return bounded.repr(value)


def one_line(text: str, limit: int = LINE_LIMIT) -> str:
    """A message on one line: control characters escaped, at most ``limit`` characters."""
    return shorten(escape_controls(str(text)), limit)


def _rounded(value: float, digits: int, rounding: str) -> str:
    if not math.isfinite(value):
        return f"{value:.{digits}f}"
    step = Decimal(1).scaleb(-digits)
    return str(Decimal(repr(float(value))).quantize(step, rounding=rounding))


def shown_below(value: float, digits: int = 1) -> str:
    """``value`` rounded down to ``digits`` decimals: a measure under a bar never reads as the
    bar itself (4.47 against a bar of 4.5 reads 4.4, not 4.5)."""
    return _rounded(value, digits, ROUND_FLOOR)


def shown_above(value: float, digits: int = 1) -> str:
    """``value`` rounded up to ``digits`` decimals: a measure over a bar never reads as the
    bar itself (3.04 against a bar of 3 reads 3.1, not 3.0)."""
    return _rounded(value, digits, ROUND_CEILING)
