"""The output frame: where the canonical view lands in output pixels (Sec. 5.1,
Fig. 5.7; docs/CONVENTIONS.md, "The output image").

Composes the GS-RWT (in the image frame) with the pixel frames of the input and the output
into one 3x3 homography, output pixel from input pixel, that an OpenCV warp applies in one pass.
Pure geometry: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .camera import View
from .gsrwt import Matrix, local_stretch, map_points
from .lens import LensDistortion
from .pixelmap import PixelMap
from .rotations import opencv_from_world_from_camera, rotation_from_pose


def canonical_from_pixel(view: View) -> Matrix:
    """Input pixel ``(col, row)`` to canonical coordinates ``(U, V)`` at frontal resolution.

    ``(U, V) = (f / sin theta) * GS-RWT(x, y)`` (Eq. 4.22 scaled by ``f / sin theta``): the
    wall seen frontally, turned by 180 degrees (the negative scale of Eq. 4.25) and shifted.
    """
    return view.parameters.canonical_from_image() @ view.image_from_pixel()


def optical_axis_canonical(view: View) -> np.ndarray:
    """``(U, V)`` where the optical axis meets the wall (the image of the principal point)."""
    return map_points(view.parameters.canonical_from_image(), [[0.0, 0.0]])[0]


def upright_from_canonical(
    view: View, scale: float = 1.0, anchor: tuple[float, float] | None = None
) -> Matrix:
    """Canonical ``(U, V)`` to upright output pixels ``(col, row)``.

    The canonical view is turned by 180 degrees, so output columns run along ``-V`` and rows
    along ``+U`` (Eq. 4.25). ``scale`` output pixels per frontal pixel. The optical-axis
    point lands on ``anchor`` (default: the input's principal point, so that pan = tilt = 0
    is the identity), as in the thesis's bounding box of Fig. 5.7.
    """
    u0, v0 = optical_axis_canonical(view)
    col0, row0 = anchor if anchor is not None else (view.cx, view.cy)
    return np.array(
        [[0.0, -scale, scale * v0 + col0], [scale, 0.0, -scale * u0 + row0], [0.0, 0.0, 1.0]]
    )


def output_from_input(
    view: View, scale: float = 1.0, anchor: tuple[float, float] | None = None
) -> Matrix:
    """The pixel homography: input ``(col, row)`` to the upright canonical view's ``(col, row)``.

    One output pixel is ``Zc / (f * scale)`` wall units; the optical-axis point lands on
    ``anchor`` (default: the principal point). Normalized so that ``w = 1`` at the principal
    point; ``w > 0`` on the visible side of the vanishing line and ``w = 0`` on it.
    Near the frontal view the composition cancels terms of size ``f / sin theta``: the
    result is good to about ``1e-16 f / sin theta`` pixels (1e-6 px at 1e-6 degrees).
    """
    homography = upright_from_canonical(view, scale, anchor) @ canonical_from_pixel(view)
    principal_w = homography[2] @ np.array([view.cx, view.cy, 1.0])
    return homography / principal_w


# --------------------------------------------------------------------------------------------
# Output frames: which rectangle of the canonical view becomes the output image
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Frame:
    """A rectangle of the default frame and a resolution.

    ``x0, y0, x1, y1`` are pixel-edge coordinates of the default frame (frontal resolution,
    the optical-axis point on the principal point): its pixel ``(col, row)`` covers
    ``[col, col + 1) x [row, row + 1)``, so the default frame of a ``W x H`` image is
    ``(0, 0, W, H)``. ``scale`` output pixels per frontal pixel.
    """

    x0: float
    y0: float
    x1: float
    y1: float
    scale: float = 1.0

    @property
    def size(self) -> tuple[int, int]:
        """Output ``(width, height)`` in pixels; ``ValueError`` if it is not a finite size."""
        return (
            _whole_pixels(self.scale * (self.x1 - self.x0)),
            _whole_pixels(self.scale * (self.y1 - self.y0)),
        )

    def output_from_default(self) -> Matrix:
        """Default-frame pixel centres to output pixel centres."""
        k = self.scale
        return np.array(
            [[k, 0.0, k * (0.5 - self.x0) - 0.5], [0.0, k, k * (0.5 - self.y0) - 0.5], [0, 0, 1]]
        )


#: Output sides beyond this many pixels are refused before any size arithmetic overflows.
MAX_SIDE = 1 << 30


def _whole_pixels(length: float) -> int:
    if not math.isfinite(length) or length > MAX_SIDE:
        raise ValueError(
            f"the output would be {length:.3g} pixels across, more than any image can be; "
            "check the scale, the bounding box and the distance"
        )
    return max(0, round(length))


def fit_frame(frame: Frame, max_size: tuple[int, int]) -> Frame:
    """``frame`` with its scale lowered (never raised) so that its size fits ``max_size``."""
    span_x, span_y = frame.x1 - frame.x0, frame.y1 - frame.y0
    fits = min(max_size[0] / span_x, max_size[1] / span_y) if span_x > 0 and span_y > 0 else 0
    if not math.isfinite(fits) or frame.scale <= fits:
        return frame
    scale = fits
    while _whole_pixels(scale * span_x) > max_size[0] or _whole_pixels(scale * span_y) > (
            max_size[1]):
        scale = math.nextafter(scale, 0)  # rounding to whole pixels must not overshoot
    return Frame(frame.x0, frame.y0, frame.x1, frame.y1, scale)


def fit_area(frame: Frame, max_pixels: float) -> Frame:
    """``frame`` with its scale lowered (never raised) so that it has at most ``max_pixels``
    whole pixels (its shape kept)."""
    span_x, span_y = frame.x1 - frame.x0, frame.y1 - frame.y0
    area = _whole_pixels(frame.scale * span_x) * _whole_pixels(frame.scale * span_y)
    if area <= max_pixels or span_x <= 0 or span_y <= 0:
        return frame
    scale = math.sqrt(max_pixels / (span_x * span_y))
    while _whole_pixels(scale * span_x) * _whole_pixels(scale * span_y) > max_pixels:
        scale *= 1 - 1e-4  # rounding to whole pixels must not overshoot
    return Frame(frame.x0, frame.y0, frame.x1, frame.y1, scale)


def corners_frame(view: View, corners: np.ndarray, margin_percent: float = 0.0,
                  scale: float = 1.0) -> Frame:
    """The frame of a rectangle's four corners (input pixels, ``--bbox corners``): their
    bounding box in the default frame, widened by ``margin_percent`` of its width and height
    on each side, at the resolution that keeps the rectangle's pixels (no side of it has
    fewer output pixels than it had input pixels) times ``scale``.

    With the pose the corners gave (``--fit both``) the rectangle is upright in the output,
    so its corners land on the frame's axis-aligned rectangle.
    """
    corners = np.asarray(corners, dtype=np.float64).reshape(4, 2)
    frontal = map_points(output_from_input(view),
                         view.intrinsics.ideal_pixels(corners)) + 0.5  # centres to edges
    if not np.all(np.isfinite(frontal)):
        raise ValueError("a corner of --bbox corners is beyond the horizon")
    x0, y0 = frontal.min(axis=0)
    x1, y1 = frontal.max(axis=0)
    pad_x, pad_y = margin_percent / 100 * (x1 - x0), margin_percent / 100 * (y1 - y0)
    input_sides = np.linalg.norm(np.roll(corners, -1, axis=0) - corners, axis=1)
    frontal_sides = np.linalg.norm(np.roll(frontal, -1, axis=0) - frontal, axis=1)
    keeps = float(np.max(input_sides / np.maximum(frontal_sides, 1e-12)))
    return Frame(float(x0 - pad_x), float(y0 - pad_y), float(x1 + pad_x), float(y1 + pad_y),
                 scale * keeps)


def default_frame(view: View, scale: float = 1.0) -> Frame:
    """The thesis's bounding box (Fig. 5.7): the input's size at frontal resolution."""
    return Frame(0.0, 0.0, float(view.width), float(view.height), scale)


def wall_foot_canonical(view: View) -> np.ndarray:
    """``(U, V)`` of the wall point straight ahead of the camera's centre (where the optical
    axis of pan = tilt = 0 meets the wall) in this view's canonical coordinates.

    Canonical coordinates of one view and another differ by a shift (Eq. 4.22's shift
    depends on the pose); less this point's, they are the wall's own, ``f / Zc`` per wall
    unit, the same in every view of one focal length (checked against an independent
    camera in the tests).
    """
    # The wall's normal seen from the camera without its roll: (Rx(pan) Ry(tilt))^T z.
    direction = rotation_from_pose(view.pan, view.tilt).T @ np.array([0.0, 0.0, 1.0])
    image = view.focal * direction[:2] / direction[2]
    return map_points(view.parameters.canonical_from_image(), [image])[0]


def steady_box(view: View, first: View) -> tuple[float, float, float, float]:
    """The box of ``view``'s default frame (``X0, Y0, X1, Y1``, default-frame pixel edges)
    that shows the wall ``first``'s default frame shows: a video whose frames are all framed
    so keeps the wall still (``rectify --steady``), when the focal length stays the same.

    A default-frame pixel ``(col, row)`` shows canonical ``U = row - cy + u0``,
    ``V = v0 - (col - cx)`` (``u0, v0`` the optical axis' point); the same wall point is at
    canonical ``U - F1 + Fv`` in the other view (``F``: :func:`wall_foot_canonical`).
    """
    u1, v1 = optical_axis_canonical(first)
    uv, vv = optical_axis_canonical(view)
    f1, fv = wall_foot_canonical(first), wall_foot_canonical(view)
    dcol = (view.cx - first.cx) + (vv - fv[1]) - (v1 - f1[1])
    drow = (view.cy - first.cy) + (fv[0] - uv) - (f1[0] - u1)
    return (float(dcol), float(drow), float(dcol + first.width), float(drow + first.height))


def full_frame(
    view: View, max_stretch: float = 4.0, scale: float = 1.0, samples: int = 513
) -> Frame:
    """The whole visible wall: the forward-mapped image, cut where it over-magnifies.

    Takes the input pixels on the visible side of the vanishing line whose local stretch
    (:func:`local_stretch`) is at most ``max_stretch`` times the stretch at the principal
    point, maps them forward and bounds them (the remedy of Fig. 5.2-5.3). Sampled on a
    ``samples x samples`` grid over the image, borders included.
    """
    homography = output_from_input(view)
    cols = np.linspace(-0.5, view.width - 0.5, samples)
    rows = np.linspace(-0.5, view.height - 0.5, samples)
    grid = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
    lens = view.intrinsics.distortion()
    if lens is not None:  # the distorted image's pixels, as a pinhole would have seen them
        grid = lens.undistort(grid)  # NaN where no ray within the lens's limit reaches
        grid = grid[np.all(np.isfinite(grid), axis=1)]
        if len(grid) == 0:
            raise BeyondLensLimitError(lens)
    w = grid @ homography[2, :2] + homography[2, 2]
    visible = grid[w > 1e-12]
    reference = local_stretch(homography, np.array([[view.cx, view.cy]]))[0]
    keep = visible[local_stretch(homography, visible) <= max_stretch * reference]
    if len(keep) == 0:
        raise NothingWithinStretchError(max_stretch, NothingWithinStretchError.OVER_STRETCHED
                                        if len(visible) else
                                        NothingWithinStretchError.BEYOND_HORIZON)
    mapped = map_points(homography, keep)
    low = np.floor(mapped.min(axis=0) + 0.5)
    high = np.ceil(mapped.max(axis=0) + 0.5)
    return Frame(float(low[0]), float(low[1]), float(high[0]), float(high[1]), scale)


def crop_frame(
    view: View, max_stretch: float = 4.0, scale: float = 1.0, cells: int = 160,
    aspect: float | None = None,
) -> Frame:
    """The largest axis-aligned rectangle of the visible wall with no fill in it (auto-crop);
    with ``aspect`` (width over height), the largest of that shape (darktable's "original
    format" with the photo's own), centred in the run of cells it fits in.

    Within :func:`full_frame`'s extent, a lattice of ``cells + 1`` points a side is mapped
    back to the input: a point counts if it lands inside the image (through the lens, if
    any), in front of the horizon and within ``max_stretch``. A cell counts if its four
    corners do (for a convex visible region the cell is then inside it). The largest
    rectangle of counted cells is found for every pair of top and bottom rows at once:
    columns valid over the rows by prefix sums, the longest run of them by a running
    maximum, all in numpy.
    """
    full = full_frame(view, max_stretch, 1.0)
    xs = np.linspace(full.x0, full.x1, cells + 1)
    ys = np.linspace(full.y0, full.y1, cells + 1)
    lattice = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    homography = output_from_input(view)
    input_from_output = np.linalg.inv(homography)
    centres = lattice - 0.5  # pixel edges to the default frame's pixel centres
    ideal = map_points(input_from_output, centres)
    w = centres @ input_from_output[2, :2] + input_from_output[2, 2]
    lens = view.intrinsics.distortion()
    sources = ideal if lens is None else lens.distort(ideal)
    with np.errstate(invalid="ignore"):
        good = (w > 0) & np.all(np.isfinite(sources), axis=1)
        # Between the outer pixel centres, where interpolation needs no pixel outside.
        good &= (sources[:, 0] >= 0) & (sources[:, 0] <= view.width - 1)
        good &= (sources[:, 1] >= 0) & (sources[:, 1] <= view.height - 1)
        reference = local_stretch(homography, np.array([[view.cx, view.cy]]))[0]
        good &= local_stretch(homography, np.nan_to_num(ideal)) <= max_stretch * reference
    corners = good.reshape(cells + 1, cells + 1)
    valid = corners[:-1, :-1] & corners[1:, :-1] & corners[:-1, 1:] & corners[1:, 1:]
    cell_x, cell_y = (full.x1 - full.x0) / cells, (full.y1 - full.y0) / cells
    if aspect is not None:
        return _largest_of_aspect(valid, aspect, full, cell_x, cell_y, max_stretch, scale)
    top, bottom, left, right = _largest_rectangle(valid)
    if bottom <= top:
        raise NothingWithinStretchError(max_stretch, NothingWithinStretchError.NO_RECTANGLE)
    return Frame(full.x0 + left * cell_x, full.y0 + top * cell_y, full.x0 + right * cell_x,
                 full.y0 + bottom * cell_y, scale)


def _largest_of_aspect(valid: np.ndarray, aspect: float, full: Frame, cell_x: float,
                       cell_y: float, max_stretch: float, scale: float) -> Frame:
    """The tallest rectangle of width over height ``aspect`` (in default-frame pixels) whose
    cells are all valid: for each height in cells, the widest run of fully valid columns
    over any ``height`` rows (as :func:`_largest_rectangle`) against the width that height
    needs; the rectangle centred in its run, its height kept to the cells, its width exact."""
    rows, cols = valid.shape
    prefix = np.concatenate([np.zeros((1, cols), int), np.cumsum(valid, axis=0)])
    index = np.arange(cols)
    found = None
    for height in range(1, rows + 1):
        needed = aspect * height * cell_y / cell_x  # columns, as a fraction
        if needed > cols:
            break
        tops = np.arange(rows - height + 1)
        full_columns = (prefix[tops + height] - prefix[tops]) == height
        last_gap = np.maximum.accumulate(np.where(full_columns, -1, index), axis=1)
        runs = index - last_gap
        row = int(np.argmax(runs.max(axis=1)))
        if runs[row].max() < needed:
            break  # a taller one would hold one this tall: none does
        end = int(np.argmax(runs[row])) + 1
        found = (int(tops[row]), height, end - int(runs[row].max()), end)
    if found is None:
        raise NothingWithinStretchError(max_stretch, NothingWithinStretchError.NO_RECTANGLE)
    top, height, left, right = found
    width = aspect * height * cell_y  # default-frame pixels
    middle = full.x0 + (left + right) / 2 * cell_x
    y0 = full.y0 + top * cell_y
    return Frame(middle - width / 2, y0, middle + width / 2, y0 + height * cell_y, scale)


def _largest_rectangle(valid: np.ndarray) -> tuple[int, int, int, int]:
    """``(top, bottom, left, right)`` (ends exclusive) of the largest all-True rectangle of a
    boolean grid; all zeros if there is none."""
    rows, cols = valid.shape
    prefix = np.concatenate([np.zeros((1, cols), int), np.cumsum(valid, axis=0)])
    best, where = 0, (0, 0, 0, 0)
    index = np.arange(cols)
    for height in range(1, rows + 1):  # one vectorized pass per rectangle height
        tops = np.arange(rows - height + 1)
        full_columns = (prefix[tops + height] - prefix[tops]) == height  # (tops, cols)
        last_gap = np.maximum.accumulate(np.where(full_columns, -1, index), axis=1)
        runs = index - last_gap  # length of the run of full columns ending at each column
        run = runs.max(axis=1)
        row = int(np.argmax(run))
        if run[row] * height > best:
            end = int(np.argmax(runs[row])) + 1
            best = int(run[row]) * height
            where = (int(tops[row]), int(tops[row]) + height, end - int(run[row]), end)
    return where


class OutputTooLargeError(ValueError):
    """The output frame has more pixels than allowed: ``width x height`` above ``limit``."""

    def __init__(self, width: int, height: int, limit: float) -> None:
        self.width, self.height, self.limit = width, height, limit
        super().__init__(
            f"the output would be {width}x{height} = {width * height / 1e6:.1f} megapixels, "
            f"above the limit of {limit / 1e6:g} megapixels"
        )


class EmptyOutputError(ValueError):
    """The output frame is less than a pixel across: ``width x height`` has a 0."""

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = width, height
        super().__init__(f"the output would be empty ({width}x{height} pixels)")


class NothingWithinStretchError(ValueError):
    """Nothing to frame within ``max_stretch`` (:func:`full_frame`, :func:`crop_frame`), for
    ``reason``: one of :data:`BEYOND_HORIZON` (no pixel is in front of the vanishing line),
    :data:`OVER_STRETCHED` (every pixel in front of it is magnified more than ``max_stretch``
    times as much as the principal point: a frontal view, magnified alike everywhere, when
    ``max_stretch`` is below 1) or :data:`NO_RECTANGLE` (what is within it holds no
    rectangle without fill)."""

    BEYOND_HORIZON = "the vanishing line covers it"
    OVER_STRETCHED = ("every visible pixel is magnified more than {max_stretch:g} times as much "
                      "as the principal point")
    NO_RECTANGLE = "what is within it holds no rectangle without fill"

    def __init__(self, max_stretch: float, reason: str) -> None:
        self.max_stretch, self.reason = max_stretch, reason
        super().__init__(f"no part of the image is within a stretch of {max_stretch:g} "
                         f"({reason.format(max_stretch=max_stretch)})")


class FrameOutsideImageError(ValueError):
    """No pixel of the output frame has a source in the image: the frame lies where the
    image does not see the wall (beside it, or beyond its horizon). Every output pixel would
    be fill. ``bbox``: the frame asked for (``frontal``, ``full``, ``crop`` or ``box``);
    ``beyond_horizon``: the whole image lies beyond the wall's horizon (no frame sees it)."""

    def __init__(self, bbox: str, beyond_horizon: bool = False) -> None:
        self.bbox, self.beyond_horizon = bbox, beyond_horizon
        where = ("the whole image lies beyond the wall's horizon" if beyond_horizon else
                 "the frame lies where the image does not see the wall")
        super().__init__(f"no pixel of the output (--bbox {bbox}) has a source in the image: "
                         f"{where}")


class BeyondLensLimitError(ValueError):
    """All the output lies beyond the radius where the lens model folds back
    (:attr:`~gsrwt_cli.geometry.lens.LensDistortion.limit`): nothing in it has a source."""

    def __init__(self, lens: LensDistortion) -> None:
        angle = math.degrees(math.atan(lens.limit))
        super().__init__(
            f"the lens model folds back {angle:.1f} degrees off axis ({lens.limit_px:.0f} "
            "pixels from the principal point: its distortion stops growing there) and all "
            "of the output lies beyond that"
        )


def sees_within_lens_limit(pixel_map: PixelMap, samples: int = 65) -> bool:
    """Whether any of the output sees a ray within its lens's limit, in front of the
    horizon: the optical axis in the frame, or one of ``samples x samples`` output points."""
    lens = pixel_map.lens
    if lens is None or math.isinf(lens.limit):
        return True
    width, height = pixel_map.size
    homography = np.asarray(pixel_map.output_from_input, dtype=np.float64)
    cx, cy = lens.camera_matrix[0][2], lens.camera_matrix[1][2]
    axis = homography @ np.array([cx, cy, 1.0])
    if axis[2] > 0 and -0.5 <= axis[0] / axis[2] <= width - 0.5 and (
            -0.5 <= axis[1] / axis[2] <= height - 0.5):
        return True
    cols = np.linspace(-0.5, width - 0.5, samples)
    rows = np.linspace(-0.5, height - 0.5, samples)
    outputs = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
    input_from_output = np.linalg.inv(homography)
    w = outputs @ input_from_output[2, :2] + input_from_output[2, 2]
    ideal = map_points(input_from_output, outputs)
    return bool(np.any((w > 0) & lens.within(ideal)))


@dataclass(frozen=True)
class Plan:
    """What is done to one image: the view (with its size), the output frame, and the pixel
    map from input to output pixels."""

    view: View
    frame: Frame
    pixel_map: PixelMap

    @property
    def size(self) -> tuple[int, int]:
        """Output ``(width, height)``."""
        return self.pixel_map.size

    @property
    def homography(self) -> Matrix:
        """``output (col, row, 1) ~ homography @ input (col, row, 1)``."""
        return self.pixel_map.output_from_input

    def output_camera(self) -> tuple[Matrix, Matrix]:
        """The camera that would see the output as a photo: ``(K, camera_from_wall)``.

        Convention: ``K`` upper triangular with a positive diagonal and ``K[2, 2] = 1``
        (OpenCV's camera matrix, output pixels); ``camera_from_wall`` the rotation from the
        OpenCV wall frame (x right, y down, z into the wall) to that camera's optical frame,
        the identity for a frontal view. The output pixel of a wall direction ``d`` is
        ``K @ camera_from_wall @ d``, since ``output ~ H @ K_in @ R_in @ d`` (``H`` the
        homography on ideal input pixels, ``R_in`` the input's ``camera_from_wall``): the RQ
        decomposition of ``H @ K_in @ R_in``. A bag output's ``camera_info`` is ``K``.
        """
        view = self.view
        pose = view.pose
        camera_from_wall = opencv_from_world_from_camera(
            rotation_from_pose(pose.pan, pose.tilt, pose.roll))
        m = np.asarray(self.homography, dtype=np.float64) @ view.intrinsics.matrix() @ (
            camera_from_wall)
        if np.linalg.det(m) < 0:  # a homography's scale may be negative
            m = -m
        k, r = _rq(m)
        return k / k[2, 2], r


@dataclass(frozen=True)
class Framing:
    """Everything chosen about the output's rectangle and size, passed whole (thesis
    Fig. 5.7 and the remedies of Fig. 5.2-5.3).

    ``bbox``: ``"frontal"`` (the default frame: the input's size at frontal resolution,
    centred where the optical axis meets the wall), ``"full"`` (:func:`full_frame`),
    ``"crop"`` (:func:`crop_frame`), ``"corners"`` (:func:`corners_frame` of ``corners``,
    the image's rectangle in input pixels, widened by ``margin`` percent) or an explicit
    ``(x0, y0, x1, y1)`` in default-frame pixel edges. ``scale``: output pixels per frontal
    pixel, or ``px_per_unit``: output pixels per unit of the wall's distance (needs the
    view's ``distance``). ``max_stretch``: how much more than the principal point a pixel
    may be magnified (full, crop). ``margin`` and ``corners``: of ``"corners"``.
    ``max_pixels``: the largest output, in pixels. ``max_size``: ``(width, height)`` the
    output must fit in; a larger frame is kept but its scale lowered until it fits.
    ``crop_aspect``: the shape of ``"crop"``'s rectangle. ``max_area``: the most output
    pixels per input pixel (None: no limit); a frame with more keeps its shape and its scale
    is lowered until it has no more (:func:`fit_area`).
    """

    bbox: str | tuple[float, float, float, float] = "frontal"
    scale: float = 1.0
    px_per_unit: float | None = None
    max_stretch: float = 4.0
    max_pixels: float = 50e6
    max_size: tuple[int, int] | None = None
    margin: float = 0.0
    corners: tuple[tuple[float, float], ...] | None = None
    #: With ``"crop"``: the rectangle's width over height (None: the largest of any shape;
    #: ``"original"``: the input's own).
    crop_aspect: float | str | None = None
    max_area: float | None = None

    def output_scale(self, view: View) -> float:
        """Output pixels per frontal pixel. One frontal pixel covers ``Zc / f`` wall units,
        so ``px_per_unit`` N is a scale of ``N Zc / f``."""
        if self.px_per_unit is None:
            return self.scale
        if view.distance is None:
            raise MissingDistanceError()
        return self.px_per_unit * view.distance / view.focal


#: ``gsrwt rectify``'s ``max_area`` when the scale is not asked for (no --scale,
#: --px-per-unit or --max-size): at most twice the input's pixels, about 1.4 times its
#: sides. The thesis's frame is the input's size, so it is never lowered; a full or cropped
#: frame of an oblique view may be many times larger (the 51 York Urban photos at their true
#: poses: 2.1 times the input's pixels at the median, 5.6 at the 90th percentile, 7.3 at
#: most, with --bbox full), mostly of its far side magnified up to --max-stretch times.
DEFAULT_MAX_AREA = 2.0

#: The default framing: the thesis's frame (Fig. 5.7) at frontal resolution.
DEFAULT_FRAMING = Framing()


class MissingDistanceError(ValueError):
    """Metric output (pixels per unit of distance) for an image whose distance is unknown."""

    def __init__(self) -> None:
        super().__init__("metric output needs the camera-to-wall 'distance' of the image")


def plan_output(view: View, framing: Framing = DEFAULT_FRAMING) -> Plan:
    """Choose the output frame as ``framing`` says and compose the one pixel map.

    Raises :class:`EmptyOutputError` for an empty output, :class:`OutputTooLargeError` for one
    larger than ``framing.max_pixels``, :class:`NothingWithinStretchError` for nothing to
    frame, :class:`FrameOutsideImageError` for a frame with no source pixel,
    :class:`MissingDistanceError` for ``px_per_unit`` without a distance.
    """
    if view.width is None or view.height is None:
        raise ValueError("the image size is needed to frame the output")
    scale = framing.output_scale(view)
    with np.errstate(all="ignore"):  # non-finite results are checked below, not warned about
        plan = _plan_output(view, framing, scale)
    if not np.all(np.isfinite(plan.homography)):
        raise ValueError(
            "the transform is not finite for this view (pan or tilt too close to 90 degrees?)"
        )
    return plan


def _plan_output(view: View, framing: Framing, scale: float) -> Plan:
    bbox, max_stretch = framing.bbox, framing.max_stretch
    if bbox == "frontal":
        frame = default_frame(view, scale)
    elif bbox == "full":
        frame = full_frame(view, max_stretch, scale)
    elif bbox == "crop":
        aspect = framing.crop_aspect
        if aspect == "original":
            aspect = view.width / view.height
        frame = crop_frame(view, max_stretch, scale,
                           aspect=None if aspect is None else float(aspect))
    elif bbox == "corners":
        if framing.corners is None:
            raise ValueError("--bbox corners needs the rectangle's corners (--corners, or a "
                             "corners column) for this image")
        frame = corners_frame(view, np.array(framing.corners), framing.margin, scale)
    else:
        frame = Frame(*(float(v) for v in bbox), scale=scale)
    if framing.max_size is not None:
        frame = fit_frame(frame, framing.max_size)
    if framing.max_area is not None:
        frame = fit_area(frame, framing.max_area * view.width * view.height)
    width, height = frame.size
    if width < 1 or height < 1:
        raise EmptyOutputError(width, height)
    if width * height > framing.max_pixels:
        raise OutputTooLargeError(width, height, framing.max_pixels)
    homography = frame.output_from_default() @ output_from_input(view)
    pixel_map = PixelMap(homography, (width, height), view.intrinsics.distortion())
    if not sees_within_lens_limit(pixel_map):
        raise BeyondLensLimitError(pixel_map.lens)
    if not pixel_map.sees((view.width, view.height)):
        corners = np.array([[-0.5, -0.5, 1.0], [view.width - 0.5, -0.5, 1.0],
                            [-0.5, view.height - 0.5, 1.0],
                            [view.width - 0.5, view.height - 0.5, 1.0]])
        w = corners @ np.asarray(output_from_input(view), dtype=np.float64)[2]
        raise FrameOutsideImageError(bbox if isinstance(bbox, str) else "box",
                                     beyond_horizon=bool(np.all(w <= 0)))
    return Plan(view, frame, pixel_map)


def texture_from_camera(view: View, texture_size: tuple[int, int]) -> Matrix:
    """Camera pixel to texture pixel for a frontal texture covering the wall (``gsrwt render``).

    The texture's centre sits at the foot of the perpendicular from the camera to the wall
    and one texture pixel is ``Zc / f`` wall units, so that rectifying the camera's view
    (:func:`output_from_input`) gives the texture back, shifted. The matrix is the GS-RWT
    pixel homography plus that shift, normalized like it (``w > 0`` where the wall is seen).
    """
    width, height = texture_size
    alpha, beta = np.radians(view.pan), np.radians(view.tilt)
    # Where the optical axis meets the wall, in frontal pixels from the foot (x up, y right).
    axis_x = view.focal * np.tan(beta) / np.cos(alpha)
    axis_y = -view.focal * np.tan(alpha)
    shift = np.array(
        [[1.0, 0.0, (width - 1) / 2 - view.cx + axis_y],
         [0.0, 1.0, (height - 1) / 2 - view.cy - axis_x],
         [0.0, 0.0, 1.0]]
    )
    return shift @ output_from_input(view)


def render_map(view: View, texture_size: tuple[int, int]) -> PixelMap:
    """The pixel map of ``gsrwt render``: camera pixels (the output, of the view's size) from
    texture pixels (the input), the inverse of :func:`texture_from_camera`, through the
    camera's lens if it has one (on the output side: the camera's pixels are distorted)."""
    if view.width is None or view.height is None:
        raise ValueError("the view needs an image size (width and height) to render")
    camera_from_texture = np.linalg.inv(texture_from_camera(view, texture_size))
    return PixelMap(camera_from_texture, (view.width, view.height),
                    output_lens=view.intrinsics.distortion())


def _rq(m: Matrix) -> tuple[Matrix, Matrix]:
    """``m = K @ R``: ``K`` upper triangular with a positive diagonal, ``R`` a rotation (for
    ``det(m) > 0``), by the QR decomposition of the flipped matrix."""
    flip = np.eye(3)[::-1]
    q, upper = np.linalg.qr((flip @ m).T)
    k = flip @ upper.T @ flip
    r = flip @ q.T
    signs = np.diag(np.sign(np.diag(k)))
    return k @ signs, signs @ r
