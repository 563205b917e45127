"""The common case as plain numbers (``geometry/pinhole.py``): a square-pixel pinhole's params
row by the math module, against the view's own row."""

from __future__ import annotations

from tests.helpers.printed import PrintedComparison, allowed


def test_one_plain_view_computed_without_numpy_prints_its_views_row():
    """``gsrwt params`` with options computes a plain square-pixel pinhole by the math
    module alone (:mod:`gsrwt_cli.geometry.pinhole`): for random options, frontal views, horizons
    near
    the principal point and every combination of size and principal point, the row prints
    what the view's row prints (:mod:`printed`: a second implementation, compared as the
    table shows it) type for type, and None where the view refuses (its error is then the
    view's). The two may disagree on refusing only where the horizon's offset from the
    principal point lies within rounding of the bound."""
    import math
    import random

    from gsrwt_cli.geometry.bounds import MIN_HORIZON_OFFSET_PX

    def near_the_horizon_bound(numbers: tuple[float, ...]) -> bool:
        pan, tilt, focal = math.radians(numbers[0]), math.radians(numbers[1]), numbers[2]
        sin_theta = math.hypot(math.sin(pan), math.cos(pan) * math.sin(tilt))
        offset = focal * math.cos(pan) * math.cos(tilt) / sin_theta
        return abs(offset - MIN_HORIZON_OFFSET_PX) <= allowed(MIN_HORIZON_OFFSET_PX)

    from gsrwt_cli.geometry.pinhole import pinhole_numbers, pinhole_params_row
    from gsrwt_cli.inputs.records import RecordError, view_from_values
    from gsrwt_cli.tables.rows import params_row

    rng = random.Random(11)
    checked = refused = 0
    compare = PrintedComparison()
    for index in range(20_000):
        values = {"pan": rng.choice([rng.uniform(-89.99, 89.99), 0.0, -0.0, 1e-10, 89.9999]),
                  "tilt": rng.choice([rng.uniform(-89.99, 89.99), 0.0, 2e-9, -89.99999]),
                  "focal": rng.choice([rng.uniform(0.1, 5000), 280.0, 1e-3])}
        kind = index % 4
        if kind in (1, 3):
            values.update(width=rng.randint(1, 8000), height=rng.randint(1, 8000))
        if kind in (2, 3):
            values.update(cx=rng.uniform(-100, 9000), cy=rng.uniform(-100, 9000))
        if index % 7 == 0:
            values["distance"] = rng.uniform(0.01, 100)
        numbers = pinhole_numbers(values, "options")
        assert numbers is not None
        row = pinhole_params_row(numbers)
        try:
            expected = params_row(view_from_values(values, "options"))
        except RecordError:
            assert row is None or near_the_horizon_bound(numbers), values
            refused += 1
            continue
        if row is None:
            assert near_the_horizon_bound(numbers), values
            continue
        assert list(row) == list(expected), values
        for name, value in expected.items():
            compare.values(row[name], value, (name, values))
        checked += 1
    assert checked > 8_000 and refused > 1_000
    compare.assert_few_flips()
    assert pinhole_numbers({"pan": 10, "tilt": 5, "focal": 300, "roll": 2}, "x") is None
    assert pinhole_numbers({"pan": 10, "tilt": 95, "focal": 300}, "x") is None
