"""EXIF orientation as geometry: how the pixels a camera stored become the photo as displayed,
and the camera of the displayed photo (pure: numbers in, numbers out).

EXIF's ``Orientation`` tag (0x0112) says how to turn or mirror the stored pixels so that the
photo shows upright (as every viewer, darktable, RawTherapee and ImageMagick's
``-auto-orient`` do it). For a stored image ``W x H`` and a stored pixel ``(u, v)`` (col,
row), the displayed pixel is:

==  ===============================  ===================  ==========
1   as stored                        ``(u, v)``           ``W x H``
2   mirrored left-right              ``(W-1-u, v)``       ``W x H``
3   turned 180 degrees               ``(W-1-u, H-1-v)``   ``W x H``
4   mirrored top-bottom              ``(u, H-1-v)``       ``W x H``
5   transposed (main diagonal)       ``(v, u)``           ``H x W``
6   turned 90 degrees clockwise      ``(H-1-v, u)``       ``H x W``
7   transversed (other diagonal)     ``(H-1-v, W-1-u)``   ``H x W``
8   turned 90 degrees anticlockwise  ``(v, W-1-u)``       ``H x W``
==  ===============================  ===================  ==========

Any other value (0, 9, text, a damaged tag) means 1, as most viewers read it
(:func:`valid_orientation`).

A calibration file describes the sensor (the stored pixels); :func:`displayed_intrinsics`
gives the camera of the displayed photo: ``K' = A K L3^-1`` where ``A`` is the table's pixel
map (:func:`displayed_from_stored`) and ``L3`` the same signed permutation acting on the
camera's ``x, y`` axes, so that ``fx, fy`` swap for 5-8, ``cx, cy`` move as a pixel does, and
the lens's non-radial terms (tangential ``p1, p2``, thin prism ``s1..s4``) turn with the image;
radial terms (``k1..k6``, the fisheye model's) do not change.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .camera import Intrinsics, View
from .checks import ViewError
from .lens import LENS_MODELS, Lens

#: The EXIF ``Orientation`` tag.
ORIENTATION_TAG = 0x0112
#: The orientations EXIF defines; 1 is upright.
ORIENTATIONS = (1, 2, 3, 4, 5, 6, 7, 8)

# Each orientation as (swap, flip_x, flip_y): the stored (u, v) are swapped first (5-8), then
# the displayed column and/or row counted from the other side.
_STEPS = {
    1: (False, False, False), 2: (False, True, False), 3: (False, True, True),
    4: (False, False, True), 5: (True, False, False), 6: (True, True, False),
    7: (True, True, True), 8: (True, False, True),
}


def valid_orientation(value: object) -> int:
    """The orientation an EXIF ``Orientation`` value stands for: 1-8 as they are; anything
    else (missing, 0, 9, text, a tuple, a bool) is 1, as most viewers treat it."""
    if isinstance(value, tuple) and len(value) == 1:
        value = value[0]
    if isinstance(value, bool) or not isinstance(value, int):
        return 1
    return value if value in _STEPS else 1


def orientation_steps(orientation: int) -> tuple[bool, bool, bool]:
    """``(swap, flip_x, flip_y)`` of an orientation: the stored ``(u, v)`` swapped first
    (5-8), then the displayed column and/or row counted from the other side."""
    return _STEPS[orientation]


def swaps_sides(orientation: int) -> bool:
    """Whether the displayed photo is the stored one turned a quarter (5-8: ``W x H`` becomes
    ``H x W``)."""
    return _STEPS[orientation][0]


def displayed_size(orientation: int, width: int, height: int) -> tuple[int, int]:
    """The displayed photo's ``(width, height)`` of a stored ``width x height`` image."""
    return (height, width) if swaps_sides(orientation) else (width, height)


def displayed_from_stored(orientation: int, width: int, height: int) -> np.ndarray:
    """The 3x3 matrix ``A`` taking a stored pixel ``(u, v, 1)`` of a ``width x height`` image
    to the displayed pixel (the module's table): a signed permutation and a shift."""
    swap, flip_x, flip_y = _STEPS[orientation]
    out_width, out_height = displayed_size(orientation, width, height)
    matrix = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) if swap else np.eye(3)
    mirror = np.eye(3)
    if flip_x:
        mirror[0, 0], mirror[0, 2] = -1.0, out_width - 1.0
    if flip_y:
        mirror[1, 1], mirror[1, 2] = -1.0, out_height - 1.0
    return mirror @ matrix


