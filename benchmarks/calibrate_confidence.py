"""Calibrate ``gsrwt estimate``'s confidence on real photos: the probability that the estimate
is within 2 degrees of the truth (vertical and wall normal), fitted on the York Urban DB's
training half (``../shared/data/york-urban-train``), with and without the focal length.

The confidence is a logistic function of two measures the estimator makes of each photo
(:func:`gsrwt_cli.api.estimate.confidence_of`): ``rival``, how nearly a different frame
explains the segments as well as the one chosen (:class:`~gsrwt_cli.api.estimate.
ManhattanFrame`), and, where the focal length was estimated, how many degrees its standard
deviation turns the pose (:class:`~gsrwt_cli.api.estimate.FocalUncertainty`). This script
fits the weights by maximum likelihood (Newton's method, a weak prior against overfitting)
over the photos the estimator does not refuse, and prints them with the reliability table
(per confidence bin, the photos and the fraction within 2 degrees) before and after.

    python benchmarks/calibrate_confidence.py [PATH-TO-york-urban-train]

Copy the weights it prints into ``CONFIDENCE_WEIGHTS`` in gsrwt_cli/api/estimate.py.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_real_photos as bench  # noqa: E402
import real_photos as measure  # noqa: E402

from gsrwt_cli.api.estimate import confidence_features, estimate_pose  # noqa: E402
from gsrwt_cli.geometry.camera import Intrinsics  # noqa: E402


def photo_measures(data: Path) -> list[tuple[str, np.ndarray, bool, float]]:
    """Per photo and run (focal given, focal estimated) that the estimator does not refuse:
    the run, its features, whether within 2 degrees on both measures, the old confidence."""
    rows = []
    for image, truth in sorted(bench.read_truth(data).items()):
        picture = cv2.imread(str(data / "images" / image), cv2.IMREAD_COLOR)
        height, width = picture.shape[:2]
        focal = float(truth["focal_px"])
        given = Intrinsics(focal, focal, float(truth["cx"]), float(truth["cy"]), width=width,
                           height=height)
        for run, camera in (("focal given", given), ("focal estimated", None)):
            estimate = estimate_pose(picture, camera)
            if not estimate.ok:
                continue
            pose = estimate.pose
            errors = measure.image_errors(
                measure.directions_from_pose(pose.pan, pose.tilt, pose.roll),
                bench.true_directions(truth))
            rows.append((run, confidence_features(estimate), measure.is_within(errors),
                         estimate.confidence))
    return rows


def fit_logistic(features: np.ndarray, outcome: np.ndarray, prior: float = 1.0
                 ) -> np.ndarray:
    """Weights ``w`` (intercept first) maximising the likelihood of ``outcome`` under
    ``P = 1 / (1 + exp(-(w0 + features @ w[1:])))``, with a Gaussian prior of variance
    ``1 / prior`` on the slopes of the standardised features (a ridge, so a few photos cannot
    make a slope huge)."""
    mean, spread = features.mean(axis=0), features.std(axis=0)
    spread[spread == 0] = 1.0
    design = np.column_stack([np.ones(len(features)), (features - mean) / spread])
    weights = np.zeros(design.shape[1])
    ridge = prior * np.diag([0.0] + [1.0] * features.shape[1])
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-design @ weights))
        gradient = design.T @ (outcome - p) - ridge @ weights
        hessian = (design * (p * (1 - p))[:, None]).T @ design + ridge
        step = np.linalg.solve(hessian, gradient)
        weights += step
        if np.abs(step).max() < 1e-10:
            break
    slopes = weights[1:] / spread
    return np.concatenate([[weights[0] - mean @ slopes], slopes])


def reliability(confidences: list[float], within: list[bool]) -> str:
    return "\n".join(
        f"    {b.low:.1f}-{b.high:.1f}: n {b.count:3d}, mean {b.mean_confidence:.2f}, "
        f"within {b.fraction_within:.2f}"
        for b in measure.calibration_bins(confidences, within) if b.count)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", nargs="?", type=Path, default=bench.DEFAULT_DATA)
    data = parser.parse_args().data
    if not (data / "truth.csv").is_file():
        parser.exit(2, f"calibrate_confidence: no York Urban data at {data}\n")
    rows = photo_measures(data)
    features = np.array([row[1] for row in rows])
    within = np.array([row[2] for row in rows], dtype=float)
    weights = fit_logistic(features, within)
    fitted = 1.0 / (1.0 + np.exp(-(weights[0] + features @ weights[1:])))
    print(f"{len(rows)} estimates ({int(within.sum())} within {measure.WITHIN_DEG:g} deg) "
          f"on {data}")
    print("CONFIDENCE_WEIGHTS = (" + ", ".join(f"{w:.3f}" for w in weights) + ")")
    print("  reliability of the confidence the estimator reports now:")
    print(reliability([row[3] for row in rows], [row[2] for row in rows]))
    print("  reliability of the fitted probability (in-sample):")
    print(reliability(list(fitted), [row[2] for row in rows]))
    held_out = []
    for k in range(len(rows)):  # leave one out: each photo's probability from the others
        keep = np.arange(len(rows)) != k
        w = fit_logistic(features[keep], within[keep])
        held_out.append(float(1.0 / (1.0 + np.exp(-(w[0] + features[k] @ w[1:])))))
    print("  reliability of the fitted probability (each photo left out of its own fit):")
    print(reliability(held_out, [row[2] for row in rows]))


if __name__ == "__main__":
    main()
