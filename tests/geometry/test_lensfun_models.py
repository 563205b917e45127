"""lensfun's distortion models as the project's lens (gsrwt_cli/geometry/lensfun_models.py),
checked against lensfun's formulas written out here from lensfun's own words (``mod-coord.cpp``
of lensfun 0.3.4: ``r_d = r_u g(r_u)`` in its normalised unit), not through the module's
terms. No lensfunpy: the database's numbers are copied below (tests/inputs/test_lensfun.py
checks the normalisation against lensfunpy's own Modifier).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gsrwt_cli.geometry.lens import LensDistortion
from gsrwt_cli.geometry.lensfun_models import (
    LensfunModelError,
    lens_from_lensfun,
    lensfun_unit_px,
)

WIDTH, HEIGHT = 4000, 3000
FOCAL = 3100.0  # pixels
CX, CY = (WIDTH - 1) / 2, (HEIGHT - 1) / 2


def lensfun_distorted_px(model: str, terms: tuple[float, ...], corrected_px: np.ndarray,
                         unit: float) -> np.ndarray:
    """lensfun's forward model: the photo's pixel radius of a corrected pixel radius."""
    r = corrected_px / unit
    if model == "poly3":
        (k1,) = terms
        g = 1 - k1 + k1 * r**2
    elif model == "poly5":
        k1, k2 = terms
        g = 1 + k1 * r**2 + k2 * r**4
    else:
        a, b, c = terms
        g = a * r**3 + b * r**2 + c * r + 1 - a - b - c
    return unit * r * g


def centre_scale(model: str, terms: tuple[float, ...]) -> float:
    """``d``: how much lensfun's formula shrinks the centre (the focal rescale)."""
    return {"poly3": lambda: 1 - terms[0], "poly5": lambda: 1.0,
            "ptlens": lambda: 1 - sum(terms)}[model]()


def lens_radius_px(conversion, radii: np.ndarray) -> np.ndarray:
    """The photo's pixel radius of ideal normalised radii through the converted Lens, as
    the project evaluates it (OpenCV's projectPoints), along a diagonal."""
    lens = conversion.lens
    distortion = LensDistortion(((FOCAL, 0.0, CX), (0.0, FOCAL, CY), (0.0, 0.0, 1.0)),
                                tuple(lens.opencv_coefficients()))
    direction = np.array([0.6, 0.8])
    ideal = np.array([CX, CY]) + FOCAL * radii[:, None] * direction
    distorted = distortion.distort(ideal)
    return np.hypot(distorted[:, 0] - CX, distorted[:, 1] - CY)


def expected_radius_px(model: str, terms: tuple[float, ...], radii: np.ndarray,
                       unit: float) -> np.ndarray:
    """The photo's radius of rays at ideal normalised radii by lensfun's formula: the
    camera's paraxial focal length is the photo's (``r_d ~ d r_u`` at the centre), so the
    corrected radius of a ray at paraxial radius ``FOCAL r`` is ``FOCAL r / d``."""
    return lensfun_distorted_px(model, terms, FOCAL * radii / centre_scale(model, terms), unit)


UNIT = lensfun_unit_px(WIDTH, HEIGHT, 2.0, 2.0, 4 / 3)
RADII = np.linspace(0.0, math.hypot(CX, CY) / FOCAL, 201)


@pytest.mark.parametrize("model, terms", [
    ("poly3", (-0.079,)),  # Olympus M.Zuiko Digital ED 14-42mm at 14 mm
    ("poly3", (0.0216,)),
    ("poly5", (-0.030571632, 0.004658548)),  # Canon PowerShot G12 at 6.1 mm
    ("ptlens", (0.0, -0.0158, 0.0)),  # a ptlens profile without odd terms is poly3
])
def test_exact_conversions_agree_with_lensfuns_formula(model, terms):
    conversion = lens_from_lensfun(model, terms, FOCAL, UNIT, math.hypot(CX, CY))
    assert conversion.exact and conversion.residual_px == 0
    assert conversion.lens.model == "plumb_bob"
    got = lens_radius_px(conversion, RADII) / FOCAL
    expected = expected_radius_px(model, terms, RADII, UNIT) / FOCAL
    assert np.max(np.abs(got - expected)) <= 1e-9, np.max(np.abs(got - expected))
    # Not the same by accident: the lens moves the corner by pixels.
    assert np.max(np.abs(expected - RADII)) * FOCAL > 5


