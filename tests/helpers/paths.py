"""Where the project's files are, the same for a test in any folder of ``tests/``."""

from __future__ import annotations

from pathlib import Path

#: The project's root: README.md, docs/, sample_data/, tests/.
ROOT = Path(__file__).resolve().parents[2]
#: Real data the tests use (tests/data/README.md says where each file comes from).
DATA = ROOT / "tests" / "data"
#: The sample data of the README: the corridor wall, its views and templates.
SAMPLE_DATA = ROOT / "sample_data"
#: The nine sample views and their sidecar, ``views.csv``.
SAMPLE_VIEWS = SAMPLE_DATA / "views"
