"""``gsrwt lines`` and ``gsrwt match``: door boundaries and door parts on frontal views."""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import click
import cv2
import numpy as np

from ..batch import sources_from_directory
from ..canonical import CanonicalView, canonical_views
from ..imaging import ImageError, encode_image, read_image
from ..landmarks import (
    DEFAULT_EDGE_THRESHOLD,
    DEFAULT_MIN_VOTES,
    DEFAULT_THETA_STEP_DEG,
    Template,
    build_template,
    hough_lines,
    match_template,
)
from ..outputs import write_atomic
from ..sidecar import SidecarError, load_sidecar
from ..tables import TableWriter
from .options import InputError, format_option, resolve_format, view_defaults, view_options

LINES_COLUMNS = ("image", "rho", "theta_deg", "votes", "x1", "y1", "x2", "y2",
                 "x1_src", "y1_src", "x2_src", "y2_src")
MATCH_COLUMNS = ("image", "template", "x", "y", "scale", "votes", "score", "x_src", "y_src")


def _sources(images: tuple[Path, ...], sidecar: Path | None, view_kwargs: dict[str, Any]):
    """Canonical views of image files and of the images in directories (checked up front)."""
    paths: list[Path] = []
    for path in images:
        if path.is_dir():
            paths += [source.path for source in sources_from_directory(path, recursive=False)]
        elif path.is_file():
            paths.append(path)
        else:
            raise InputError(f"{path}: no such file or directory")
    try:
        loaded = load_sidecar(sidecar) if sidecar is not None else None
    except SidecarError as error:
        raise InputError(str(error)) from None
    return canonical_views(paths, loaded, view_defaults(view_kwargs))


def _draw_target(draw: Path | None, images: tuple[Path, ...]) -> None:
    if draw is None:
        return
    for image in images:
        if (draw / image.name).resolve() == image.resolve():
            raise InputError(f"--draw {draw}: would overwrite the input {image}")


def _save_overlay(draw: Path, view: CanonicalView, overlay: np.ndarray) -> None:
    write_atomic(draw / (view.path.stem + ".png"), encode_image(overlay, ".png"))


def _colour(pixels: np.ndarray) -> np.ndarray:
    if pixels.dtype != np.uint8:
        pixels = cv2.convertScaleAbs(pixels, alpha=255.0 / float(np.iinfo(pixels.dtype).max))
    if pixels.ndim == 2:
        return cv2.cvtColor(pixels, cv2.COLOR_GRAY2BGR)
    return pixels[..., :3].copy()


