"""What the pixels show: edges, Hough segments, GHT matches, frontal-view pixels, their drawings.

Imports only: base, geometry, io, imaging (tests/test_layers.py).
"""
