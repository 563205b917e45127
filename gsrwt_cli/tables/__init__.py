"""The public tables: their rows and columns, and the one writer.

Imports only: base, geometry, io, imaging, vision, inputs, api (tests/test_layers.py).
"""
