"""``gsrwt lines`` on real photos: recall and precision against the York Urban labels, time.

Measures as the data's README defines them (``benchmarks/lines_measure.py`` says how the
details are read): recall of the labelled vertical segments longer than 40 px in the frontal
view, precision of the vertical and of all reported lines against the labels, lines per
image; each photo rectified with its true pose, then the edge and Hough stages of ``gsrwt
lines`` at its defaults, in this process with OpenCV on one thread: CPU and wall-clock time
per image (median and mean; the CPU time is the steadier on a shared machine).
Issue 23's goal on the held-back half: recall >= 0.75, precision >= 0.55 (vertical) and
>= 0.45 (all).

``--cli`` runs the real command once over the photos instead (``gsrwt lines --sidecar
... --format csv``) and scores its output, and checks the labels' map against the reported
lines' source ends (:func:`lines_measure.map_check_px`).

``--detector`` scores another of OpenCV's line detectors on the same frontal views, each at
its defaults, keeping its segments of :data:`OTHER_MIN_LENGTH` px and more with both ends
on pixels the photo shows: ``lsd`` (the line segment detector the pose estimate uses),
``edlines`` (EDLines, ``cv2.ximgproc.EdgeDrawing``) and ``fld`` (the fast line detector,
``cv2.ximgproc.FastLineDetector``). The last two are in ``opencv-contrib-python-headless``,
which replaces gsrwt's ``opencv-python-headless`` (same version): install it in a venv of its
own.

    python benchmarks/bench_lines_real.py [YORK_DIR] [--per-image] [--cli]
    python benchmarks/bench_lines_real.py [YORK_DIR] --detector {lsd,edlines,fld}
"""

from __future__ import annotations

import argparse
import csv
import io
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import lines_measure  # noqa: E402

from gsrwt_cli.batch.canonical_views import CanonicalView  # noqa: E402
from gsrwt_cli.vision.edges import grey8  # noqa: E402
from gsrwt_cli.vision.frontal_pixels import frontal_edges, seen  # noqa: E402
from gsrwt_cli.vision.hough import hough_lines  # noqa: E402

#: The shortest segment kept of the other detectors (px in the frontal view).
OTHER_MIN_LENGTH = 30.0


def lines_in_process(view: CanonicalView) -> list:
    """What ``gsrwt lines`` at its defaults finds on ``view`` (its edge and Hough stages)."""
    edges = frontal_edges(grey8(view.pixels), view.pixel_map, view.source_size)
    return hough_lines(view.pixels, edges=edges)


def other_detector(name: str):
    """``find_lines(view)`` with OpenCV's detector ``name`` at its defaults (module docstring),
    or exit with a line saying what to install."""
    if name != "lsd" and not hasattr(cv2, "ximgproc"):
        sys.exit(f"--detector {name}: needs cv2.ximgproc; install opencv-contrib-python-headless "
                 f"{cv2.__version__} in place of opencv-python-headless, in a venv of its own")

    def detect(grey: np.ndarray) -> np.ndarray | None:
        if name == "lsd":
            return cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD).detect(grey)[0]
        if name == "fld":
            return cv2.ximgproc.createFastLineDetector().detect(grey)
        drawing = cv2.ximgproc.createEdgeDrawing()
        drawing.detectEdges(grey)
        return drawing.detectLines()

    def find_lines(view: CanonicalView) -> list[SimpleNamespace]:
        found = detect(grey8(view.pixels))
        if found is None:
            return []
        ends = found.reshape(-1, 4).astype(np.float64)
        shown = seen(view.pixel_map, view.source_size)
        height, width = shown.shape
        cols = np.clip(np.rint(ends[:, [0, 2]]).astype(int), 0, width - 1)
        rows = np.clip(np.rint(ends[:, [1, 3]]).astype(int), 0, height - 1)
        keep = (np.hypot(ends[:, 2] - ends[:, 0], ends[:, 3] - ends[:, 1]) >= OTHER_MIN_LENGTH) \
            & shown[rows, cols].all(axis=1)
        return [SimpleNamespace(x1=x1, y1=y1, x2=x2, y2=y2) for x1, y1, x2, y2 in ends[keep]]

    return find_lines


