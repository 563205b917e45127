"""lensfun's distortion models as the project's :class:`~gsrwt_cli.geometry.lens.Lens`: exact
where OpenCV's plumb_bob model can say the same (poly5, poly3), fitted where it cannot
(ptlens with odd terms), with the fit's residual in pixels. Pure numpy, no lensfun: the
profile's numbers come from :mod:`~gsrwt_cli.inputs.lensfun`.

Convention (lensfun 0.3.4, ``libs/lensfun/modifier.cpp`` and ``mod-coord.cpp``, checked
against lensfunpy's ``Modifier`` to 5e-5 px in ``tests/inputs/test_lensfun.py``):

- Radii are measured from the image centre ``((W-1)/2, (H-1)/2)`` in lensfun's normalised
  unit ``L`` pixels (:func:`lensfun_unit_px`): ``r = 1`` is half the short side of the
  *calibration* sensor (crop factor ``lens_crop``, aspect ratio ``lens_aspect`` >= 1),
  carried to this image through the crop factors: the image's half diagonal in pixels is
  ``21.63 / crop`` mm, so ``L = half_diagonal_px * crop / (lens_crop * sqrt(1 +
  lens_aspect^2))``, with ``half_diagonal_px = hypot(W-1, H-1) / 2``.
- A corrected radius ``r_u`` goes to the photo's radius ``r_d = r_u g(r_u)``:
  ``poly3``: ``g = 1 - k1 + k1 r^2``; ``poly5``: ``g = 1 + k1 r^2 + k2 r^4``;
  ``ptlens``: ``g = a r^3 + b r^2 + c r + d``, ``d = 1 - a - b - c``.

The photo's own focal length (EXIF's, the lens's paraxial one) is what OpenCV's model keeps
(``r_d ~ r`` near the axis), as lensfun's later releases do ("Note about PT-based distortion
models": ``a' = a/d^4, b' = b/d^3, c' = c/d^2``): near the centre ``r_d = d r_u``, so the
corrected radius of a ray seen at paraxial pixel radius ``f r`` is ``r_u = f r / (d L)``
(the focal rescale ``1/d``). With ``u = f r / L`` (``r = tan`` of the angle off axis, OpenCV's
normalised radius):

- poly5 (``d = 1``): ``r_d / r = 1 + k1 u^2 + k2 u^4``: plumb_bob ``k1 (f/L)^2, k2 (f/L)^4``;
- poly3 (``d = 1 - k1``): ``r_d / r = 1 + k1/d^3 u^2``: plumb_bob ``k1/d^3 (f/L)^2``;
- ptlens: ``r_d / r = 1 + c/d^2 u + b/d^3 u^2 + a/d^4 u^3``: odd powers, which OpenCV's
  models (even powers of ``r`` only) do not have, unless ``a = c = 0`` (then it is poly3);
  fitted by least squares to the pixel displacement over the image's radii, plumb_bob or
  rational, whichever is closer (:func:`lens_from_lensfun`), the largest error reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .lens import Lens, monotonic_radius

#: The lensfun distortion models converted.
LENSFUN_MODELS = ("poly3", "poly5", "ptlens")
#: Half the diagonal of a 36 x 24 mm frame, in mm: a crop factor's reference.
HALF_FULL_FRAME_DIAGONAL_MM = math.hypot(36.0, 24.0) / 2
#: The aspect ratio lensfun assumes for a calibration that names none (3:2).
DEFAULT_ASPECT = 1.5
#: Radii sampled for the ptlens fit, uniform from the centre to the image's farthest pixel.
FIT_SAMPLES = 512


class LensfunModelError(ValueError):
    """A lensfun profile that has no usable conversion (an unknown model, ``d <= 0``)."""


@dataclass(frozen=True)
class LensfunConversion:
    """A lensfun profile as a :class:`Lens`: ``exact`` (poly3, poly5) or fitted (ptlens),
    and the fit's largest pixel error over the image's radii (0 when exact)."""

    lens: Lens
    exact: bool
    residual_px: float


def lensfun_unit_px(width: int, height: int, crop: float, lens_crop: float,
                    lens_aspect: float = DEFAULT_ASPECT) -> float:
    """Pixels per lensfun normalised radius unit of a ``width`` x ``height`` image taken by
    a camera of crop factor ``crop`` with a profile calibrated at ``lens_crop`` and aspect
    ratio ``lens_aspect`` (module docstring); the same for the image turned a quarter."""
    if not (width > 0 and height > 0 and crop > 0 and lens_crop > 0 and lens_aspect > 0):
        raise LensfunModelError(f"lensfun needs positive sizes and crop factors, got "
                                f"{width}x{height}, crop {crop:g}, calibration crop "
                                f"{lens_crop:g}, aspect {lens_aspect:g}")
    aspect = max(lens_aspect, 1 / lens_aspect)
    half_diagonal = math.hypot(max(width - 1, 1), max(height - 1, 1)) / 2
    return half_diagonal * crop / (lens_crop * math.sqrt(1 + aspect * aspect))


def _scale(model: str, terms: tuple[float, ...]) -> float:
    """``d``: the profile's magnification at the centre (1 for poly5)."""
    a, b, c = (tuple(terms) + (0.0, 0.0, 0.0))[:3]
    d = {"poly3": 1 - a, "poly5": 1.0, "ptlens": 1 - a - b - c}[model]
    if not d > 0:
        raise LensfunModelError(f"the {model} profile's centre scale 1 - ... is {d:g}, not "
                                "positive")
    return d


