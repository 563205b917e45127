"""The map from output pixels back to input pixels: what a warp needs, in one object.

A :class:`PixelMap` is what framing produces and rectify, render, the landmark commands and the
table consume. It maps points both ways, knows which output pixels have no source, resamples
an image in one OpenCV pass and says what the table's geometry columns are. Today's is a
homography (the GS-RWT composed with the pixel frames); a dense map (for lens distortion) can
stand behind the same methods without its callers changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .geometry import Matrix, map_points


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

    def to_output(self, points: np.ndarray) -> np.ndarray:
        """``(N, 2)`` input pixels to output pixels."""
        return map_points(self.output_from_input, points)

    def to_input(self, points: np.ndarray) -> np.ndarray:
        """``(N, 2)`` output pixels to input pixels."""
        return map_points(np.linalg.inv(self.output_from_input), points)

    def then(self, output_from_output: Matrix, size: tuple[int, int]) -> PixelMap:
        """This map followed by a homography of the output (a new frame of ``size``)."""
        return PixelMap(np.asarray(output_from_output) @ self.output_from_input, size)

    def beyond_horizon(self) -> np.ndarray | None:
        """The output region (pixel-edge coordinates, a convex polygon) whose source lies
        beyond the vanishing line, ``w <= 0``; None if there is none.

        In the output that region is a half-plane, ``(H^-1)[2] . (col, row, 1) <= 0`` (for
        ``o ~ H p``, ``(H^-1 o)_3 = 1 / w(p)``), clipped to the output's rectangle.
        """
        width, height = self.size
        line = np.linalg.inv(np.asarray(self.output_from_input, dtype=np.float64))[2]
        corners = [(-0.5, -0.5), (width - 0.5, -0.5), (width - 0.5, height - 0.5),
                   (-0.5, height - 0.5)]
        polygon = _clip_to_half_plane(corners, line)
        return np.array(polygon) if len(polygon) >= 3 else None

    def warp(
        self,
        pixels: np.ndarray,
        interpolation: int,
        fill: tuple[float, ...],
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Backward-map ``pixels`` into the output in one OpenCV pass (thesis Sec. 5.1).

        ``interpolation``: an OpenCV flag; ``fill``: the 4 channel values of output pixels
        with no source (outside the input or beyond the horizon); ``out``: an array of the
        output's shape and type to write into.
        """
        warped = cv2.warpPerspective(
            pixels,
            np.asarray(self.output_from_input, dtype=np.float64),
            self.size,
            dst=out,
            flags=interpolation,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=fill,
        )
        polygon = self.beyond_horizon()
        if polygon is not None:
            scale = 256  # 8 fractional bits
            points = np.round((polygon + 0.5) * scale - 0.5).astype(np.int32)
            cv2.fillPoly(warped, [points], fill, lineType=cv2.LINE_8, shift=8)
        return warped

    def table_columns(self) -> dict[str, object]:
        """The rectify table's geometry columns: ``out_width``, ``out_height``, ``homography``
        (9 numbers row-major, scaled so that ``w = 1`` at the principal point)."""
        return {
            "out_width": self.size[0],
            "out_height": self.size[1],
            "homography": " ".join(f"{value:.12g}" for value in self.output_from_input.ravel()),
        }


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
