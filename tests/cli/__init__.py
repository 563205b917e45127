"""Tests of ``gsrwt_cli/cli/``: one command end to end, through the installed ``gsrwt`` in a
real subprocess."""
