"""How well gsrwt's lens follows lensfun's ptlens profiles, over the whole database
lensfunpy ships (needs the extra ``gsrwt[lenses]``).

For every rectilinear lens's ptlens calibration (each focal length), on a 6000 x 4000 photo
taken at that focal length with the calibration's own crop factor (the focal length in
pixels from the 3:2 sensor's diagonal, 43.27 mm / crop): whether the conversion is exact (no
odd terms), which model the fit chose, its largest pixel error over the image's radii
(:func:`~gsrwt_cli.geometry.lensfun_models.lens_from_lensfun`), and that of plumb_bob alone
for comparison; profiles whose fit folds back inside the image are counted apart.

    python benchmarks/bench_lensfun_fits.py
"""

from __future__ import annotations

import collections
import math
import time

import numpy as np

from gsrwt_cli.geometry.lensfun_models import (
    LensfunModelError,
    _fitted,
    _ideal_reach,
    focal_preserving_terms,
    lens_from_lensfun,
    lensfun_unit_px,
)

WIDTH, HEIGHT = 6000, 4000


def main() -> None:
    import lensfunpy

    database = lensfunpy.Database(load_common=False)
    kinds: collections.Counter[str] = collections.Counter()
    chosen, plumb_bob = [], []
    started = time.perf_counter()
    for lens in database.lenses:
        if lens.type.name != "RECTILINEAR":
            continue
        for calibration in lens.calib_distortion:
            if calibration.model.name != "PTLENS":
                continue
            terms = tuple(calibration.terms[:3])
            focal = calibration.focal / (43.27 / lens.crop_factor) * math.hypot(WIDTH, HEIGHT)
            unit = lensfun_unit_px(WIDTH, HEIGHT, lens.crop_factor, lens.crop_factor, 1.5)
            radius = math.hypot(WIDTH - 1, HEIGHT - 1) / 2
            try:
                conversion = lens_from_lensfun("ptlens", terms, focal, unit, radius)
            except LensfunModelError:
                kinds["not used: the fit folds back inside the image"] += 1
                continue
            if conversion.exact:
                kinds["exact (a = c = 0)"] += 1
                continue
            kinds[f"fitted as {conversion.lens.model}"] += 1
            chosen.append(conversion.residual_px)
            e1, e2, e3, _ = focal_preserving_terms("ptlens", terms)
            q = focal / unit
            r = np.linspace(0.0, _ideal_reach(e1, e2, e3, q, radius / focal), 512)
            u = q * r
            try:  # plumb_bob alone: the rational model's columns left out
                only = _fitted(r, 1 + e1 * u + e2 * u**2 + e3 * u**3, focal, ("plumb_bob",))
                plumb_bob.append(only.residual_px)
            except LensfunModelError:
                pass
    elapsed = time.perf_counter() - started
    total = sum(kinds.values())
    print(f"{total} ptlens calibrations of rectilinear lenses, {WIDTH}x{HEIGHT} photos "
          f"({elapsed / total * 1000:.1f} ms each)")
    for kind, count in kinds.most_common():
        print(f"  {kind}: {count}")
    for name, errors in (("fitted (chosen model)", chosen), ("plumb_bob alone", plumb_bob)):
        errors = np.array(errors)
        print(f"{name}: largest error median {np.median(errors):.2f} px, 90th percentile "
              f"{np.percentile(errors, 90):.2f} px, below 1 px {np.mean(errors < 1):.0%} "
              f"({len(errors)} profiles)")


if __name__ == "__main__":
    main()
