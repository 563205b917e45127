"""``gsrwt render``: simulate what a camera at a given pan and tilt sees of a textured wall."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from ..imaging import (
    INTERPOLATIONS,
    ImageError,
    check_writable,
    encode_image,
    read_image,
)
from ..outputs import write_atomic
from ..render import render_view
from ..sidecar import RecordError, SidecarError, format_sidecar, load_sidecar, view_from_values
from .options import InputError, option_message, view_defaults, view_options


@click.command()
@click.argument("texture", type=click.Path(path_type=Path, dir_okay=False))
@view_options
@click.option("--sidecar", type=click.Path(path_type=Path, dir_okay=False),
              help="CSV or YAML of views to render, one per row (image = output name).")
@click.option("-o", "--output", "output", required=True, type=click.Path(path_type=Path),
              help="Output image (one view), or directory (with --sidecar).")
@click.option("--out-sidecar", type=click.Path(path_type=Path, dir_okay=False),
              help="Where to write the views' sidecar (.csv or .yaml) [default: OUTPUT's "
                   "NAME.yaml for one view, OUTPUT/views.csv with --sidecar].")
@click.option("--interpolation", type=click.Choice(tuple(INTERPOLATIONS)), default="linear",
              show_default=True)
@click.option("--fill", type=float, default=0.0, show_default=True,
              help="Value of pixels that see no texture.")
@click.option("--alpha", is_flag=True, help="Make pixels that see no texture transparent.")
@click.option("--quality", type=click.IntRange(1, 100), default=95, show_default=True,
              help="JPEG and WebP quality.")
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
      gsrwt render wall.png --sidecar views.csv -o rendered/
    """
    try:
        pixels = read_image(texture)
    except ImageError as error:
        raise InputError(f"{texture}: {error}") from None
    defaults = view_defaults(view_kwargs)
    defaults.setdefault("width", pixels.shape[1])
    defaults.setdefault("height", pixels.shape[0])
    if sidecar is None:
        if output.is_dir():
            raise InputError(f"-o {output}: is a directory; give an image file name")
        try:
            views = [(output.name, view_from_values(defaults, "options"), output)]
        except RecordError as error:
            raise InputError(option_message(error)) from None
        table_path = out_sidecar or output.with_suffix(".yaml")
        errors: list[str] = []
    else:
        try:
            records = load_sidecar(sidecar).records
        except SidecarError as error:
            raise InputError(str(error)) from None
        views, errors = [], []
        for record in records:
            try:
                views.append((record.image, record.view(defaults), output / record.image))
            except RecordError as error:
                errors.append(str(error))
        table_path = out_sidecar or output / "views.csv"
    targets = [target for _, _, target in views]
    protected = {texture.resolve()} | ({sidecar.resolve()} if sidecar else set())
    for target in [*targets, table_path]:
        if target.resolve() in protected:
            raise InputError(f"{target}: would overwrite an input; choose another output")
        if target.exists() and not overwrite:
            raise InputError(f"{target}: exists; use --overwrite to replace it")
    for message in errors:
        click.echo(f"Error: {message}", err=True)
    rows = []
    for name, view, target in views:
        try:
            channels = 4 if alpha else (1 if pixels.ndim == 2 else pixels.shape[2])
            check_writable(target.suffix, pixels.dtype, channels)
            image = render_view(pixels, view, interpolation=interpolation, fill=fill,
                                alpha=alpha)
            write_atomic(target, encode_image(image, target.suffix, quality))
        except (ImageError, ValueError, OSError) as error:
            errors.append(f"{target}: {error}")
            click.echo(f"Error: {target}: {error}", err=True)
            continue
        rows.append(
            {"image": name, "pan": view.pan, "tilt": view.tilt, "focal": view.focal,
             "cx": view.cx, "cy": view.cy, "width": view.width, "height": view.height,
             "distance": view.distance}
        )
    if rows:
        try:
            text = format_sidecar(table_path, rows)
        except SidecarError as error:
            raise InputError(str(error)) from None
        write_atomic(table_path, text.encode("utf-8"))
    if errors:
        sys.exit(1)
