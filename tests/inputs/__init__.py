"""Tests of ``gsrwt_cli/inputs/``: input files, records, sidecars, calibration files, EXIF,
which source of parameters wins."""
