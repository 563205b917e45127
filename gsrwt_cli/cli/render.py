"""``gsrwt render``: simulate what a camera at a given pan and tilt sees of a textured wall."""

from __future__ import annotations

import os
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
from ..messages import escape_controls, quote, shorten
from ..outputs import OutsideOutputError, relative_output, write_atomic
from ..render import render_view
from ..sidecar import RecordError, SidecarError, format_sidecar, load_sidecar, view_from_values
from .options import (
    InputError,
    make_output_directory,
    option_message,
    output_target,
    report_error,
    view_defaults,
    view_options,
)

#: Characters of a sidecar row's description (``views.yaml record 'NAME'``) in a message.
WHERE_LIMIT = 160


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
    errors: list[str] = []
    if sidecar is None:
        if output.is_dir():
            raise InputError(f"-o {output}: is a directory; give an image file name")
        try:
            views = [(output.name, view_from_values(defaults, "options"), output)]
        except RecordError as error:
            raise InputError(option_message(error)) from None
        table_path = out_sidecar or output.with_suffix(".yaml")
        root = None  # a file the user named: written where they said
    else:
        try:
            records = load_sidecar(sidecar).records
        except SidecarError as error:
            raise InputError(str(error)) from None
        if output.exists() and not output.is_dir():
            raise InputError(f"-o {output}: exists and is not a directory")
        table_path = out_sidecar or output / "views.csv"
        views = []
        claimed: dict[str, str] = {os.path.realpath(table_path): "the views' sidecar"}
        for record in records:
            try:
                target = sidecar_target(output, record.image, claimed, record.where)
                views.append((record.image, record.view(defaults), target))
            except RecordError as error:
                errors.append(str(error))
        root = output
    protected = {os.path.realpath(texture)} | ({os.path.realpath(sidecar)} if sidecar else set())
    for message in errors:
        report_error(message)
    for target in [*(target for _, _, target in views), table_path]:
        if os.path.realpath(target) in protected:
            raise InputError(f"{target}: would overwrite an input; choose another output")
        if os.path.lexists(target) and not overwrite:
            raise InputError(f"{target}: exists; use --overwrite to replace it")
    if root is not None and views:
        make_output_directory("-o", root)  # before the first write: the rule needs the root
    rows = []
    channels = 4 if alpha else (1 if pixels.ndim == 2 else pixels.shape[2])
    for name, view, target in views:
        try:
            check_writable(target.suffix, pixels.dtype, channels)
            image = render_view(pixels, view, interpolation=interpolation, fill=fill,
                                alpha=alpha)
            write_atomic(target, encode_image(image, target.suffix, quality), root=root)
        except (ImageError, ValueError, OSError) as error:
            reason = getattr(error, "strerror", None) or error
            errors.append(f"{target}: {reason}")
            report_error(f"{target}: {reason}")
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
        try:
            write_atomic(table_path, text.encode("utf-8"))
        except OSError as error:
            raise InputError(f"--out-sidecar {table_path}: cannot write it "
                             f"({error.strerror or error})") from None
    if errors:
        sys.exit(1)


def sidecar_target(output: Path, image: str, claimed: dict[str, str], where: str) -> Path:
    """Where the sidecar row ``image`` is rendered: inside ``output``, or a :class:`RecordError`.

    The name must be relative, without ``..``, lead through no symbolic link out of
    ``output`` (:func:`~.options.output_target`), and not be the file of an earlier row or
    of the views' sidecar: ``claimed`` maps the real paths taken so far to what took them.
    """
    where = shorten(escape_controls(where), WHERE_LIMIT)  # a YAML key may be any length
    try:
        target = output_target(output, relative_output(image))
    except OutsideOutputError as error:
        reason = str(error)
        verb = "is " if reason.startswith("not ") else ""
        raise RecordError(where, "image", f"{quote(image)} {verb}{reason}") from None
    real = os.path.realpath(target)
    if real in claimed:
        raise RecordError(where, "image",
                          f"{quote(image)} is the same file as {claimed[real]}; give another name")
    claimed[real] = where
    return target
