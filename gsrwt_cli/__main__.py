"""``python -m gsrwt_cli`` runs the ``gsrwt`` command."""

from .cli import run

run()
