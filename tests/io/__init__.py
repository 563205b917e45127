"""Tests of ``gsrwt_cli/io/``: local files and URLs, whole-file outputs, where a command may
write, JPEG streams."""