def _displayed_lens(lens: Lens, swap: bool, flip_x: bool, flip_y: bool) -> Lens:
    """The lens seen in displayed pixels: ``L o D o L^-1`` for the lens's distortion ``D`` of
    normalized coordinates (OpenCV's model). Swapping ``x, y`` swaps ``p1, p2`` and the prism
    pairs ``(s1, s2), (s3, s4)``; mirroring ``x`` negates ``p2, s1, s2``, mirroring ``y``
    negates ``p1, s3, s4``. The tilted-sensor terms have no such form: refused if not 0."""
    values = dict(lens.coefficients)
    if values.get("tau_x", 0.0) or values.get("tau_y", 0.0):
        raise ViewError("tau_x", "a tilted-sensor lens (tau_x, tau_y) cannot be turned with "
                        "the photo's EXIF orientation; use --orientation ignore")
    if lens.is_fisheye:
        return lens  # radial only
    if swap:
        for first, second in (("p1", "p2"), ("s1", "s3"), ("s2", "s4")):
            values[first], values[second] = values.get(second, 0.0), values.get(first, 0.0)
    for flipped, names in ((flip_x, ("p2", "s1", "s2")), (flip_y, ("p1", "s3", "s4"))):
        if flipped:
            for name in names:
                values[name] = -values.get(name, 0.0)
    allowed = LENS_MODELS[lens.model]
    return Lens(lens.model, tuple((name, value) for name, value in values.items()
                                  if name in allowed and value))


def displayed_intrinsics(intrinsics: Intrinsics, orientation: int,
                         stored_size: tuple[int, int] | None = None) -> Intrinsics:
    """The camera of the displayed photo from the camera of its stored pixels (a calibration
    file's): ``K' = A K L3^-1`` (module docstring), the size and the lens turned with it.

    ``stored_size``: the stored image's ``(width, height)`` if the intrinsics carry none (the
    shift of ``A`` needs it). Raises :class:`ViewError` for what has no displayed form: a
    skewed camera turned a quarter, a tilted-sensor lens, an unknown size or principal point.
    """
    if orientation == 1:
        return intrinsics
    swap, flip_x, flip_y = _STEPS[orientation]
    width, height = ((intrinsics.width, intrinsics.height)
                     if intrinsics.width is not None and intrinsics.height is not None
                     else stored_size or (None, None))
    if width is None or height is None or intrinsics.cx is None or intrinsics.cy is None:
        raise ViewError("width", "the image size is needed to turn a camera with the photo's "
                        "EXIF orientation")
    if swap and intrinsics.skew:
        raise ViewError("skew", "a skewed camera cannot be turned a quarter with the photo's "
                        "EXIF orientation; use --orientation ignore")
    a = displayed_from_stored(orientation, width, height)
    cx, cy, _ = a @ np.array([intrinsics.cx, intrinsics.cy, 1.0])
    fx, fy = (intrinsics.fy, intrinsics.fx) if swap else (intrinsics.fx, intrinsics.fy)
    # The skew's sign follows the product of the axes' signs (K's upper-right entry).
    skew = intrinsics.skew * (-1.0 if flip_x != flip_y else 1.0)
    out_width, out_height = displayed_size(orientation, width, height)
    lens = (None if intrinsics.lens is None
            else _displayed_lens(intrinsics.lens, swap, flip_x, flip_y))
    has_size = intrinsics.width is not None
    return replace(intrinsics, fx=fx, fy=fy, cx=float(cx), cy=float(cy), skew=skew,
                   width=out_width if has_size else None,
                   height=out_height if has_size else None, lens=lens)


def displayed_view(view: View, orientation: int,
                   stored_size: tuple[int, int] | None = None) -> View:
    """``view`` with its intrinsics turned by :func:`displayed_intrinsics` (pose unchanged:
    the pose was given for the displayed photo)."""
    if orientation == 1:
        return view
    return replace(view, intrinsics=displayed_intrinsics(view.intrinsics, orientation,
                                                          stored_size))
