"""What every layer uses: how user data appears in messages (one line, escaped, bounded).

Imports only: no other layer (tests/test_layers.py).
"""
