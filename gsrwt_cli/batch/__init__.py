"""Many images: executors (processes, Dask), the rectify, estimate and render jobs, frontal views of
files.

Imports only: base, geometry, io, imaging, vision, inputs, api, tables (tests/test_layers.py).
"""
