"""Tests of ``gsrwt_cli/api/``: one image in memory: rectify it, estimate its pose."""
