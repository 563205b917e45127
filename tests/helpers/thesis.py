"""The thesis's tables, as printed: the reference values of the GS-RWT's parameters."""

from __future__ import annotations

#: Table 5.1 (images a-d), f = 280: pan, tilt, delta, the vanishing point printed as (y, x),
#: a, gamma.
TABLE_5_1 = [
    (0, 30, 0, (0, 485), 485, 0),
    (15, 30, 28, (-201, 376), 427, -24),
    (30, 15, 66, (-390, 174), 427, -61),
    (30, 30, 49, (-240, 207), 317, -41),
]
#: Fig. 5.2, the over-decompressed view, f = 280: pan, tilt, the vanishing point (y, x), a.
FIG_5_2 = (45, 30, (-193, 96), 217)
#: Table 5.2: pan, tilt, theta, foreshortening ("Jacobian determinant").
TABLE_5_2 = [(53, 13, 54.10, 0.59), (40, 15, 42.27, 0.74), (29, 18, 33.71, 0.83)]
