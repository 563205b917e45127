"""Issue 23: ``gsrwt lines`` on real photos, measured against hand-labelled segments.

The York Urban training half (``../shared/data/york-urban-train``, skipped where absent):
one real run of ``gsrwt lines`` over its 51 photos with their true poses, scored as the
data's README says (``benchmarks/lines_measure.py`` reads the details; ``python
benchmarks/bench_lines_real.py`` prints the table). The floors are a little under what was
measured, so that a regression fails; the defaults before issue 23 (edges' orientation
blurred over 2 px, every segment kept) measured 0.461 / 0.537 / 0.425 and fail all three.

The other tests need no data set: straight edges in texture, the way a window frame sits in
a brick wall, and the gradient noise that sets how far each pixel's vote spreads.
"""

from __future__ import annotations

import subprocess
import sys

import cv2
import numpy as np
import pytest

from gsrwt_cli.vision.edges import line_edges
from gsrwt_cli.vision.hough import hough_lines
from tests.helpers.cli import lines_of
from tests.helpers.paths import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
import lines_measure  # noqa: E402

YORK = lines_measure.DEFAULT_ROOT
needs_york = pytest.mark.skipif(not (YORK / "truth.csv").is_file(),
                                reason=f"York Urban training half not at {YORK}")


@pytest.mark.slow
@needs_york
def test_york_urban_training_half_recall_and_precision(tmp_path):
    sidecar = lines_measure.write_sidecar(YORK, tmp_path / "views.csv")
    found = lines_of(*map(str, lines_measure.photos(YORK)), "--sidecar", str(sidecar))
    labels = lines_measure.read_labels(YORK)
    total = lines_measure.Score()
    for view in lines_measure.frontal_views(YORK, sidecar):
        rows = found.get(view.path.name, [])
        # The labels go into the frontal view through the view's own map: the same map,
        # to rounding, as a homography OpenCV fits to the reported lines' two sets of ends.
        assert not lines_measure.map_check_px(view, rows) > 1e-3, view.path
        shown = lines_measure.visible_labels(view, labels[view.path.name])
        total.add(lines_measure.score(shown, rows))
    print(f"York Urban training half: recall {total.recall:.3f} ({total.found}/"
          f"{total.long_vertical}), precision vertical {total.vertical_precision:.3f}, all "
          f"{total.precision:.3f}, {total.lines / 51:.1f} lines per photo")
    assert total.long_vertical == 1265 and total.lines >= 51 * 50
    assert total.recall >= 0.48  # measured 0.500 (before issue 23: 0.461)
    assert total.vertical_precision >= 0.56  # measured 0.579 (0.537)
    assert total.precision >= 0.46  # measured 0.481 (0.425)


@pytest.mark.slow
@needs_york
def test_york_urban_line_segment_detector_finds_less_than_gsrwt_lines(tmp_path):
    """OpenCV's line segment detector at its defaults (``bench_lines_real.py --detector
    lsd``), on the same frontal views: fewer labels found, and its lines less often on one
    (measured 0.477 / 0.466 / 0.379 against 0.500 / 0.579 / 0.481), so the recall ``gsrwt
    lines`` lacks is not there for the taking with the detector the pose estimate uses."""
    import bench_lines_real

    sidecar = lines_measure.write_sidecar(YORK, tmp_path / "views.csv")
    total = lines_measure.total(lines_measure.measure(
        YORK, sidecar, bench_lines_real.other_detector("lsd")))
    assert total.long_vertical == 1265
    assert total.recall <= 0.49
    assert total.vertical_precision <= 0.50
    assert total.precision <= 0.42


def test_other_detectors_say_what_to_install(tmp_path):
    """EDLines and the fast line detector are in OpenCV's contrib build only; where the
    installed OpenCV lacks them the benchmark says so in one line and installs nothing."""
    if hasattr(cv2, "ximgproc"):
        pytest.skip("this OpenCV has cv2.ximgproc")
    (tmp_path / "truth.csv").write_text("image,pan,tilt,roll,focal_px,cx,cy\n")
    result = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_lines_real.py"),
                             str(tmp_path), "--detector", "edlines"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 1
    assert result.stderr == (f"--detector edlines: needs cv2.ximgproc; install "
                             f"opencv-contrib-python-headless {cv2.__version__} in place of "
                             f"opencv-python-headless, in a venv of its own\n")


def textured(length: int, step: float, seed: int, height: int = 400,
             width: int = 200) -> np.ndarray:
    """Texture a few pixels across (grey levels of deviation 6, like brick or foliage) with a
    vertical step edge of ``step`` levels, ``length`` px long, at ``x = 99.5``."""
    rng = np.random.default_rng(seed)
    texture = cv2.GaussianBlur(rng.normal(0, 1, (height, width)).astype(np.float32), (0, 0), 1.5)
    image = 128 + texture * (6.0 / texture.std())
    top = (height - length) // 2
    image[top:top + length, 100:] += step
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def longest_at_the_step(image: np.ndarray) -> float:
    found = [line.length for line in hough_lines(image)
             if abs(line.x1 - 99.5) < 2 and abs(line.x2 - 99.5) < 2]
    return max(found, default=0.0)


def test_straight_edges_in_texture():
    """An edge in texture is found when it stands out of it: a long one at a lower contrast
    than a short one (the bar falls with the square root of the length). The 2-px blur of
    the edges' orientation before issue 23 mixed the texture into the edge's pixels: it
    found none of these edges."""
    for seed in range(6):
        assert longest_at_the_step(textured(300, 20, seed)) >= 100, seed
        assert longest_at_the_step(textured(60, 40, seed)) >= 50, seed
        assert longest_at_the_step(textured(60, 20, seed)) == 0, seed  # not out of the texture


def test_gradient_noise_is_measured_away_from_edges():
    """The deviation of each gradient component that noise gives, measured on a grid of
    strong lines (a fifth of the pixels are edges): it is what the filters make of white
    noise of the image's deviation (with the rounding to whole grey levels), from their
    impulse response."""
    impulse = np.zeros((31, 31), np.float32)
    impulse[15, 15] = 1.0
    response = cv2.GaussianBlur(cv2.Sobel(impulse, cv2.CV_32F, 1, 0, ksize=3), (0, 0), 1.0)
    gain = float(np.sqrt(np.sum(response.astype(np.float64) ** 2)))
    grid = np.full((300, 400), 120.0)
    grid[:, ::16] += 60
    grid[:, 1::16] += 60
    grid[::16, :] += 40
    grid = cv2.GaussianBlur(grid, (0, 0), 0.7)
    rng = np.random.default_rng(0)
    for sigma in (1.0, 2.0, 4.0):
        image = np.clip(np.rint(grid + rng.normal(0, sigma, grid.shape)), 0, 255)
        edges = line_edges(image.astype(np.uint8))
        assert edges.mask.mean() > 0.15
        expected = gain * np.sqrt(sigma**2 + 1 / 12)
        assert edges.gradient_noise == pytest.approx(expected, rel=0.05), sigma
