"""The test suite: one folder per layer of ``gsrwt_cli`` (docs/DEVELOPMENT.md#tests)."""