def focal_preserving_terms(model: str, terms: tuple[float, ...]) -> tuple[float, ...]:
    """The coefficients of ``r_d / r = 1 + e1 u + e2 u^2 + e3 u^3 + e4 u^4`` (``u = f r /
    L``, module docstring) of a lensfun profile: ``(e1, e2, e3, e4)``."""
    if model not in LENSFUN_MODELS:
        raise LensfunModelError(f"unknown lensfun distortion model {model!r}")
    a, b, c = (tuple(terms) + (0.0, 0.0, 0.0))[:3]
    d = _scale(model, terms)
    if model == "poly5":
        return (0.0, a, 0.0, b)
    if model == "poly3":
        return (0.0, a / d**3, 0.0, 0.0)
    return (c / d**2, b / d**3, a / d**4, 0.0)


def lens_from_lensfun(model: str, terms: tuple[float, ...], focal_px: float, unit_px: float,
                      max_radius_px: float) -> LensfunConversion:
    """A lensfun profile (``model``, its ``terms`` at the photo's focal length: k1 | k1, k2 |
    a, b, c) as a :class:`Lens` of a camera of focal length ``focal_px`` (the photo's
    paraxial one) whose profile unit is ``unit_px`` (:func:`lensfun_unit_px`).

    poly3, poly5 and a ptlens profile without odd terms (``a = c = 0``: poly3 in other
    words) are plumb_bob exactly. Other ptlens profiles are fitted (:func:`_fitted`) over
    the ideal radii from the centre to the one the profile puts at ``max_radius_px`` (the
    image's farthest pixel from the centre, :func:`_ideal_reach`), and ``residual_px`` is
    the fit's largest error there. Raises :class:`LensfunModelError`.
    """
    if not (focal_px > 0 and unit_px > 0 and max_radius_px > 0):
        raise LensfunModelError("the focal length, the profile's unit and the image's radius "
                                "must be positive")
    e1, e2, e3, e4 = focal_preserving_terms(model, terms)
    q = focal_px / unit_px
    if e1 == 0 and e3 == 0:
        coefficients = (("k1", e2 * q**2), ("k2", e4 * q**4))
        return LensfunConversion(Lens("plumb_bob", coefficients), True, 0.0)
    reach = _ideal_reach(e1, e2, e3, q, max_radius_px / focal_px)
    r = np.linspace(0.0, reach, FIT_SAMPLES)
    u = q * r
    ratio = 1 + e1 * u + e2 * u**2 + e3 * u**3  # r_d / r
    return _fitted(r, ratio, focal_px)


