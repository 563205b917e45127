"""Tests of ``gsrwt_cli/base/``: how values appear in messages."""