def test_poly3_is_plumb_bob_with_a_focal_rescale():
    """Derived: r_d = L s (1 - k1 + k1 s^2) with s = f r / (d L), d = 1 - k1, is
    f r (1 + k1 / d^3 (f/L)^2 r^2): plumb_bob k1' = k1 (f/L)^2 / (1 - k1)^3."""
    k1 = -0.079
    conversion = lens_from_lensfun("poly3", (k1,), FOCAL, UNIT, 2000.0)
    assert conversion.lens.value("k1") == pytest.approx(k1 * (FOCAL / UNIT) ** 2 / (1 - k1) ** 3,
                                                        rel=1e-12)
    # Without the rescale (the raw formula read as r_d / r) the centre would be off by d.
    raw = lensfun_distorted_px("poly3", (k1,), np.array([1.0]), UNIT)[0]
    assert raw == pytest.approx(1 - k1, rel=1e-6)


# A typical ptlens profile with odd terms (Canon EF-S 18-55mm f/3.5-5.6 IS at 18 mm, crop
# 1.622, lensfun 0.3.4's database as lensfunpy 1.18 ships it): the fit's largest error over
# the image's radii.
TYPICAL_PTLENS = (0.00644, -0.01245, -0.0348)
ODD_PTLENS = (0.02465, -0.089989, 0.111108)  # iPhone XS back camera 4.25mm: a strong c


@pytest.mark.parametrize("terms, below_px", [(TYPICAL_PTLENS, 1.0), (ODD_PTLENS, 5.0)])
def test_ptlens_is_fitted_and_its_residual_is_what_it_reports(terms, below_px):
    unit = lensfun_unit_px(WIDTH, HEIGHT, 1.622, 1.622, 1.5)
    conversion = lens_from_lensfun("ptlens", terms, FOCAL, unit, math.hypot(CX, CY))
    assert not conversion.exact
    # The largest error, measured here over the rays that land in the image.
    radii = np.linspace(0.0, 1.0, 4001)
    expected = expected_radius_px("ptlens", terms, radii, unit)
    inside = expected <= math.hypot(CX, CY)
    error = np.abs(lens_radius_px(conversion, radii) - expected)[inside]
    assert np.max(error) == pytest.approx(conversion.residual_px, rel=0.05, abs=0.01)
    assert conversion.residual_px < below_px, conversion.residual_px
    assert np.max(np.abs(expected - radii * FOCAL)[inside]) > 20  # a lens worth correcting


def test_the_unit_follows_lensfuns_crop_factors_and_aspect_ratio():
    # r = 1 is half the short side of the calibration sensor: for the same sensor (crop and
    # aspect), half the image's short side (between pixel centres).
    assert lensfun_unit_px(4001, 3001, 2.0, 2.0, 4 / 3) == pytest.approx(1500.0, rel=1e-12)
    assert lensfun_unit_px(3001, 4001, 2.0, 2.0, 4 / 3) == pytest.approx(1500.0, rel=1e-12)
    # A calibration made on a smaller sensor (larger crop) covers fewer of this image's pixels.
    assert lensfun_unit_px(4001, 3001, 1.0, 2.0, 4 / 3) == pytest.approx(750.0, rel=1e-12)
    # A 3:2 calibration's half short side is a smaller part of its diagonal than a 4:3's.
    assert lensfun_unit_px(4001, 3001, 2.0, 2.0, 1.5) == pytest.approx(
        2500 / math.sqrt(1 + 1.5**2), rel=1e-12)


def test_unusable_profiles_are_refused():
    with pytest.raises(LensfunModelError):
        lens_from_lensfun("poly3", (1.0,), FOCAL, UNIT, 2000.0)  # d = 0
    with pytest.raises(LensfunModelError):
        lens_from_lensfun("acm", (0.1,), FOCAL, UNIT, 2000.0)
    with pytest.raises(LensfunModelError):
        lensfun_unit_px(0, 10, 1.0, 1.0)
