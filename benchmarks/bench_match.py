"""Time of ``gsrwt match`` on a 640x480 frontal view (goal: under 0.2 s per view).

A 640x480 box of the rectified sample view ``door_p20_t-8_f800.jpg`` is searched for the
knob (40x100) and the peek window (120x90) models over 5 scales, as ``gsrwt match`` does
(edges of :func:`~gsrwt_cli.vision.edges.line_edges`, their time included); the best of
10 runs is reported, per template and for both, with OpenCV on one thread.

    python benchmarks/bench_match.py
"""

from __future__ import annotations

import time
from pathlib import Path

import cv2

from gsrwt_cli import View
from gsrwt_cli.api.rectify import Framing, rectify_image
from gsrwt_cli.vision.edges import line_edges
from gsrwt_cli.vision.ght import MATCH_ORIENTATION_SMOOTHING
from gsrwt_cli.vision.landmarks import build_template, match_template

SAMPLES = Path(__file__).resolve().parent.parent / "sample_data"


def main() -> None:
    cv2.setNumThreads(1)
    image = cv2.imread(str(SAMPLES / "views" / "door_p20_t-8_f800.jpg"))
    frontal, _ = rectify_image(image, View(20, -8, 800), Framing(bbox=(320, 100, 960, 580)))
    grey = cv2.cvtColor(frontal, cv2.COLOR_BGR2GRAY)
    assert grey.shape == (480, 640)
    templates = {}
    for name in ("knob", "window"):
        cut = cv2.imread(str(SAMPLES / "templates" / f"{name}.png"), cv2.IMREAD_GRAYSCALE)
        templates[name] = build_template(
            cut, edges=line_edges(cut, orientation_smoothing=MATCH_ORIENTATION_SMOOTHING))
    scales = (0.9, 0.95, 1.0, 1.05, 1.1)
    total = 0.0
    for name, template in templates.items():
        times = []
        for _ in range(10):
            start = time.perf_counter()
            (best,) = match_template(grey, template, scales=scales, max_matches=1,
                                     edges=line_edges(
                                         grey, orientation_smoothing=MATCH_ORIENTATION_SMOOTHING))
            times.append(time.perf_counter() - start)
        total += min(times)
        print(f"{name:7s} {template.width}x{template.height}: {min(times) * 1000:6.1f} ms  "
              f"(found at {best.x:.1f}, {best.y:.1f}, scale {best.scale:g}, score "
              f"{best.score:.2f})")
    print(f"both templates on one 640x480 view: {total * 1000:.1f} ms  (goal < 200 ms)")


if __name__ == "__main__":
    main()
