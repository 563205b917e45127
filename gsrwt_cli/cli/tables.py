"""``gsrwt tables merge``: the tables of ``gsrwt rectify --shard K/N`` runs as one table."""

from __future__ import annotations

import contextlib
import io
import sys
from collections.abc import Iterator
from typing import IO

import click

from ..base.messages import quote
from ..io.outputs import open_atomic
from ..io.storage import Location, location
from ..tables.shards import (
    RECTIFY_TABLE,
    MergeError,
    order_shards,
    read_shard_table,
    write_merged,
)
from ..tables.writer import format_from_extension
from .options import InputError, prepare_table, quiet_option

MACHINE_FORMATS = ("csv", "tsv", "json", "jsonl")


def table_format(name: str, option: str) -> str:
    """The machine format a table's name asks for, or an :class:`InputError` naming it."""
    fmt = format_from_extension(name)
    if fmt not in MACHINE_FORMATS:
        raise InputError(f"{option}{quote(name)}: a table's name must end in .csv, .tsv, "
                         ".json or .jsonl")
    return fmt


@contextlib.contextmanager
def _output(name: str) -> Iterator[IO[str]]:
    if name == "-":
        yield sys.stdout
        return
    with open_atomic(location(name), "w", encoding="utf-8", errors="surrogateescape",
                     newline="") as stream:
        yield stream


def _input(name: str) -> IO[str]:
    """A table to read: a local file, or an object named by URL (read whole)."""
    found = location(name)
    if isinstance(found, Location):
        return io.StringIO(found.read_bytes().decode("utf-8", "surrogateescape"), newline="")
    return open(found, encoding="utf-8", errors="surrogateescape", newline="")


@click.group()
def tables() -> None:
    """Work with the tables gsrwt writes: merge the tables of --shard runs.

    \b
    Example:
      gsrwt rectify sample_data/views --sidecar sample_data/views/views.csv \\
          -o sharded --shard 1/2
      gsrwt rectify sample_data/views --sidecar sample_data/views/views.csv \\
          -o sharded --shard 2/2
      gsrwt tables merge sharded/gsrwt.1-of-2.csv sharded/gsrwt.2-of-2.csv \\
          -o sharded/gsrwt.csv
    """


@tables.command()
@click.argument("shard_tables", nargs=-1, required=True, metavar="TABLE...")
@click.option("-o", "--output", "output", required=True,
              help="The merged table (.csv, .tsv, .json, .jsonl; - for stdout); a path or a "
                   "URL, as are the TABLEs.")
@quiet_option("No summary.")
def merge(shard_tables: tuple[str, ...], output: str, quiet: bool) -> None:
    """Join the tables of `gsrwt rectify --shard K/N` runs into one, in input order.

    Tables named NAME.K-of-N.EXT are put in shard order, and all N must be given; other
    tables are joined in the order given. Each must be a table gsrwt rectify wrote: its
    columns, and in each cell what gsrwt writes there (else nothing is written).

    \b
    Example:
      gsrwt rectify sample_data/views --sidecar sample_data/views/views.csv \\
          -o sharded --shard 1/2
      gsrwt rectify sample_data/views --sidecar sample_data/views/views.csv \\
          -o sharded --shard 2/2
      gsrwt tables merge sharded/gsrwt.1-of-2.csv sharded/gsrwt.2-of-2.csv \\
          -o sharded/gsrwt.csv
    """
    out_format = "csv" if output == "-" else table_format(output, "-o ")
    try:
        ordered = order_shards(list(shard_tables))
    except MergeError as error:
        raise InputError(str(error)) from None
    if output != "-" and output in ordered:
        raise InputError(f"-o {output}: is one of the tables to merge; choose another path")
    prepare_table(output, "-o")
    schema = RECTIFY_TABLE
    parts = []
    for name in ordered:  # every table read and checked before anything is written
        fmt = table_format(name, "")
        try:
            with _input(name) as stream:
                parts.append(read_shard_table(name, stream, fmt, schema))
        except OSError as error:
            raise InputError(f"{name}: cannot read ({error.strerror or error})") from None
        except MergeError as error:
            raise InputError(str(error)) from None
    try:
        with _output(output) as stream:
            count = write_merged(parts, schema.columns, stream, out_format)
    except OSError as error:
        raise InputError(f"-o {output}: cannot write the table "
                         f"({error.strerror or error})") from None
    if not quiet:
        click.echo(f"gsrwt: {count} rows from {len(ordered)} tables", err=True)
