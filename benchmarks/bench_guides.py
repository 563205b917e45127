"""Accuracy of guided correction (``--corners``, ``--verticals``/``--horizontals``) against
noise on the clicked points, on rectangles rendered through OpenCV's own camera.

``--shots`` rectangles (``tests/helpers/rectangles.py``: 1024x768, pans up to 40 degrees, tilts
up to 30, rolls up to 15, focal lengths 600-1600 px, aspect ratios 0.5-2, the rectangle 40-70 %
of the image's height), with Gaussian noise of each standard deviation on every corner
coordinate, solved three ways: focal length and aspect ratio both estimated, the focal length
given, the aspect ratio given. For each, the errors of pan, tilt and roll (the largest of
the three, degrees), of the focal length and of the aspect ratio (percent), median and 95th
percentile over the views not refused, and the share refused as too frontal. ``oblique``
keeps only views with ``|pan|`` and ``|tilt|`` of 15 degrees or more.

The yardstick is an exact least-squares fit of the same corners by another solver
(``scipy.optimize.least_squares`` over OpenCV's ``projectPoints``, started at the truth):
``vs LS`` is the 95th percentile of how much larger gsrwt's pose error is than the
yardstick's (degrees; 0 means as good). Then the guides: the rectangle's four sides as two
verticals and two horizontals, given the focal length, against the corners' pose.

    python benchmarks/bench_guides.py --shots 200
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the tests' helpers
from gsrwt_cli.geometry.guides import (  # noqa: E402
    GuideError,
    image_points,
    pose_from_corners,
    pose_from_segments,
)
from tests.helpers.rectangles import (  # noqa: E402
    RectangleShot,
    least_squares_pose,
    random_shots,
)

NOISES = (0.0, 0.25, 0.5, 1.0, 2.0)
MODES = ("estimated", "focal given", "aspect given")


def solve(shot: RectangleShot, noisy: np.ndarray, mode: str):
    points = image_points(noisy, shot.cx, shot.cy)
    return pose_from_corners(points, focal=shot.focal if mode == "focal given" else None,
                             aspect=shot.aspect if mode == "aspect given" else None)


def pose_error(shot: RectangleShot, pan: float, tilt: float, roll: float) -> float:
    return max(abs(pan - shot.pan), abs(tilt - shot.tilt), abs(roll - shot.roll))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shots", type=int, default=200)
    parser.add_argument("--seed", type=int, default=24)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    sets = {"all": random_shots(args.shots, args.seed),
            "oblique": random_shots(args.shots, args.seed + 1, min_angle=15.0)}
    print("| views | mode | noise px | pose err ° (median / 95 %) | focal err % | aspect err % "
          "| refused | vs LS ° (95 %) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, shots in sets.items():
        for mode in MODES:
            for noise in NOISES:
                pose_errors, focal_errors, aspect_errors, worse, refused = [], [], [], [], 0
                for shot in shots:
                    noisy = shot.corners + rng.normal(0.0, noise, shot.corners.shape)
                    try:
                        found = solve(shot, noisy, mode)
                    except GuideError:
                        refused += 1
                        continue
                    error = pose_error(shot, *found.pose)
                    pose_errors.append(error)
                    focal_errors.append(100 * abs(found.focal / shot.focal - 1))
                    aspect_errors.append(100 * abs(found.aspect / shot.aspect - 1))
                    if noise > 0:
                        best = least_squares_pose(shot, noisy, mode)
                        worse.append(error - pose_error(shot, *best[:3]))
                cells = [f"{np.median(v):.3g} / {np.percentile(v, 95):.3g}" if v else "-"
                         for v in (pose_errors, focal_errors, aspect_errors)]
                vs = f"{np.percentile(worse, 95):.2g}" if worse else "-"
                print(f"| {name} | {mode} | {noise:g} | {' | '.join(cells)} | "
                      f"{100 * refused / len(shots):.0f} % | {vs} |")
    print()
    print("| noise px | guides vs corners, focal given: pose difference ° (median / 95 %) |")
    print("|---|---|")
    for noise in NOISES:
        differences = []
        for shot in sets["all"]:
            noisy = shot.corners + rng.normal(0.0, noise, shot.corners.shape)
            points = image_points(noisy, shot.cx, shot.cy)
            corners = pose_from_corners(points, focal=shot.focal).pose
            verticals, horizontals = shot.sides(points)
            guides = pose_from_segments(verticals, horizontals, focal=shot.focal).pose
            differences.append(max(abs(a - b) for a, b in zip(corners, guides)))
        print(f"| {noise:g} | {np.median(differences):.3g} / "
              f"{np.percentile(differences, 95):.3g} |")


if __name__ == "__main__":
    main()
