"""``gsrwt params``: the GS-RWT parameter table of one view or of every row of a sidecar."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from ..records import RecordError
from ..report import PARAMS_COLUMNS, params_row
from ..sidecar import SidecarError, load_sidecar
from ..tables import write_table
from .options import (
    InputError,
    format_option,
    report_error,
    resolve_format,
    view_defaults,
    view_from_options,
    view_options,
)


@click.command()
@view_options
@click.option(
    "--sidecar",
    type=click.Path(path_type=Path, dir_okay=False),
    help="CSV or YAML of views, one row per image; options above fill fields it leaves out.",
)
@format_option
def params(sidecar: Path | None, fmt: str | None, **kwargs: Any) -> None:
    """Print the GS-RWT parameters (theta, delta, a, gamma, vanishing point and line).

    For one view given by options, or for every row of a sidecar file.

    \b
    Examples:
      gsrwt params --pan 15 --tilt 30 --focal 280 --width 320 --height 240
      gsrwt params --sidecar sample_data/views/views.csv --format json
    """
    defaults = view_defaults(kwargs)
    rows = []
    if sidecar is None:
        rows.append(params_row(view_from_options(defaults)))
    else:
        try:
            records = load_sidecar(sidecar).records
        except SidecarError as error:
            raise InputError(str(error)) from None
        errors = []
        for record in records:
            try:
                rows.append(params_row(record.view(defaults), record.image))
            except RecordError as error:
                errors.append(str(error))
        if errors:
            for message in errors[:-1]:
                report_error(message)
            raise InputError(errors[-1])
    write_table(sys.stdout, PARAMS_COLUMNS, rows, resolve_format(fmt))
