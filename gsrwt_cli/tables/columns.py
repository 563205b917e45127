"""The columns of every public table, in one place: a contract, documented in docs/TABLES.md
and docs/COMMANDS.md, and kept by golden tables (``tests/test_golden_tables.py``).

Plain tuples, no numpy: ``gsrwt params`` with options starts without it.
"""

from __future__ import annotations

#: ``gsrwt params``: the GS-RWT parameters of a view (thesis Sec. 4.5, Tables 5.1 and 5.2).
PARAMS_COLUMNS = (
    "image", "pan_deg", "tilt_deg", "focal_px", "roll_deg", "fx_px", "fy_px", "theta_deg",
    "delta_deg", "a_px", "gamma_deg", "vp_x", "vp_y", "vp_col", "vp_row", "vl_a", "vl_b",
    "vl_c", "foreshortening", "horizon_in_image",
)

#: ``gsrwt rectify``: the view's parameters, where they came from, the output and its
#: geometry, what made it, and how it went.
RECTIFY_COLUMNS = (
    *PARAMS_COLUMNS, "focal_source", "pose_source", "confidence", "aspect", "aspect_source",
    "orientation", "metadata", "lens_source", "lens_profile", "output",
    "out_width", "out_height", "scale", "homography", "made_with", "status", "error",
)

#: ``gsrwt rectify VIDEO --poses FILE``: one row per frame, the rectify table's columns with
#: the frame's index (``frame``, from 0) and ``time`` (seconds from the first frame) after
#: ``image`` (the video). Still images keep :data:`RECTIFY_COLUMNS`.
VIDEO_COLUMNS = (RECTIFY_COLUMNS[0], "frame", "time", *RECTIFY_COLUMNS[1:])

#: Where a rectify row's focal length and pose came from (``focal_source``, ``pose_source``),
#: and the statuses of its rows.
FOCAL_SOURCES = ("option", "sidecar", "camera", "exif", "exif+lines", "estimated")
POSE_SOURCES = ("sidecar", "yaml", "options", "estimated")
RECTIFY_STATUSES = ("ok", "skipped", "error", "interrupted", "planned")
#: Where a rectify row's lens came from (``lens_source``): lens columns of a sidecar row, the
#: YAML beside the image or the options, a calibration file, lensfun's database (its profile
#: named in ``lens_profile``), the image's lines (``--lens-from-lines``: its evidence, or why
#: it was refused, in ``lens_profile``), or nowhere.
LENS_SOURCES = ("camera", "sidecar", "lensfun", "lines", "none")
#: A rectify row's ``orientation``: the EXIF orientation applied (1-8, 1 also for a photo
#: without one), or ``ignored`` (``--orientation ignore``: the stored pixels).
ORIENTATION_VALUES = ("1", "2", "3", "4", "5", "6", "7", "8", "ignored")
#: A rectify row's ``metadata``: what its output carries of the input's (docs/TABLES.md).
#: ``kept``: the input's EXIF and gsrwt's record (XMP); ``none``: the input had no EXIF, so
#: neither; ``stripped``: ``--strip-metadata``; ``damaged``: the input's EXIF could not be
#: read, so neither; ``unsupported``: the output's format holds none (BMP), or not this
#: much (a JPEG's 64 KB segment), so neither.
METADATA_VALUES = ("kept", "none", "stripped", "damaged", "unsupported")

#: The vanishing points ``gsrwt estimate`` reports, in the estimator's order (its
#: ``DIRECTION_NAMES``).
VANISHING_DIRECTIONS = ("vertical", "wall", "normal")

#: ``gsrwt estimate``: a sidecar row of the estimated camera, and the evidence (``focal_sd``:
#: an estimated or refined focal length's standard deviation, a fraction of it; ``aspect``,
#: ``aspect_source``: the rectangle of ``--corners``, ``given`` or ``estimated``).
ESTIMATE_COLUMNS = (
    "image", "pan", "tilt", "roll", "focal", "fx", "fy", "cx", "cy", "width", "height",
    "confidence", "segments", "inliers", "focal_source", "focal_sd", "aspect", "aspect_source",
    "corners",
    *(f"vp_{name}_{axis}" for name in VANISHING_DIRECTIONS for axis in ("col", "row")),
    "status", "error",
)

