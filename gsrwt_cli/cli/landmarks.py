"""``gsrwt lines`` and ``gsrwt match``: door boundaries and door parts on frontal views."""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import click
import numpy as np

from ..base.messages import quote
from ..base.numerals import parse_decimal
from ..batch.canonical_views import CanonicalView, canonical_views
from ..imaging.images import ImageError, encode_image, file_orientation, read_image
from ..inputs.sources import sources_from_directory
from ..io.storage import Location
from ..io.targets import Drawings
from ..tables.rows import LINES_COLUMNS, MATCH_COLUMNS, line_row, match_row
from ..tables.writer import TableWriter
from ..vision.drawing import draw_lines, draw_matches
from ..vision.edges import DEFAULT_LINE_THRESHOLD, DEFAULT_ORIENTATION_SMOOTHING, line_edges
from ..vision.frontal_pixels import frontal_edges
from ..vision.ght import DEFAULT_MATCH_THRESHOLD, MATCH_ORIENTATION_SMOOTHING
from ..vision.hough import DEFAULT_MAX_GAP, DEFAULT_MIN_LENGTH, ORIENTATIONS
from ..vision.landmarks import (
    DEFAULT_MIN_VOTES,
    DEFAULT_THETA_STEP_DEG,
    EdgeMap,
    Template,
    build_template,
    colour8,
    grey8,
    hough_lines,
    match_template,
)
from .options import (
    InputError,
    Integer,
    Number,
    PathOrUrl,
    draw_option,
    edge_threshold_option,
    format_option,
    images_argument,
    load_sidecar_option,
    make_output_directory,
    orientation_option,
    raw_views_sidecar_option,
    report_error,
    resolve_format,
    view_defaults,
    view_options,
)
from .sequence_options import frames_option, pose_file_options


def _image_paths(images: tuple[Path | Location, ...]) -> list[Path | Location]:
    """The image files given and the images in the directories given (checked up front);
    URLs as ``gsrwt rectify`` takes them (an object, or the images below a prefix)."""
    paths: list[Path | Location] = []
    for path in images:
        if isinstance(path, Location):
            from .rectify import sources_at_url

            paths += [source.path for source in sources_at_url(str(path), path, False)]
        elif path.is_dir():
            paths += [source.path for source in sources_from_directory(path, recursive=False)]
        elif path.is_file():
            paths.append(path)
        else:
            raise InputError(f"{path}: no such file or directory")
    return paths


def _sources(paths: list[Path], sidecar: Path | None, view_kwargs: dict[str, Any],
             exif_orientation: str):
    """Canonical views of ``paths``, with the parameters of ``sidecar`` and the options."""
    return canonical_views(paths, load_sidecar_option(sidecar), view_defaults(view_kwargs),
                           exif_orientation)


def _start_drawings(draw: Path | None, inputs: list[Path]) -> Drawings | None:
    if draw is None:
        return None
    make_output_directory("--draw", draw)
    return Drawings(draw, inputs)


def _drawing_target(drawings: Drawings | None, view: CanonicalView) -> Path | None:
    """The picture's file for ``view``, or None (reported, counted by the caller) if refused."""
    if drawings is None:
        return None
    try:
        return drawings.target(view.path)
    except ValueError as error:
        report_error(f"{view.path}: --draw: {error}")
        return None


def _save_drawing(drawings: Drawings, target: Path, view: CanonicalView,
                  overlay: np.ndarray) -> bool:
    """Write one picture; False (and one error line) when it could not be written."""
    try:
        drawings.save(target, encode_image(overlay, ".png"))
    except (OSError, ValueError, ImageError) as error:
        reason = getattr(error, "strerror", None) or error
        report_error(f"{view.path}: --draw {target}: {reason}")
        return False
    return True


