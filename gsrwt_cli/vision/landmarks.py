"""Landmarks on rectified (frontal) wall images: straight segments and door parts (Sec. 5.2.2).

Once a wall has been rectified into its frontal view, the thesis looks for a door with two
voting schemes on the Sobel edges of the grey image (:mod:`.edges`: the thesis's raw
threshold, :func:`edge_map`, and the thin hysteresis edges of real photos,
:func:`line_edges`, given the view's fill and magnification by :mod:`.frontal_pixels`):

- straight segments with a Hough transform in which every edge pixel casts ONE vote, in the
  orientation bin of its own gradient direction, each line cut where its edge pixels have
  gaps (:func:`hough_lines`, :mod:`.hough`);
- the door knob and the peek window with the Generalized Hough Transform (GHT, Ballard 1981)
  and a single fixed model cut out of an example image (:func:`build_template`,
  :func:`match_template`, :mod:`.ght`).

Pure numpy (and ``cv2`` for the Sobel mask, colour conversion and 3x3 filters): arrays in,
dataclasses out, no file I/O, no printing. :mod:`.drawing` draws what was found.

Conventions
-----------
Unlike :mod:`gsrwt_cli.geometry.gsrwt` (``x`` up, ``y`` right), these modules work in plain pixel
coordinates: ``x`` is the column (to the right), ``y`` the row (downward), pixel centres at
integers. Angles are degrees. Images are 2-D ``uint8`` grey arrays or ``uint8`` BGR / BGRA
colour arrays, converted to grey with :func:`cv2.cvtColor`.
"""

from __future__ import annotations

from .edges import (
    DEFAULT_EDGE_THRESHOLD,
    DEFAULT_LINE_THRESHOLD,
    EdgeMap,
    colour8,
    edge_map,
    grey8,
    grey_image,
    line_edges,
    pixels8,
)
from .ght import DEFAULT_GHT_ORIENTATION_STEP_DEG, Match, Template, build_template, match_template
from .hough import (
    DEFAULT_MAX_GAP,
    DEFAULT_MIN_LENGTH,
    DEFAULT_MIN_VOTES,
    DEFAULT_THETA_STEP_DEG,
    ORIENTATIONS,
    Line,
    hough_lines,
)

__all__ = [
    "DEFAULT_EDGE_THRESHOLD",
    "DEFAULT_GHT_ORIENTATION_STEP_DEG",
    "DEFAULT_LINE_THRESHOLD",
    "DEFAULT_MAX_GAP",
    "DEFAULT_MIN_LENGTH",
    "DEFAULT_MIN_VOTES",
    "DEFAULT_THETA_STEP_DEG",
    "EdgeMap",
    "Line",
    "Match",
    "ORIENTATIONS",
    "Template",
    "build_template",
    "colour8",
    "edge_map",
    "grey8",
    "grey_image",
    "hough_lines",
    "line_edges",
    "match_template",
    "pixels8",
]
