"""Tests of ``gsrwt_cli/tables/``: the public tables' rows, the one writer, shards."""
