"""The map from output pixels back to input pixels: what a warp needs, in one object.

A :class:`PixelMap` is what framing produces and rectify, render, the landmark commands and the
table consume. It maps points both ways, knows which output pixels have no source and
resamples an image in one OpenCV pass. It is a homography (the GS-RWT composed with the pixel
frames) from ideal input pixels, and for a camera with a lens the lens model (:mod:`.lens`)
after it: then the warp is one ``cv2.remap`` through dense maps built once (and cached) per
camera, pose and frame, never an undistortion followed by a second warp.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from .gsrwt import Matrix, largest_singular_value, local_stretch, map_points
from .lens import NO_SOURCE, LensDistortion, map_step

#: Bytes of remap maps a process keeps for poses it may see again (a 12-megapixel frame's
#: maps take 96 MB, a 640x480 one's 2.5 MB): a robot's small frames keep some 80 poses.
#: Maps over a quarter of this (frames over about 6 megapixels) are not kept beside others:
#: only the last frame's, whose memory the next big frame's maps reuse (fresh memory costs
#: page faults: 39 ms against 6 ms to expand a 12-megapixel frame's grid, measured).
MAP_CACHE_BYTES = 200 * 2**20
#: Bytes of big frames' grids (:meth:`LensDistortion.grid`, a sixteenth of their maps) a
#: process keeps for poses it may see again: 8 poses of a 12-megapixel frame (6 MB each), whose
#: maps are then only expanded, the lens model not evaluated again.
GRID_CACHE_BYTES = 48 * 2**20


class _MapCache:
    """A process's maps by (camera, pose, frame), least recently used first out, within
    :data:`MAP_CACHE_BYTES`: a pan-tilt unit revisits the same poses thousands of times.
    Big frames' maps are :attr:`last` only (the memory of one frame's maps, reused), and
    their grids are kept within ``grid_budget`` (:attr:`grids`)."""

    def __init__(self, budget: int, grid_budget: int = GRID_CACHE_BYTES) -> None:
        self.budget = budget
        self.grid_budget = grid_budget
        self.entries: OrderedDict[tuple, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self.grids: OrderedDict[tuple, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self.last: tuple[tuple, tuple[np.ndarray, np.ndarray]] | None = None
        self.hits = self.misses = 0

    def get(self, lens: LensDistortion, homography: np.ndarray, size: tuple[int, int]):
        key = (lens, homography.tobytes(), size)
        if self.last is not None and self.last[0] == key:
            self.hits += 1
            return self.last[1]
        if key in self.entries:
            self.hits += 1
            self.entries.move_to_end(key)
            return self.entries[key]
        step = map_step(size)
        if size[0] * size[1] * 8 > self.budget // 4 and step > 1:  # 2 float maps
            reuse = self.last[1] if self.last is not None and self.last[0][2] == size else None
            self.last = None  # a frame of another size: its memory goes first
            grid = self.grids.get(key)
            if grid is None:
                self.misses += 1
                grid = lens.grid(homography, size, step)
                self.grids[key] = grid
                while len(self.grids) > 1 and sum(
                        a.nbytes + b.nbytes for a, b in self.grids.values()) > self.grid_budget:
                    self.grids.popitem(last=False)
            else:
                self.hits += 1
                self.grids.move_to_end(key)
            maps = lens.expand(grid, size, step, reuse)
            self.last = key, maps
            return maps
        self.misses += 1
        maps = lens.maps(homography, size)
        self.entries[key] = maps
        while len(self.entries) > 1 and self._bytes() > self.budget:
            self.entries.popitem(last=False)
        return maps

    def _bytes(self) -> int:
        return sum(a.nbytes + b.nbytes for a, b in self.entries.values())

    def clear(self) -> None:
        self.entries.clear()
        self.grids.clear()
        self.last = None
        self.hits = self.misses = 0


MAP_CACHE = _MapCache(MAP_CACHE_BYTES)


@dataclass(frozen=True)
class PixelMap:
    """``output (col, row, 1) ~ output_from_input @ input (col, row, 1)`` for an output of
    ``size = (width, height)`` pixels.

    ``output_from_input`` is scaled so that ``w > 0`` where the wall is visible (as the
    framing module makes it): output pixels whose source has ``w <= 0`` look beyond the
    wall's horizon and have no source, like those that map outside the input.
    """

    output_from_input: Matrix
    size: tuple[int, int]
    lens: LensDistortion | None = None  # input pixels are ideal ones distorted by this
    output_lens: LensDistortion | None = None  # output pixels are, instead (gsrwt render)

    def to_output(self, points: np.ndarray) -> np.ndarray:
        """``(N, 2)`` input pixels to output pixels."""
        if self.lens is not None:
            points = self.lens.undistort(points)
        output = map_points(self.output_from_input, points)
        return output if self.output_lens is None else self.output_lens.distort(output)

    def to_input(self, points: np.ndarray) -> np.ndarray:
        """``(N, 2)`` output pixels to input pixels."""
        if self.output_lens is not None:
            points = self.output_lens.undistort(np.asarray(points, dtype=np.float64))
        ideal = map_points(self._input_from_output, points)
        return ideal if self.lens is None else self.lens.distort(ideal)

    def _output_lens_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """Float maps through a lens on the output side: every output pixel undistorted, then
        back through the homography; beyond the horizon (``w <= 0``) nothing is sampled."""
        width, height = self.size
        cols, rows = np.meshgrid(np.arange(width, dtype=np.float64),
                                 np.arange(height, dtype=np.float64))
        ideal = self.output_lens.undistort(np.column_stack([cols.ravel(), rows.ravel()]))
        inverse = self._input_from_output
        sources = map_points(inverse, ideal)
        w = ideal @ inverse[2, :2] + inverse[2, 2]
        sources[~(w > 0) | ~np.all(np.isfinite(sources), axis=1)] = NO_SOURCE
        return (sources[:, 0].reshape(height, width).astype(np.float32),
                sources[:, 1].reshape(height, width).astype(np.float32))

    @cached_property
    def _input_from_output(self) -> np.ndarray:
        """``output_from_input``'s inverse (float64), computed once per map: the map's
        checks and its antialiasing use it several times an image."""
        inverse = np.linalg.inv(np.asarray(self.output_from_input, dtype=np.float64))
        inverse.setflags(write=False)  # shared by every use
        return inverse

    @property
    def _homography(self) -> np.ndarray:
        """``output_from_input`` as the 3x3 float64 array OpenCV and the map cache take."""
        return np.ascontiguousarray(self.output_from_input, dtype=np.float64)

    def then(self, output_from_output: Matrix, size: tuple[int, int]) -> PixelMap:
        """This map followed by a homography of the output (a new frame of ``size``)."""
        if self.output_lens is not None:
            raise ValueError("a map with a lens on its output side has no other frame")
        return PixelMap(np.asarray(output_from_output) @ self.output_from_input, size, self.lens)

    def beyond_horizon(self) -> np.ndarray | None:
        """The output region (pixel-edge coordinates, a convex polygon) whose source lies
        beyond the vanishing line, ``w <= 0``; None if there is none.

        In the output that region is a half-plane, ``(H^-1)[2] . (col, row, 1) <= 0`` (for
        ``o ~ H p``, ``(H^-1 o)_3 = 1 / w(p)``), clipped to the output's rectangle.
        """
        width, height = self.size
        line = self._input_from_output[2]
        corners = [(-0.5, -0.5), (width - 0.5, -0.5), (width - 0.5, height - 0.5),
                   (-0.5, height - 0.5)]
        polygon = _clip_to_half_plane(corners, line)
        return np.array(polygon) if len(polygon) >= 3 else None

    def sees(self, source_size: tuple[int, int], samples: int = 65) -> bool:
        """Whether any of the output has a source in an input of ``source_size`` pixels:
        a point in front of the horizon that maps inside the input's pixel edges.

        Through a pinhole that region of the output is exact: the output's rectangle clipped
        by five half-planes, all linear in the output point ``o`` for ``G = H^-1``:
        ``G[2] . o > 0`` (in front of the horizon) and ``-0.5 <= (G[0] . o) / (G[2] . o) <=
        W - 0.5``, likewise for rows, each multiplied out by the positive ``G[2] . o``. It
        sees the input if that polygon has an area. Through a lens (or a lens on the output
        side) ``samples x samples`` output points are mapped back instead.
        """
        width, height = self.size
        source_width, source_height = source_size
        if self.lens is not None or self.output_lens is not None:
            cols = np.linspace(-0.5, width - 0.5, samples)
            rows = np.linspace(-0.5, height - 0.5, samples)
            outputs = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
            with np.errstate(all="ignore"):
                inverse = self._input_from_output
                ideal = outputs if self.output_lens is None else self.output_lens.undistort(
                    outputs)
                w = ideal @ inverse[2, :2] + inverse[2, 2]
                inputs = self.to_input(outputs)
                inside = ((w > 0) & np.all(np.isfinite(inputs), axis=1)
                          & (inputs[:, 0] >= -0.5) & (inputs[:, 0] <= source_width - 0.5)
                          & (inputs[:, 1] >= -0.5) & (inputs[:, 1] <= source_height - 0.5))
            return bool(np.any(inside))
        g = self._input_from_output
        polygon: list[tuple[float, float]] = [
            (-0.5, -0.5), (width - 0.5, -0.5), (width - 0.5, height - 0.5),
            (-0.5, height - 0.5)]
        for line in (-g[2], -(g[0] + 0.5 * g[2]), g[0] - (source_width - 0.5) * g[2],
                     -(g[1] + 0.5 * g[2]), g[1] - (source_height - 0.5) * g[2]):
            polygon = _clip_to_half_plane(polygon, line)
            if len(polygon) < 3:
                return False
        xs, ys = np.array(polygon).T
        area = 0.5 * abs(float(np.dot(xs, np.roll(ys, -1)) - np.dot(ys, np.roll(xs, -1))))
        return area > 1e-9

    def shrink(self, step: int = 8, source_size: tuple[int, int] | None = None) -> np.ndarray:
        """Input pixels per output pixel (the largest singular value of the output-to-input
        Jacobian) on a grid of every ``step``-th output pixel, shape ``(rows, cols)``.

        With ``source_size`` (the input's width and height), 1 where the output pixel has no
        source: outside the input nothing is sampled, however much the map shrinks there.
        """
        shape, grid, values, sources = self._shrink_grid(step)
        if source_size is not None:
            values = np.where(self._sampling(grid, sources, source_size), values, 1.0)
        return values.reshape(shape)

    def least_shrink(self, source_size: tuple[int, int], step: int = 8) -> float:
        """The least :meth:`shrink` over the output pixels that sample an input of
        ``source_size`` (width, height): every output pixel with a source spans at least this
        many input pixels (in the direction where it spans most, the antialiasing's measure);
        ``inf`` when no output pixel has a source.

        Conservative at the input's edges: grid points up to one grid step outside the input
        count as sampling it, so that the shrink between the last grid point inside and the
        edge is represented (it varies smoothly there).
        """
        _, grid, values, sources = self._shrink_grid(step)
        sampled = self._sampling(grid, sources, source_size, margin=values * step)
        return float(values[sampled].min()) if np.any(sampled) else math.inf

    def _shrink_grid(self, step: int):
        """``((rows, cols), grid, shrink, sources)`` of :meth:`shrink`: the output points of the
        grid ``(N, 2)``, the shrink at each (1 where it is not finite) and, through a lens,
        their input pixels (None for a pinhole: :meth:`to_input` finds them when needed)."""
        width, height = self.size
        cols = np.arange(0, width + step - 1, step, dtype=np.float64).clip(max=width - 1)
        rows = np.arange(0, height + step - 1, step, dtype=np.float64).clip(max=height - 1)
        grid = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
        if self.lens is None:
            values = local_stretch(self._input_from_output, grid)
            sources = None
        else:  # finite differences of the warp's own maps (cached: it has just used them)
            maps = MAP_CACHE.get(self.lens, self._homography, self.size)
            col, row = grid.T.astype(np.intp)
            # one pixel right and down (left and up on the last column and row)
            across = np.where(col + 1 < width, 1, -1) if width > 1 else np.zeros_like(col)
            along = np.where(row + 1 < height, 1, -1) if height > 1 else np.zeros_like(row)

            def at(rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
                return np.column_stack([part[rows, cols] for part in maps]).astype(np.float64)

            sources = at(row, col)
            a, c = ((at(row, col + across) - sources) * across[:, None]).T
            b, d = ((at(row + along, col) - sources) * along[:, None]).T
            values = largest_singular_value(a, b, c, d)
        values = np.nan_to_num(values, nan=1.0, posinf=1.0)
        return (len(rows), len(cols)), grid, values, sources

    def _sampling(self, grid: np.ndarray, sources: np.ndarray | None,
                  source_size: tuple[int, int], margin: float | np.ndarray = 0.0
                  ) -> np.ndarray:
        """Which output points of ``grid`` have a source: in front of the horizon and inside
        an input of ``source_size``'s pixel edges grown by ``margin`` input pixels."""
        sources = self.to_input(grid) if sources is None else sources
        inverse = self._input_from_output
        w = grid @ inverse[2, :2] + inverse[2, 2]
        with np.errstate(invalid="ignore"):
            inside = (w > 0) & np.all(np.isfinite(sources), axis=1)
            inside &= (sources[:, 0] >= -0.5 - margin)
            inside &= (sources[:, 0] <= source_size[0] - 0.5 + margin)
            inside &= (sources[:, 1] >= -0.5 - margin)
            inside &= (sources[:, 1] <= source_size[1] - 0.5 + margin)
        return inside

    def reduced(self, factor: int, offset: tuple[float, float] = (0.0, 0.0)) -> PixelMap:
        """This map onto the input reduced ``factor`` times, as libjpeg's scaled decoding
        reduces it: reduced pixel ``k`` is input pixels ``factor k .. factor (k + 1) - 1``,
        so with pixel centres at integers ``x_reduced = (x + 0.5) / factor - 0.5`` (a box
        average's centre; not the pyramid's, whose levels :meth:`_resample` centres on every
        ``2^level``-th pixel of the reduced image), plus ``offset`` (reduced pixels, per axis:
        a reduced image mirrored along an axis whose length ``factor`` does not divide is
        shifted by the part of a pixel its last one lacks).

        Exact through a lens too: the lens's camera matrix becomes ``A K`` (``A``: reduced
        from input pixels), so that the reduced lens distorts ``A p`` to ``A distort(p)``.
        """
        if self.output_lens is not None:
            raise ValueError("a map with a lens on its output side has no reduced input")
        scale = 1.0 / factor
        reduced_from_input = np.array([[scale, 0.0, 0.5 * scale - 0.5 + offset[0]],
                                       [0.0, scale, 0.5 * scale - 0.5 + offset[1]],
                                       [0.0, 0.0, 1.0]])
        homography = (np.asarray(self.output_from_input, dtype=np.float64)
                      @ np.linalg.inv(reduced_from_input))
        lens = None
        if self.lens is not None:
            matrix = reduced_from_input @ np.array(self.lens.camera_matrix, dtype=np.float64)
            lens = LensDistortion(tuple(tuple(float(v) for v in row) for row in matrix),
                                  self.lens.coefficients, self.lens.fisheye)
        return PixelMap(homography, self.size, lens)

    def warp(
        self,
        pixels: np.ndarray,
        interpolation: int,
        fill: tuple[float, ...],
        out: np.ndarray | None = None,
        antialias: bool = False,
    ) -> np.ndarray:
        """Backward-map ``pixels`` into the output in one OpenCV pass (thesis Sec. 5.1).

        ``interpolation``: an OpenCV flag; ``fill``: the 4 channel values of output pixels
        with no source (outside the input or beyond the horizon); ``out``: an array of the
        output's shape and type to write into. ``antialias``: where an output pixel spans
        more than :data:`ANTIALIAS_SHRINK` input pixels, sample a Gaussian pyramid of the
        input at the level of the local shrink, blended between levels (area filtering
        without a per-pixel loop); nothing changes, and nothing is spent, where no part of
        the output shrinks that much.
        """
        if self.output_lens is not None:
            map_x, map_y = self._output_lens_maps()
            return cv2.remap(pixels, map_x, map_y, interpolation, dst=out,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=fill)
        warped = self._resample(pixels, 0, interpolation, fill, out)
        if antialias:
            self._antialias(pixels, warped, interpolation, fill)
        polygon = self.beyond_horizon()
        if polygon is not None:
            scale = 256  # 8 fractional bits
            points = np.round((polygon + 0.5) * scale - 0.5).astype(np.int32)
            cv2.fillPoly(warped, [points], fill, lineType=cv2.LINE_8, shift=8)
        return warped

    def filters(self, source_size: tuple[int, int], step: int = 32) -> bool:
        """Whether :meth:`warp`'s ``antialias`` filters any of the output of an input of
        ``source_size`` (width, height): some output pixel with a source spans more than
        :data:`ANTIALIAS_SHRINK` input pixels (on :meth:`shrink`'s grid of every ``step``-th
        pixel, as the warp measures it)."""
        return bool(pyramid_level(self.shrink(step, source_size)).max() > 0)

    def _antialias(self, pixels: np.ndarray, warped: np.ndarray, interpolation: int,
                   fill: tuple[float, ...], step: int = 32) -> None:
        """Blend coarser pyramid levels into ``warped`` where the map shrinks the input by
        more than :data:`ANTIALIAS_SHRINK`. Only the output rectangle that needs it, from
        the input rectangle it comes from, is filtered and resampled."""
        source_size = (pixels.shape[1], pixels.shape[0])
        level_grid = pyramid_level(self.shrink(step, source_size))
        if level_grid.max() <= 0:
            return
        rows, cols = np.nonzero(level_grid > 0)
        width, height = self.size
        r0, r1 = max(0, rows.min() - 1), min(len(level_grid), rows.max() + 2)
        c0, c1 = max(0, cols.min() - 1), min(len(level_grid[0]), cols.max() + 2)
        x0, x1 = c0 * step, min(width, (c1 - 1) * step + 1)
        y0, y1 = r0 * step, min(height, (r1 - 1) * step + 1)
        region = self.then(np.array([[1.0, 0, -x0], [0, 1.0, -y0], [0, 0, 1]]), (x1 - x0, y1 - y0))
        level = cv2.resize(level_grid[r0:r1, c0:c1].astype(np.float32), (x1 - x0, y1 - y0),
                           interpolation=cv2.INTER_LINEAR)
        levels = min(int(math.ceil(level.max())), 8)
        # The input rectangle the region samples, with room for the pyramid's filters, at
        # offsets that are whole pixels of the coarsest level.
        across, down = np.meshgrid(np.linspace(0, x1 - x0 - 1, 17),
                                   np.linspace(0, y1 - y0 - 1, 17), indexing="ij")
        corners = np.column_stack([across.ravel(), down.ravel()])
        sources = region.to_input(corners)
        sources = sources[np.all(np.isfinite(sources), axis=1)]
        if len(sources) == 0:
            return
        unit, margin = 2**levels, 4 * 2**levels
        left = int(max(0, (np.floor(sources[:, 0].min()) - margin) // unit * unit))
        top = int(max(0, (np.floor(sources[:, 1].min()) - margin) // unit * unit))
        right = int(min(source_size[0], np.ceil(sources[:, 0].max()) + margin))
        bottom = int(min(source_size[1], np.ceil(sources[:, 1].max()) + margin))
        if right <= left or bottom <= top:
            return
        crop = pixels[top:bottom, left:right]
        target = warped[y0:y1, x0:x1]
        # Coarser levels repeat the image's edge outward, so that their blur does not pull
        # the fill (or transparency) inward; outside the image the output stays the fill.
        inside = np.full(pixels.shape[:2], 255, np.uint8)
        outside = region._resample(inside, 0, cv2.INTER_LINEAR, (0.0,) * 4, None) == 0
        pyramid = crop
        for index in range(1, levels + 1):
            pyramid = cv2.pyrDown(pyramid)
            coarser = region._resample(pyramid, index, interpolation, fill, None,
                                       cv2.BORDER_REPLICATE, (left, top))
            weight = np.clip(level - (index - 1), 0.0, 1.0)
            weight[outside] = 0.0
            _blend(target, coarser, weight)

    def _resample(self, pixels: np.ndarray, level: int, interpolation: int,
                  fill: tuple[float, ...], out: np.ndarray | None,
                  border: int = cv2.BORDER_CONSTANT,
                  offset: tuple[int, int] = (0, 0)) -> np.ndarray:
        """One OpenCV pass from pyramid ``level`` of the input (``2^level`` pixels per pixel),
        or of the part of the input whose first pixel is ``offset`` (column, row).

        ``cv2.pyrDown`` filters with a 5-tap Gaussian centred on the even samples and keeps
        those, so a level's pixel ``i`` is centred on pixel ``2^level i`` of the image it was
        made from: ``x_level = (x - offset) / 2^level``, no half-pixel terms (unlike a box
        average's ``(x + 0.5) / r - 0.5``, :meth:`reduced`; sampled that way, each level was
        ``(2^level - 1) / 2`` input pixels off)."""
        homography = self._homography
        factor = 0.5**level
        if self.lens is None:
            if offset != (0, 0):
                homography = homography @ np.array(
                    [[1.0, 0.0, offset[0]], [0.0, 1.0, offset[1]], [0.0, 0.0, 1.0]])
            if level:
                input_from_level = np.diag([2.0**level, 2.0**level, 1.0])
                homography = homography @ input_from_level
            return cv2.warpPerspective(pixels, homography, self.size, dst=out,
                                       flags=interpolation, borderMode=border,
                                       borderValue=fill)
        # one pass: output -> wall -> camera ray -> lens -> input pixel
        map_x, map_y = MAP_CACHE.get(self.lens, homography, self.size)
        if level or offset != (0, 0):
            map_x = (map_x - offset[0]) * factor
            map_y = (map_y - offset[1]) * factor
        return cv2.remap(pixels, map_x, map_y, interpolation, dst=out, borderMode=border,
                         borderValue=fill)


#: Output pixels spanning more input pixels than this are filtered (``antialias``).
ANTIALIAS_SHRINK = 1.5


def pyramid_level(shrink: np.ndarray) -> np.ndarray:
    """The pyramid level to sample at a local shrink: 0 up to :data:`ANTIALIAS_SHRINK`,
    rising smoothly to level 1 at a shrink of 2, then ``log2(shrink)`` (a level-``l`` pixel
    is ``2^l`` input pixels)."""
    start = math.log2(ANTIALIAS_SHRINK)
    logarithm = np.log2(np.maximum(shrink, 1.0))
    ramp = np.clip((logarithm - start) / (1.0 - start), 0.0, 1.0)
    return np.where(logarithm >= 1.0, logarithm, ramp)


def _blend(into: np.ndarray, other: np.ndarray, weight: np.ndarray) -> None:
    """``into = (1 - weight) into + weight other``, per pixel, in place."""
    if into.dtype in (np.uint8, np.float32):
        into[...] = cv2.blendLinear(into, other, (1.0 - weight).astype(np.float32),
                                    weight.astype(np.float32))
        return
    weights = weight[..., None] if into.ndim == 3 else weight
    mixed = into.astype(np.float32) * (1.0 - weights) + other.astype(np.float32) * weights
    if np.issubdtype(into.dtype, np.integer):
        mixed = np.rint(mixed)
    into[...] = mixed.astype(into.dtype)


def _clip_to_half_plane(polygon: list[tuple[float, float]], line: np.ndarray):
    """The part of a convex polygon where ``line . (x, y, 1) <= 0`` (Sutherland-Hodgman)."""
    clipped = []
    count = len(polygon)
    for index in range(count):
        current, following = polygon[index], polygon[(index + 1) % count]
        d_current = line[0] * current[0] + line[1] * current[1] + line[2]
        d_following = line[0] * following[0] + line[1] * following[1] + line[2]
        if d_current <= 0:
            clipped.append(current)
        if (d_current <= 0) != (d_following <= 0):
            t = d_current / (d_current - d_following)
            clipped.append(
                (
                    current[0] + t * (following[0] - current[0]),
                    current[1] + t * (following[1] - current[1]),
                )
            )
    return clipped
