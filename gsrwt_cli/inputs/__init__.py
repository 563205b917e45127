"""What the user gave: image files, records, sidecars, calibration files, EXIF, and which source of
parameters wins.

Imports only: base, geometry, io, imaging, vision (tests/test_layers.py).
"""
