"""Bytes in and out: local files and URLs (fsspec), outputs that appear whole, the files a command
may write, JPEG streams, metadata in image files, safe YAML.

Imports only: base, geometry (tests/test_layers.py).
"""
