"""One image in memory: rectify it, estimate its pose (and draw the estimate).

Imports only: base, geometry, io, imaging, vision, inputs (tests/test_layers.py).
"""