def _fitted(r: np.ndarray, ratio: np.ndarray, focal_px: float,
            models: tuple[str, ...] = ("plumb_bob", "rational_polynomial")
            ) -> LensfunConversion:
    """The radial model closest in pixels to ``r_d / r = ratio`` at the ideal radii ``r``:
    plumb_bob ``k1, k2, k3`` by least squares of the pixel displacement, and the rational
    model (``k1, k2, k3`` over ``k4, k5, k6``, linearised least squares: ``num - ratio den =
    0``), which follows an odd term far better (over lensfun's 3923 rectilinear ptlens
    profiles with odd terms on a 6000 x 4000 photo, the largest error's median is 2.1 px for
    plumb_bob, 0.17 px for the rational model). The rational model is taken when it is
    closer, its denominator stays positive and it is one-to-one over the radii
    (:func:`~gsrwt_cli.geometry.lens.monotonic_radius`). ``models``: those tried."""
    s = r * r
    target = focal_px * r * (ratio - 1)  # pixels the lens moves each ray
    candidates = []
    for model, columns in (("plumb_bob", [s, s**2, s**3]),
                           ("rational_polynomial",
                            [s, s**2, s**3, -ratio * s, -ratio * s**2, -ratio * s**3])):
        if model not in models:
            continue
        design = focal_px * r[:, None] * np.column_stack(columns)
        norms = np.linalg.norm(design, axis=0)
        norms[norms == 0] = 1.0
        solution, *_ = np.linalg.lstsq(design / norms, target, rcond=None)
        k = solution / norms
        if model == "plumb_bob":
            names, model_ratio = ("k1", "k2", "k3"), 1 + s * (k[0] + s * (k[1] + s * k[2]))
            vector = (k[0], k[1], 0.0, 0.0, k[2])
        else:
            names = ("k1", "k2", "k3", "k4", "k5", "k6")
            denominator = 1 + s * (k[3] + s * (k[4] + s * k[5]))
            if not np.all(denominator > 0):
                continue
            model_ratio = (1 + s * (k[0] + s * (k[1] + s * k[2]))) / denominator
            vector = (k[0], k[1], 0.0, 0.0, k[2], k[3], k[4], k[5])
        if not all(math.isfinite(value) and abs(value) < 1e6 for value in k):
            continue
        if monotonic_radius(vector) <= r[-1]:
            continue
        residual = float(np.max(np.abs(focal_px * r * (model_ratio - ratio))))
        candidates.append((residual, Lens(model, tuple(zip(names, k.tolist())))))
    if not candidates:
        raise LensfunModelError("no radial model is one-to-one over the image's radii")
    residual, lens = min(candidates, key=lambda candidate: candidate[0])
    return LensfunConversion(lens, False, residual)


def _ideal_reach(e1: float, e2: float, e3: float, q: float, radius: float) -> float:
    """The ideal normalised radius whose ray the profile puts at the photo's normalised
    ``radius`` (``r (1 + e1 u + e2 u^2 + e3 u^3) = radius``, ``u = q r``): the first crossing
    on a fine grid, refined by one secant step; where the profile folds back before it, the
    fold."""
    r = np.linspace(0.0, 4.0 * radius, 4001)
    u = q * r
    distorted = r * (1 + e1 * u + e2 * u**2 + e3 * u**3)
    rising = np.diff(distorted) > 0
    end = int(np.argmin(rising)) if not rising.all() else len(rising)
    beyond = np.nonzero(distorted[: end + 1] >= radius)[0]
    if len(beyond) == 0:
        return float(r[end])
    i = int(beyond[0])
    if i == 0:
        return radius
    low, high = distorted[i - 1], distorted[i]
    return float(r[i - 1] + (radius - low) / (high - low) * (r[i] - r[i - 1]))
