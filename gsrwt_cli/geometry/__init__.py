"""Pure geometry, no I/O: the GS-RWT, rotations, the camera and its lens, the pixel map, the output
frame, gaze.

Imports only: base (tests/test_layers.py).
"""
