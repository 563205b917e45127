"""The error a camera value raises and the checks every value passes where it enters.

Plain Python and no numpy: :mod:`.lens` and :mod:`.camera` check every number they are given
with these, so an invalid value is refused naming its field before any computation.
"""

from __future__ import annotations

import math
import numbers

from ..base.messages import quote


class ViewError(ValueError):
    """An invalid camera parameter; ``field`` names the offending parameter."""

    def __init__(self, field_name: str, message: str) -> None:
        super().__init__(message)
        self.field = field_name


def as_number(name: str, value: object) -> float | int | None:
    """``value`` as a finite Python number (numpy scalars and big integers too), else ViewError."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ViewError(name, f"{name} must be a number, got {quote(value)}")
    given = value
    try:
        if type(value) not in (int, float):  # numpy scalars, Fractions: plain Python numbers
            value = int(value) if isinstance(value, numbers.Integral) else float(value)
        finite = math.isfinite(value)
    except OverflowError:  # an int or a Fraction too large for a float
        finite = False
    if not finite:
        raise ViewError(name, f"{name} must be a finite number, got {quote(given)}")
    return value


def check_range(name: str, value: float, low: float, high: float, unit: str) -> None:
    """``low < value < high``; ``low`` 0 reads "positive"."""
    if value <= low:
        what = "positive" if low == 0 else f"above {low:g}{unit}"
        raise ViewError(name, f"{name} must be {what}, got {value:.15g}")
    if value >= high:
        raise ViewError(name, f"{name} must be below {high:g}{unit}, got {value:.15g}")
