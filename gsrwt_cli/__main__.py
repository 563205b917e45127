"""``python -m gsrwt_cli`` runs the ``gsrwt`` command."""

from .cli import main

main(prog_name="gsrwt")