def _readable(
    views: Iterable[CanonicalView | tuple[Path, str]], failures: list[Path]
) -> Iterator[CanonicalView]:
    """The views that could be read (and rectified); the others are reported in one line each
    and collected in ``failures``."""
    for view in views:
        if isinstance(view, tuple):
            failures.append(view[0])
            report_error(f"{view[0]}: {view[1]}")
        else:
            yield view


def _edges(view: CanonicalView, threshold: float,
           orientation_smoothing: float = DEFAULT_ORIENTATION_SMOOTHING) -> EdgeMap:
    """The edge stage of ``lines`` and ``match`` on a view (:func:`frontal_edges`)."""
    return frontal_edges(grey8(view.pixels), view.pixel_map, view.source_size, threshold,
                         orientation_smoothing)


def _min_length_px(view: CanonicalView, pixels: float, units: float | None) -> float | None:
    """The shortest segment in the view's pixels: ``--min-length-units`` through the view's
    ``Zc / f`` when given (None, reported, when the view's distance is unknown)."""
    if units is None:
        return pixels
    if view.units_per_pixel is None:
        report_error(f"{view.path}: --min-length-units needs the camera-to-wall distance "
                     "(--distance or a 'distance' column) and the camera's parameters")
        return None
    return units / view.units_per_pixel


@click.command()
@images_argument
@raw_views_sidecar_option
@view_options
@functools.partial(edge_threshold_option, default=DEFAULT_LINE_THRESHOLD,
                   text="High hysteresis threshold: gradient magnitude (3x3 Sobel of the "
                        "smoothed view, x magnification) a chain of edge pixels needs; "
                        "it keeps pixels down to 0.4 of it.")
@click.option("--theta-step", type=Number(), default=DEFAULT_THETA_STEP_DEG, show_default=True,
              help="Orientation sampling, degrees.")
@click.option("--min-votes", type=Integer(min=1), default=DEFAULT_MIN_VOTES,
              show_default=True, help="Votes a Hough cell needs to be a candidate line.")
@click.option("--max-gap", type=Number(min=0), default=DEFAULT_MAX_GAP,
              show_default=True, help="Longest gap inside a segment, frontal pixels.")
@click.option("--min-length", type=Number(min=0), default=DEFAULT_MIN_LENGTH,
              show_default=True, help="Shortest segment reported, frontal pixels.")
@click.option("--min-length-units", type=Number(min=0), default=None,
              help="Shortest segment in wall units (needs the distance); instead of "
                   "--min-length.")
@click.option("--orientation", type=click.Choice(ORIENTATIONS), default="all",
              show_default=True, help="Keep vertical or horizontal segments only (within "
                                      "5 degrees).")
