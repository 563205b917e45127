"""Pixels: decode any depth and layout, warp with OpenCV, encode, scratch memory.

Imports only: base, geometry, io (tests/test_layers.py).
"""
