"""Tests of ``gsrwt_cli/geometry/``: the GS-RWT, rotations, the camera and its lens, the pixel
map, the output frame, gaze."""
