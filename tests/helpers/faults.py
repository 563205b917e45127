"""A batch under faults: photos worth interrupting, what a run leaves on disk, and the
processes that must be gone (shared by the fault suites of rectify, Dask and object storage)."""

from __future__ import annotations

import hashlib
import os
import subprocess
import time
from pathlib import Path

import cv2
import numpy as np

from tests.helpers.images import smooth_texture

#: A pose every photo of :func:`make_photos` is rectified with.
POSE = ("--pan", "20", "--tilt", "10", "--focal", "900")


def sha256_tree(root: Path) -> dict[str, str]:
    """Relative path -> sha256 of every file under ``root`` (symbolic links not followed)."""
    found = {}
    for path in sorted(root.rglob("*")):
        if path.is_file() and not path.is_symlink():
            found[str(path.relative_to(root))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def stray_files(root: Path) -> list[Path]:
    """Temporary or partial files left anywhere under ``root``."""
    return [p for p in root.rglob("*") if p.name.endswith(".part") or ".gsrwt-" in p.name]


def assert_clean_stderr(stderr: str, limit: int = 4000) -> None:
    assert "Traceback" not in stderr and "Warning" not in stderr, stderr
    assert len(stderr) < limit, stderr[:500]


def make_photos(folder: Path, count: int, size: tuple[int, int] = (1600, 1200)) -> list[Path]:
    """``count`` distinct JPEGs big enough that a batch of them takes a few seconds."""
    folder.mkdir(parents=True, exist_ok=True)
    base = cv2.resize(smooth_texture(300, 400, 3), size, interpolation=cv2.INTER_CUBIC)
    paths = []
    for index in range(count):
        path = folder / f"img{index:02d}.jpg"
        cv2.imwrite(str(path), np.roll(base, 29 * index, axis=1), [cv2.IMWRITE_JPEG_QUALITY, 90])
        paths.append(path)
    return paths


def wait_for_outputs(folder: Path, count: int, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if folder.is_dir() and len(list(folder.glob("img*.jpg"))) >= count:
            return
        time.sleep(0.02)
    raise AssertionError(f"fewer than {count} outputs appeared in {folder}")


def group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


def wait_until_gone(pgid: int, seconds: float = 15) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if not group_alive(pgid):
            return True
        time.sleep(0.05)
    return False


def assert_table_is_the_record(rows: list[dict[str, str]], out: Path, sources: list[Path]):
    """One row per source; every ``ok``/``skipped`` row's output exists, decodes, and has
    the row's size and full geometry; no other row has an output."""
    assert sorted(Path(row["image"]).name for row in rows) == sorted(p.name for p in sources)
    for row in rows:
        output = Path(row["output"])
        if not output.is_absolute():
            output = out.parent / output
        if row["status"] in ("ok", "skipped"):
            image = cv2.imread(str(output), cv2.IMREAD_UNCHANGED)
            assert image is not None, row
            assert (image.shape[1], image.shape[0]) == (int(row["out_width"]),
                                                        int(row["out_height"]))
            assert len(row["homography"].split()) == 9, row
        else:
            assert not output.exists(), row