def lines_of_cli(root: Path, sidecar: Path) -> dict[str, list[SimpleNamespace]]:
    """One run of ``gsrwt lines`` over the photos: its rows per image name."""
    command = [str(Path(sys.executable).with_name("gsrwt")), "lines",
               *map(str, lines_measure.photos(root)), "--sidecar", str(sidecar),
               "--format", "csv"]
    result = subprocess.run(command, capture_output=True, text=True, check=True)
    found: dict[str, list[SimpleNamespace]] = {}
    for row in csv.DictReader(io.StringIO(result.stdout)):
        values = {key: float(value) for key, value in row.items() if key != "image" and value}
        found.setdefault(Path(row["image"]).name, []).append(SimpleNamespace(**values))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", nargs="?", type=Path, default=lines_measure.DEFAULT_ROOT,
                        help="the York Urban folder (truth.csv, segments.csv, images/)")
    parser.add_argument("--per-image", action="store_true", help="a row per photo")
    parser.add_argument("--cli", action="store_true",
                        help="score one real run of gsrwt lines instead (no timing)")
    parser.add_argument("--detector", choices=("lsd", "edlines", "fld"),
                        help="score another of OpenCV's line detectors instead")
    args = parser.parse_args()
    if not (args.root / "truth.csv").is_file():
        sys.exit(f"{args.root}: no truth.csv (give the York Urban folder)")
    cv2.setNumThreads(1)
    with tempfile.TemporaryDirectory() as folder:
        sidecar = lines_measure.write_sidecar(args.root, Path(folder) / "views.csv")
        if args.cli:
            found = lines_of_cli(args.root, sidecar)
            worst_map = 0.0
            for view in lines_measure.frontal_views(args.root, sidecar):
                check = lines_measure.map_check_px(view, found.get(view.path.name, []))
                worst_map = max(worst_map, check) if check == check else worst_map
            measured = list(lines_measure.measure(args.root, sidecar,
                                                  lambda view: found.get(view.path.name, [])))
            print(f"labels' map against the lines' own source ends: {worst_map:.2g} px at worst")
        else:
            find_lines = lines_in_process if args.detector is None else \
                other_detector(args.detector)
            measured = list(lines_measure.measure(args.root, sidecar, find_lines))
    if args.per_image:
        print(f"{'image':14} {'recall':>11} {'vertical':>11} {'all':>11}")
        for item in measured:
            s = item.score
            print(f"{item.name:14} {s.found:4}/{s.long_vertical:<4}  {s.vertical_on_labels:4}/"
                  f"{s.vertical_lines:<4}  {s.on_labels:4}/{s.lines:<4}")
    total = lines_measure.total(measured)
    print(f"{args.detector or 'gsrwt lines'} on York Urban ({args.root.name}): "
          f"{len(measured)} photos, "
          f"{total.long_vertical} long vertical labels")
    print(f"recall (long verticals)  {total.recall:.3f}  ({total.found}/{total.long_vertical})")
    print(f"precision vertical       {total.vertical_precision:.3f}  "
          f"({total.vertical_on_labels}/{total.vertical_lines})")
    print(f"precision all            {total.precision:.3f}  ({total.on_labels}/{total.lines})")
    print(f"  stricter: within a label {total.strict_vertical_precision:.3f} / "
          f"{total.strict_precision:.3f} (vertical / all; ends within 2 px of the label itself)")
    print(f"lines per image          {total.lines / max(len(measured), 1):.1f}")
    if not args.cli:
        cpu = [item.cpu_s * 1000 for item in measured]
        wall = [item.wall_s * 1000 for item in measured]
        print(f"time per image (ms)      CPU median {statistics.median(cpu):.0f}, mean "
              f"{statistics.mean(cpu):.0f}; wall median {statistics.median(wall):.0f}")


if __name__ == "__main__":
    main()
