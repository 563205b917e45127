"""A measure that missed its bar reads as having missed it: rounded away from the bar."""

from __future__ import annotations

import numpy as np
import pytest

from gsrwt_cli.api.estimate import MIN_STRUCTURE_RATIO, _refusal
from gsrwt_cli.base.messages import shown_above, shown_below


@pytest.mark.parametrize("digits", [1, 2, 3])
def test_a_measure_just_under_or_over_its_bar_never_reads_as_the_bar(digits: int) -> None:
    rng = np.random.default_rng(7)
    bars = np.round(rng.uniform(0.0, 10.0, 400), digits)
    step = 10.0**-digits
    for bar, gap in zip(bars, rng.uniform(1e-9, 0.6 * step, 400)):
        under, over = float(shown_below(bar - gap, digits)), float(shown_above(bar + gap, digits))
        assert under < bar and bar - gap - step < under <= bar - gap
        assert over > bar and bar + gap <= over < bar + gap + step


def test_values_on_a_decimal_step_are_shown_as_they_are() -> None:
    shown = [shown_below(v, 2) for v in (0.29, 0.57, 1.1, -0.01)]
    assert shown == ["0.29", "0.57", "1.10", "-0.01"]
    assert [shown_above(v, 1) for v in (3.0, 2.3, -0.1)] == ["3.0", "2.3", "-0.1"]


def test_a_structure_ratio_a_hair_under_the_bar_reads_under_it() -> None:
    """A cabin's photo (Pillow's sample ``sugarshack.mpo``) fit 4.47 times as well as random
    frames and was refused "only 4.5 times ... (need 4.5)"."""
    reason = _refusal(MIN_STRUCTURE_RATIO - 0.03, None)
    assert reason is not None and "only 4.4 times as well" in reason
    assert reason.endswith("(need 4.5); give the pose, or guides (--verticals)")