def _grey8(pixels: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(_colour(pixels), cv2.COLOR_BGR2GRAY)


def _readable(
    views: Iterable[CanonicalView | tuple[Path, str]], failures: list[Path]
) -> Iterator[CanonicalView]:
    """The views that could be read (and rectified); the others are reported in one line each
    and collected in ``failures``."""
    for view in views:
        if isinstance(view, tuple):
            failures.append(view[0])
            click.echo(f"Error: {view[0]}: {view[1]}", err=True)
        else:
            yield view


@click.command()
@click.argument("images", nargs=-1, required=True, type=click.Path(path_type=Path),
                metavar="IMAGE...")
@click.option("--sidecar", type=click.Path(path_type=Path, dir_okay=False),
              help="Parameters of raw views (as for rectify); images without are taken as "
                   "frontal already.")
@view_options
@click.option("--edge-threshold", type=float, default=DEFAULT_EDGE_THRESHOLD, show_default=True,
              help="Sobel magnitude of an edge pixel.")
@click.option("--theta-step", type=float, default=DEFAULT_THETA_STEP_DEG, show_default=True,
              help="Orientation sampling, degrees.")
@click.option("--min-votes", type=click.IntRange(min=1), default=DEFAULT_MIN_VOTES,
              show_default=True, help="Votes a line needs.")
@click.option("--draw", type=click.Path(path_type=Path, file_okay=False),
              help="Write the frontal views with the lines drawn into this directory.")
@format_option
def lines(images: tuple[Path, ...], sidecar: Path | None, edge_threshold: float,
          theta_step: float, min_votes: int, draw: Path | None, fmt: str | None,
          **view_kwargs: Any) -> None:
    """Straight lines (door boundaries) by the Hough transform on frontal views (Sec. 5.2.2).

    Each edge pixel (3x3 Sobel) votes once, at its own gradient orientation. x1..y2 are
    the segment's end points in the frontal view, x1_src..y2_src in the original image.

    \b
    Example:
      gsrwt lines sample_data/views/corridor_p30_t15.png --sidecar sample_data/views/views.csv
    """
    _draw_target(draw, images)
    views = _sources(images, sidecar, view_kwargs)
    writer = TableWriter(sys.stdout, LINES_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        found = hough_lines(_grey8(view.pixels), edge_threshold=edge_threshold,
                            theta_step_deg=theta_step, min_votes=min_votes)
        overlay = _colour(view.pixels) if draw is not None else None
        for line in found:
            row = {"image": str(view.path), "rho": line.rho, "theta_deg": line.theta_deg,
                   "votes": line.votes, "x1": line.x1, "y1": line.y1, "x2": line.x2,
                   "y2": line.y2}
            source = view.to_source(np.array([[line.x1, line.y1], [line.x2, line.y2]]))
            if source is not None:
                row.update(x1_src=source[0, 0], y1_src=source[0, 1], x2_src=source[1, 0],
                           y2_src=source[1, 1])
            writer.write_row(row)
            if overlay is not None:
                ends = np.round([[line.x1, line.y1], [line.x2, line.y2]]).astype(int)
                cv2.line(overlay, tuple(ends[0]), tuple(ends[1]), (0, 0, 255), 2, cv2.LINE_AA)
        if overlay is not None:
            _save_overlay(draw, view, overlay)
    writer.close()
    if failures:
        sys.exit(1)


def _parse_scales(text: str, steps: int) -> list[float]:
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise click.BadParameter(f"expected MIN,MAX, got {text!r}",
                                 param_hint="'--scales'") from None
    if not (0 < low <= high and math.isfinite(high)):
        raise click.BadParameter(f"expected 0 < MIN <= MAX, got {text!r}",
                                 param_hint="'--scales'")
    return list(np.linspace(low, high, steps)) if high > low else [low]


@click.command()
@click.argument("images", nargs=-1, required=True, type=click.Path(path_type=Path),
                metavar="IMAGE...")
@click.option("--template", "templates", multiple=True, required=True,
              type=click.Path(path_type=Path, dir_okay=False),
              help="A frontal image of the object (its bounding box); repeatable.")
@click.option("--sidecar", type=click.Path(path_type=Path, dir_okay=False),
              help="Parameters of raw views (as for rectify); images without are taken as "
                   "frontal already.")
@view_options
@click.option("--scales", default="0.9,1.1", show_default=True, metavar="MIN,MAX",
              help="Scale range to search around the expected scale 1 (the template at "
                   "frontal resolution).")
@click.option("--scale-steps", type=click.IntRange(min=1), default=5, show_default=True)
@click.option("--min-score", type=click.FloatRange(0, 1), default=0.6, show_default=True,
              help="Fraction of the model's edge pixels a match must find.")
@click.option("--max-matches", type=click.IntRange(min=1), default=1, show_default=True,
              help="Matches per image and template.")
@click.option("--edge-threshold", type=float, default=DEFAULT_EDGE_THRESHOLD, show_default=True,
              help="Sobel magnitude of an edge pixel.")
@click.option("--draw", type=click.Path(path_type=Path, file_okay=False),
              help="Write the frontal views with the matches drawn into this directory.")
@format_option
def match(images: tuple[Path, ...], templates: tuple[Path, ...], sidecar: Path | None,
          scales: str, scale_steps: int, min_score: float, max_matches: int,
          edge_threshold: float, draw: Path | None, fmt: str | None,
          **view_kwargs: Any) -> None:
    """Find objects (door knob, peek window) with the Generalized Hough Transform (Sec. 5.2.2).

    The model is every edge pixel of the template image, its centre the reference point;
    on frontal views one fixed model serves every camera angle. x, y: the object's centre
    in the frontal view; x_src, y_src: in the original image.

    \b
    Example:
      gsrwt match sample_data/views/door_p20_t-8_f800.jpg --template knob.png \\
          --sidecar sample_data/views/views.csv
    """
    _draw_target(draw, images)
    scale_list = _parse_scales(scales, scale_steps)
    models: list[tuple[Path, Template]] = []
    for path in templates:
        try:
            models.append((path, build_template(_grey8(read_image(path)),
                                                edge_threshold=edge_threshold)))
        except (ImageError, ValueError) as error:
            raise InputError(f"--template {path}: {error}") from None
    views = _sources(images, sidecar, view_kwargs)
    writer = TableWriter(sys.stdout, MATCH_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        grey = _grey8(view.pixels)
        overlay = _colour(view.pixels) if draw is not None else None
        for path, model in models:
            found = match_template(grey, model, scales=scale_list, edge_threshold=edge_threshold,
                                   min_score=min_score, max_matches=max_matches)
            for item in found:
                row = {"image": str(view.path), "template": path.name, "x": item.x, "y": item.y,
                       "scale": item.scale, "votes": item.votes, "score": item.score}
                source = view.to_source(np.array([[item.x, item.y]]))
                if source is not None:
                    row.update(x_src=source[0, 0], y_src=source[0, 1])
                writer.write_row(row)
                if overlay is not None:
                    half = np.array([model.width, model.height]) * item.scale / 2
                    corner0 = np.round([item.x, item.y] - half).astype(int)
                    corner1 = np.round([item.x, item.y] + half).astype(int)
                    cv2.rectangle(overlay, tuple(corner0), tuple(corner1), (0, 0, 255), 2)
        if overlay is not None:
            _save_overlay(draw, view, overlay)
    writer.close()
    if failures:
        sys.exit(1)
