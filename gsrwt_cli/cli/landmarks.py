"""``gsrwt lines`` and ``gsrwt match``: door boundaries and door parts on frontal views."""

from __future__ import annotations

import math
import os
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
from ..messages import quote
from ..outputs import OutsideOutputError, write_atomic
from ..sidecar import SidecarError, load_sidecar
from ..tables import TableWriter
from .options import (
    InputError,
    format_option,
    make_output_directory,
    output_target,
    report_error,
    resolve_format,
    view_defaults,
    view_options,
)

LINES_COLUMNS = ("image", "rho", "theta_deg", "votes", "x1", "y1", "x2", "y2",
                 "x1_src", "y1_src", "x2_src", "y2_src")
MATCH_COLUMNS = ("image", "template", "x", "y", "scale", "votes", "score", "x_src", "y_src")


def _image_paths(images: tuple[Path, ...]) -> list[Path]:
    """The image files given and the images in the directories given (checked up front)."""
    paths: list[Path] = []
    for path in images:
        if path.is_dir():
            paths += [source.path for source in sources_from_directory(path, recursive=False)]
        elif path.is_file():
            paths.append(path)
        else:
            raise InputError(f"{path}: no such file or directory")
    return paths


def _sources(paths: list[Path], sidecar: Path | None, view_kwargs: dict[str, Any]):
    """Canonical views of ``paths``, with the parameters of ``sidecar`` and the options."""
    try:
        loaded = load_sidecar(sidecar) if sidecar is not None else None
    except SidecarError as error:
        raise InputError(str(error)) from None
    return canonical_views(paths, loaded, view_defaults(view_kwargs))


class Drawings:
    """Where ``--draw DIR`` puts the picture of each image: ``DIR/STEM.png``, inside DIR.

    A picture is refused (an error for that image, the others still drawn) when its file
    would lie outside DIR (a symbolic link in DIR leading out), would replace an input
    (an image, a template, the sidecar), or would replace the picture of an earlier image of
    the same run: ``a/door.jpg`` and ``b/door.png`` both draw to ``DIR/door.png``, and the
    second is refused rather than silently given another name or drawn over the first.
    """

    def __init__(self, directory: Path, inputs: Iterable[Path]) -> None:
        self.directory = directory
        self.protected = {os.path.realpath(path) for path in inputs}
        self.drawn: dict[str, Path] = {}  # real path of a picture -> the image it shows

    def target(self, image: Path) -> Path:
        """The picture's file for ``image``, or :class:`ValueError` saying why there is none."""
        target = self.directory / (image.stem + ".png")
        try:
            output_target(self.directory, target.name)
        except OutsideOutputError as error:
            raise ValueError(f"its picture {target} {error}") from None
        real = os.path.realpath(target)
        if real in self.protected:
            raise ValueError(f"its picture {target} would overwrite an input")
        if real in self.drawn:
            raise ValueError(f"its picture {target} would replace the picture of "
                             f"{self.drawn[real]} (same name); draw them in separate runs")
        self.drawn[real] = image
        return target

    def save(self, target: Path, overlay: np.ndarray) -> None:
        """Write the picture whole, inside the directory (or raise OSError, ValueError)."""
        write_atomic(target, encode_image(overlay, ".png"), root=self.directory)


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
        drawings.save(target, overlay)
    except (OSError, ValueError, ImageError) as error:
        reason = getattr(error, "strerror", None) or error
        report_error(f"{view.path}: --draw {target}: {reason}")
        return False
    return True


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
            report_error(f"{view[0]}: {view[1]}")
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
    paths = _image_paths(images)
    views = _sources(paths, sidecar, view_kwargs)
    drawings = _start_drawings(draw, [*paths, *([sidecar] if sidecar else [])])
    writer = TableWriter(sys.stdout, LINES_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        picture = _drawing_target(drawings, view)
        if drawings is not None and picture is None:
            failures.append(view.path)
        found = hough_lines(_grey8(view.pixels), edge_threshold=edge_threshold,
                            theta_step_deg=theta_step, min_votes=min_votes)
        overlay = _colour(view.pixels) if picture is not None else None
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
        if picture is not None and not _save_drawing(drawings, picture, view, overlay):
            failures.append(view.path)
    writer.close()
    if failures:
        sys.exit(1)


def _parse_scales(text: str, steps: int) -> list[float]:
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise click.BadParameter(f"expected MIN,MAX, got {quote(text)}",
                                 param_hint="'--scales'") from None
    if not (0 < low <= high and math.isfinite(high)):
        raise click.BadParameter(f"expected 0 < MIN <= MAX, got {quote(text)}",
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
      gsrwt match sample_data/views/door_p20_t-8_f800.jpg \\
          --template sample_data/templates/knob.png \\
          --sidecar sample_data/views/views.csv
    """
    scale_list = _parse_scales(scales, scale_steps)
    models: list[tuple[Path, Template]] = []
    for path in templates:
        try:
            models.append((path, build_template(_grey8(read_image(path)),
                                                edge_threshold=edge_threshold)))
        except (ImageError, ValueError) as error:
            raise InputError(f"--template {path}: {error}") from None
    paths = _image_paths(images)
    views = _sources(paths, sidecar, view_kwargs)
    drawings = _start_drawings(draw, [*paths, *templates, *([sidecar] if sidecar else [])])
    writer = TableWriter(sys.stdout, MATCH_COLUMNS, resolve_format(fmt))
    failures: list[Path] = []
    for view in _readable(views, failures):
        picture = _drawing_target(drawings, view)
        if drawings is not None and picture is None:
            failures.append(view.path)
        grey = _grey8(view.pixels)
        overlay = _colour(view.pixels) if picture is not None else None
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
        if picture is not None and not _save_drawing(drawings, picture, view, overlay):
            failures.append(view.path)
    writer.close()
    if failures:
        sys.exit(1)
