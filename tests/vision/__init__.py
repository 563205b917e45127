"""Tests of ``gsrwt_cli/vision/``: edges, Hough segments, GHT matches on frontal views."""
