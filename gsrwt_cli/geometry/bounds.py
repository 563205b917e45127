"""The fields of one view and the bounds each value is checked against.

Plain numbers, no numpy: the command line reads them at start-up (its options are made from
:data:`VIEW_FIELDS`), and :mod:`.pinhole` computes one view's ``params`` row with them.
:mod:`.camera` and :mod:`.gsrwt`, which check every value against them, name them too.
"""

from __future__ import annotations

#: The fields a sidecar row or the command line gives for one view, in the tables' order:
#: the pose, then the intrinsics, then the distance.
VIEW_FIELDS = ("pan", "tilt", "roll", "focal", "fx", "fy", "cx", "cy", "skew", "width", "height",
               "distance")

#: |pan| and |tilt| at or below this many degrees count as the frontal view (identity transform).
FRONTAL_TOLERANCE_DEG = 1e-9

#: Focal lengths (fx, fy) must be below this many pixels. The longest real ones are ~1e5-1e6
#: (a 2000 mm lens on 2 um pixels is 1e6); the bound keeps ``f**2`` and ``f / sin(theta)``
#: far from floating-point limits.
MAX_FOCAL_PX = 1e7
#: Image width and height: whole numbers of pixels, at most this many each.
MAX_SIDE_PX = 1_000_000
#: The principal point may lie outside the image (a crop), but within this many pixels of 0.
MAX_PRINCIPAL_POINT_PX = 1e7
#: ``distance`` (``Zc``, in the user's unit) must lie strictly between these. Twelve orders of
#: magnitude either way of any unit (nanometres to terametres, in metres): no wall needs more,
#: and ``Zc``, ``1/Zc`` and their products with focal lengths and scales stay finite.
DISTANCE_RANGE = (1e-12, 1e12)
#: The vanishing line (the horizon of the wall) must pass at least this many pixels from the
#: principal point: ``a = f cos(theta) / sin(theta) >= 0.5`` (Eq. 4.16). Closer, the pixel at
#: the principal point sees the horizon, so the point where the optical axis meets the wall
#: (which anchors the output frame, Fig. 5.7) is beyond what the camera resolves, and the
#: pixel homography, normalized at the principal point, divides by ``w ~ a`` that rounding
#: errors of size ``1e-16 (|cx| + |cy|)`` swamp (pan = tilt = 89.9999999 at f = 300 has
#: ``a = 9e-16`` px). Non-frontal views only.
MIN_HORIZON_OFFSET_PX = 0.5