@functools.partial(orientation_option, names=("--exif-orientation",))
@draw_option("lines")
@pose_file_options("each frame is rectified with its pose first")
@frames_option
@format_option
def lines(images: tuple[Path, ...], sidecar: Path | None, edge_threshold: float,
          theta_step: float, min_votes: int, max_gap: float, min_length: float,
          min_length_units: float | None, orientation: str, exif_orientation: str,
          draw: Path | None, poses: str | None, time_mode: str, max_pose_gap: float,
          frame_range: tuple[int, int | None, int] | None, fmt: str | None,
          **view_kwargs: Any) -> None:
    """Straight segments (door boundaries) by the Hough transform on frontal views (Sec. 5.2.2).

    Edges: thin hysteresis edges of the smoothed 3x3 Sobel gradient, compensated for the
    rectification's magnification, none at the fill. Each edge pixel votes at its own
    gradient orientation and as far beside it as the image's noise makes that uncertain;
    each line is cut where its edge pixels have gaps, and a segment is kept if it stands out
    from what lies beside it (a short one clearly, a long one may be faint). x1..y2 are the
    segment's end points in the frontal view, x1_src..y2_src in the original image.

    \b
    A video as the only IMAGE (with --poses, or the view options for a fixed camera) gives
    each frame's segments, frame and time in front, status at the end (none: no segment).

    \b
    Example:
      gsrwt lines sample_data/views --sidecar sample_data/views/views.csv --orientation vertical
    """
    video = _video_run(images, poses, time_mode, max_pose_gap, view_kwargs, frame_range)
    if video is not None:
        from ..tables.columns import LINES_SEQUENCE_COLUMNS
        from .sequences import LineSearch, lines_work, print_frame_rows

        search = LineSearch(edge_threshold, theta_step, min_votes, max_gap, min_length,
                            min_length_units, orientation)
        print_frame_rows(video, lines_work(video, search), LINES_SEQUENCE_COLUMNS, fmt)
        return
    paths = _image_paths(images)
    views = _sources(paths, sidecar, view_kwargs, exif_orientation)
    drawings = _start_drawings(draw, [*paths, *([sidecar] if sidecar else [])])
    writer = TableWriter(sys.stdout, LINES_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        picture = _drawing_target(drawings, view)
        if drawings is not None and picture is None:
            failures.append(view.path)
        shortest = _min_length_px(view, min_length, min_length_units)
        if shortest is None:
            failures.append(view.path)
            continue
        found = hough_lines(view.pixels, edges=_edges(view, edge_threshold),
                            theta_step_deg=theta_step, min_votes=min_votes, max_gap=max_gap,
                            min_length=shortest, orientation=orientation)
        overlay = colour8(view.pixels) if picture is not None else None
        writer.write_rows(line_row(view.path, line, view.to_source) for line in found)
        if overlay is not None:
            draw_lines(overlay, found)
        if picture is not None and not _save_drawing(drawings, picture, view, overlay):
            failures.append(view.path)
    writer.close()
    if failures:
        sys.exit(1)


def _video_run(images: tuple[Path, ...], poses: str | None, time_mode: str,
               max_pose_gap: float, view_kwargs: dict[str, Any],
               frame_range: tuple[int, int | None, int] | None = None) -> Any:
    """The checked video run (:class:`~gsrwt_cli.cli.sequences.VideoRun`) when the only
    IMAGE is a video, else None (``--poses`` then refused)."""
    from .sequences import (
        given_options,
        open_video_run,
        refuse_for_video,
        refuse_poses_without_video,
        video_input,
    )

    video = video_input(images)
    if video is None:
        refuse_poses_without_video(poses, frame_range)
        return None
    refuse_for_video(video, given_options(click.get_current_context(), {
        "sidecar": "--sidecar", "draw": "--draw", "exif_orientation": "--exif-orientation"}))
    return open_video_run(video, poses, time_mode, max_pose_gap, view_defaults(view_kwargs),
                          frame_range=frame_range)


def template_models(templates: Iterable[Path], edge_threshold: float,
                    exif_orientation: str = "exif") -> list[tuple[Path, Template]]:
    """The GHT model of each ``--template`` file (every edge pixel of it, the edges of
    ``gsrwt lines``); a template that cannot be read is an error naming it."""
    models: list[tuple[Path, Template]] = []
    for path in templates:
        try:
            turn = 1 if exif_orientation == "ignore" else file_orientation(path)
            grey = grey8(read_image(path, orientation=turn))
            edges = line_edges(grey, edge_threshold,
                               orientation_smoothing=MATCH_ORIENTATION_SMOOTHING)
            models.append((path, build_template(grey, edges=edges)))
        except (ImageError, ValueError) as error:
            raise InputError(f"--template {path}: {error}") from None
    return models


def _parse_scales(text: str, steps: int) -> list[float]:
    try:
        low, high = (parse_decimal(v) for v in text.split(","))
    except ValueError:
        raise click.BadParameter(f"expected MIN,MAX, got {quote(text)}",
                                 param_hint="'--scales'") from None
    if not (0 < low <= high and math.isfinite(high)):
        raise click.BadParameter(f"expected 0 < MIN <= MAX, got {quote(text)}",
                                 param_hint="'--scales'")
    return list(np.linspace(low, high, steps)) if high > low else [low]


@click.command()
@images_argument
@click.option("--template", "templates", multiple=True, required=True,
              type=PathOrUrl(dir_okay=False),
              help="A frontal image of the object (its bounding box); repeatable.")
@raw_views_sidecar_option
@view_options
@click.option("--scales", default="0.9,1.1", show_default=True, metavar="MIN,MAX",
              help="Scale range to search around the expected scale 1 (the template at "
                   "frontal resolution).")
@click.option("--scale-steps", type=Integer(min=1), default=5, show_default=True)
@click.option("--min-score", type=Number(0, 1), default=0.6, show_default=True,
              help="Fraction of the model's edge pixels a match must find.")
@click.option("--max-matches", type=Integer(min=1), default=1, show_default=True,
              help="Matches per image and template.")
@functools.partial(edge_threshold_option, default=DEFAULT_MATCH_THRESHOLD,
                   text="High hysteresis threshold of the edges (as for gsrwt lines), in the "
                        "template and the views.")
@orientation_option
@draw_option("matches")
@pose_file_options("each frame is rectified with its pose first")
@frames_option
@format_option
def match(images: tuple[Path, ...], templates: tuple[Path, ...], sidecar: Path | None,
          scales: str, scale_steps: int, min_score: float, max_matches: int,
          edge_threshold: float, exif_orientation: str, draw: Path | None, poses: str | None,
          time_mode: str, max_pose_gap: float,
          frame_range: tuple[int, int | None, int] | None, fmt: str | None,
          **view_kwargs: Any) -> None:
    """Find objects (door knob, peek window) with the Generalized Hough Transform (Sec. 5.2.2).

    The model is every edge pixel of the template image (the edges of gsrwt lines), its
    centre the reference point;
    on frontal views one fixed model serves every camera angle. x, y: the object's centre
    in the frontal view; x_src, y_src: in the original image.

    A video as the only IMAGE (with --poses, or the view options for a fixed camera) gives
    each frame's matches, frame and time in front, status at the end (none: a template not
    found).

    \b
    Example:
      gsrwt match sample_data/views/door_p20_t-8_f800.jpg \\
          --template sample_data/templates/knob.png \\
          --sidecar sample_data/views/views.csv
    """
    scale_list = _parse_scales(scales, scale_steps)
    video = _video_run(images, poses, time_mode, max_pose_gap, view_kwargs, frame_range)
    models = template_models(templates, edge_threshold, exif_orientation)
    if video is not None:
        from ..tables.columns import MATCH_SEQUENCE_COLUMNS
        from .sequences import TemplateSearch, match_work, print_frame_rows

        search = TemplateSearch([(path.name, model) for path, model in models], scale_list,
                                min_score, max_matches, edge_threshold)
        print_frame_rows(video, match_work(video, search), MATCH_SEQUENCE_COLUMNS, fmt)
        return
    paths = _image_paths(images)
    views = _sources(paths, sidecar, view_kwargs, exif_orientation)
    drawings = _start_drawings(draw, [*paths, *templates, *([sidecar] if sidecar else [])])
    writer = TableWriter(sys.stdout, MATCH_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        picture = _drawing_target(drawings, view)
        if drawings is not None and picture is None:
            failures.append(view.path)
        edges = _edges(view, edge_threshold, MATCH_ORIENTATION_SMOOTHING)
        overlay = colour8(view.pixels) if picture is not None else None
        for path, model in models:
            found = match_template(view.pixels, model, scales=scale_list, edges=edges,
                                   min_score=min_score, max_matches=max_matches)
            writer.write_rows(match_row(view.path, path.name, item, view.to_source)
                              for item in found)
            if overlay is not None:
                draw_matches(overlay, model, found)
        if picture is not None and not _save_drawing(drawings, picture, view, overlay):
            failures.append(view.path)
    writer.close()
    if failures:
        sys.exit(1)
