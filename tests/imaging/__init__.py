"""Tests of ``gsrwt_cli/imaging/``: decoding every sample type, warping, encoding."""