#: ``gsrwt estimate --lens-from-lines`` adds these before ``status``: where the lens came from
#: (:data:`LENS_SOURCES`), the lens the lines gave (``distortion_model``, ``k1``: a sidecar's
#: lens columns, which ``rectify --sidecar`` reads back) and ``lens_lines``, their evidence or
#: why they were refused. Without the flag the table is as before.
ESTIMATE_LENS_COLUMNS = ("lens_source", "distortion_model", "k1", "lens_lines")


def estimate_columns(lens_from_lines: bool = False) -> tuple[str, ...]:
    """The columns of ``gsrwt estimate``'s table (:data:`ESTIMATE_COLUMNS`, with
    :data:`ESTIMATE_LENS_COLUMNS` before ``status`` when the lens is estimated)."""
    if not lens_from_lines:
        return ESTIMATE_COLUMNS
    return (*ESTIMATE_COLUMNS[:-2], *ESTIMATE_LENS_COLUMNS, *ESTIMATE_COLUMNS[-2:])


#: ``gsrwt gaze`` and ``gsrwt track`` (thesis Sec. 5.2.2-5.2.3).
GAZE_COLUMNS = ("pan_deg", "tilt_deg", "wall_x", "wall_y")
TRACK_COLUMNS = ("position", "pan_deg", "tilt_deg", "theta_deg", "foreshortening")

#: ``gsrwt lines`` and ``gsrwt match`` (thesis Sec. 5.2.2).
LINES_COLUMNS = ("image", "rho", "theta_deg", "votes", "x1", "y1", "x2", "y2",
                 "x1_src", "y1_src", "x2_src", "y2_src", "length", "contrast")
MATCH_COLUMNS = ("image", "template", "x", "y", "scale", "votes", "score", "x_src", "y_src")

#: The commands above on a video (``gsrwt params VIDEO --poses FILE``, ``estimate VIDEO``,
#: ``lines VIDEO``, ``match VIDEO``): the frame's index (``frame``, from 0) and ``time``
#: (seconds from the first frame) in front of the command's columns, and ``status`` and
#: ``error`` at the end (``ok``; ``none`` for a frame where ``lines`` or ``match`` found
#: nothing; ``error`` for a frame that cannot be decoded or has no pose).
SEQUENCE_PREFIX = ("frame", "time")
SEQUENCE_STATUSES = ("ok", "none", "error")
PARAMS_SEQUENCE_COLUMNS = (*SEQUENCE_PREFIX, *PARAMS_COLUMNS, "status", "error")
ESTIMATE_SEQUENCE_COLUMNS = (*SEQUENCE_PREFIX, *ESTIMATE_COLUMNS)
LINES_SEQUENCE_COLUMNS = (*SEQUENCE_PREFIX, *LINES_COLUMNS, "status", "error")
MATCH_SEQUENCE_COLUMNS = (*SEQUENCE_PREFIX, *MATCH_COLUMNS, "status", "error")

#: ``gsrwt track VIDEO --poses FILE --template FILE`` (thesis Sec. 5.2.2-5.2.3): per frame,
#: where the landmark was found (``x_src``, ``y_src`` in the frame; ``x``, ``y`` on its
#: canonical view), its match, and the gaze command that centres it (``pan_deg``,
#: ``tilt_deg``, and the wall point ``wall_x``, ``wall_y`` as ``gsrwt gaze`` gives it);
#: ``status`` ``ok``, ``lost`` (not found: ``error`` says why) or ``error``.
TRACK_SEQUENCE_COLUMNS = (
    *SEQUENCE_PREFIX, "image", "template", "x_src", "y_src", "x", "y", "scale", "score",
    "pan_deg", "tilt_deg", "wall_x", "wall_y", "status", "error",
)
TRACK_STATUSES = ("ok", "lost", "error")
