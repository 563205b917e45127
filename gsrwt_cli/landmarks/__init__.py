"""Landmarks on rectified (frontal) wall images: straight lines and door parts (thesis Sec. 5.2.2).

Once a wall has been rectified into its frontal view, the thesis looks for a door with two
voting schemes on the Sobel edges of the grey image (:mod:`.edges`):

- straight lines with a Hough transform in which every edge pixel casts ONE vote, in the
  orientation bin of its own gradient direction (:func:`hough_lines`, :mod:`.hough`);
- the door knob and the peek window with the Generalized Hough Transform (GHT, Ballard 1981)
  and a single fixed model cut out of an example image (:func:`build_template`,
  :func:`match_template`, :mod:`.ght`).

Pure numpy (and ``cv2`` for the Sobel mask, colour conversion and 3x3 filters): arrays in,
dataclasses out, no file I/O, no printing. :mod:`.drawing` draws what was found.

Conventions
-----------
Unlike :mod:`gsrwt_cli.geometry` (``x`` up, ``y`` right), these modules work in plain pixel
coordinates: ``x`` is the column (to the right), ``y`` the row (downward), pixel centres at
integers. Angles are degrees. Images are 2-D ``uint8`` grey arrays or ``uint8`` BGR / BGRA
colour arrays, converted to grey with :func:`cv2.cvtColor`.
"""

from __future__ import annotations

from .edges import DEFAULT_EDGE_THRESHOLD, EdgeMap, colour8, edge_map, grey8, grey_image
from .ght import DEFAULT_GHT_ORIENTATION_STEP_DEG, Match, Template, build_template, match_template
from .hough import DEFAULT_MIN_VOTES, DEFAULT_THETA_STEP_DEG, Line, hough_lines

__all__ = [
    "DEFAULT_EDGE_THRESHOLD",
    "DEFAULT_GHT_ORIENTATION_STEP_DEG",
    "DEFAULT_MIN_VOTES",
    "DEFAULT_THETA_STEP_DEG",
    "EdgeMap",
    "Line",
    "Match",
    "Template",
    "build_template",
    "colour8",
    "edge_map",
    "grey8",
    "grey_image",
    "hough_lines",
    "match_template",
]
