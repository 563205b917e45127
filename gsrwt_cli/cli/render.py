"""``gsrwt render``: simulate what a camera at a given pan and tilt sees of a textured wall."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from ..batch.render_jobs import plan_one_view, plan_views, render_views, write_views_sidecar
from ..imaging.images import ImageError, read_image
from ..inputs.records import RecordError
from ..inputs.sidecar import SidecarError, load_sidecar
from ..io.targets import NotADirectoryTargetError, TargetError, UncreatableDirectoryError
from .options import (
    InputError,
    LocalPath,
    Number,
    PathOrUrl,
    interpolation_option,
    option_message,
    quality_option,
    report_error,
    target_message,
    view_defaults,
    view_options,
)


@click.command()
@click.argument("texture", type=PathOrUrl(dir_okay=False))
@view_options
@click.option("--sidecar", type=PathOrUrl(dir_okay=False),
              help="CSV or YAML of views to render, one per row (image = output name).")
@click.option("-o", "--output", "output", required=True, type=LocalPath(),
              help="Output image (one view), or directory (with --sidecar).")
@click.option("--out-sidecar", type=LocalPath(dir_okay=False),
              help="Where to write the views' sidecar (.csv or .yaml) [default: OUTPUT's "
                   "NAME.yaml for one view, OUTPUT/views.csv with --sidecar].")
@interpolation_option
@click.option("--fill", type=Number(), default=0.0, show_default=True,
              help="Value of pixels that see no texture.")
@click.option("--alpha", is_flag=True, help="Make pixels that see no texture transparent.")
@quality_option
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
def render(
    texture: Path, sidecar: Path | None, output: Path, out_sidecar: Path | None,
    interpolation: str, fill: float, alpha: bool, quality: int, overwrite: bool,
    **view_kwargs: Any,
) -> None:
    """Render the view of a camera at --pan/--tilt of a wall covered by TEXTURE.

    TEXTURE is a frontal image of the wall; its centre is where the perpendicular from the
    camera meets the wall, one texture pixel per Zc/f wall units, so `gsrwt rectify` of the
    render gives the texture back. Writes the image(s) and the sidecar that rectify reads.
    The image size defaults to the texture's.

    \b
    Examples:
      gsrwt render sample_data/corridor_wall.png --pan 15 --tilt 30 --focal 280 \\
          --width 320 --height 240 -o view.png
      gsrwt render sample_data/corridor_wall.png --sidecar sample_data/views/views.csv \\
          -o rendered
    """
    try:
        pixels = read_image(texture)
    except ImageError as error:
        raise InputError(f"{texture}: {error}") from None
    defaults = view_defaults(view_kwargs)
    defaults.setdefault("width", pixels.shape[1])
    defaults.setdefault("height", pixels.shape[0])
    try:
        if sidecar is None:
            plan = plan_one_view(defaults, output, out_sidecar)
        else:
            records = load_sidecar(sidecar).records
            plan = plan_views(records, output, defaults, out_sidecar)
    except RecordError as error:  # of the view options: a sidecar's are in plan.errors
        raise InputError(option_message(error)) from None
    except SidecarError as error:
        raise InputError(str(error)) from None
    except TargetError as error:
        raise InputError(target_message(error, "-o")) from None
    for problem in plan.errors:
        report_error(str(problem))
    try:
        results = render_views(pixels, plan, inputs=[texture, *([sidecar] if sidecar else [])],
                               overwrite=overwrite, interpolation=interpolation, fill=fill,
                               alpha=alpha, quality=quality)
    except (NotADirectoryTargetError, UncreatableDirectoryError) as error:  # creating -o
        raise InputError(target_message(error, "-o")) from None
    except TargetError as error:
        raise InputError(target_message(error)) from None
    failed = bool(plan.errors)
    rendered = []
    for result in results:
        if result.error is None:
            rendered.append(result.job)
        else:
            failed = True
            report_error(f"{result.job.target}: {result.error}")
    if rendered:
        try:
            write_views_sidecar(plan.sidecar, rendered)
        except SidecarError as error:
            raise InputError(str(error)) from None
        except TargetError as error:
            raise InputError(target_message(error, "--out-sidecar")) from None
    if failed:
        sys.exit(1)
