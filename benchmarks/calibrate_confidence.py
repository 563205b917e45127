"""Calibrate ``gsrwt estimate``'s confidence on real photos: the probability that the estimate
is within 2 degrees of the truth (vertical and wall normal), fitted on the York Urban DB's
training half (``../shared/data/york-urban-train``), with and without the focal length.

The confidence is a logistic function of three measures the estimator makes of each photo
(:func:`gsrwt_cli.api.estimate.confidence_of`): ``rival``, how nearly a different frame
explains the segments as well as the one chosen (:class:`~gsrwt_cli.api.estimate.
ManhattanFrame`); where the focal length was estimated, how many degrees its standard
deviation turns the pose (:class:`~gsrwt_cli.api.estimate.FocalUncertainty`); and
``misfit``, how many degrees the vertical's and the wall normal's own segments, taken alone,
point from the frame's (:func:`~gsrwt_cli.api.estimate.frame_misfit`). This script fits the
weights by maximum likelihood (Newton's method, a weak prior against overfitting) over the
photos the estimator does not refuse, and prints them with the reliability table (per
confidence bin, the photos and the fraction within 2 degrees) before and after, and the
two-fold check: the weights fitted on the photos of odd index (in sorted order) judge those
of even index and the other way round, each fold's accepted and confidently wrong (accepted
and more than 3 degrees off) per run.

    python benchmarks/calibrate_confidence.py [PATH-TO-york-urban-train] [--frontal]

Copy the weights it prints into ``CONFIDENCE_WEIGHTS`` in gsrwt_cli/api/estimate.py.
``--frontal`` instead fits ``UNSEEN_NORMAL_LOGIT``, the logit's offset for walls seen
frontally (:func:`frontal_views`), over all the views and over each half.
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

from gsrwt_cli.api.estimate import (  # noqa: E402
    DEFAULT_MIN_CONFIDENCE,
    confidence_features,
    confidence_of,
    estimate_pose,
)
from gsrwt_cli.geometry.camera import Intrinsics  # noqa: E402


def photo_measures(data: Path) -> list[tuple[str, np.ndarray, bool, float, int, bool]]:
    """Per photo and run (focal given, focal estimated) that the estimator does not refuse:
    the run, its features, whether within 2 degrees on both measures, the old confidence, the
    photo's index in sorted order, whether more than 3 degrees off on either."""
    rows = []
    for index, (image, truth) in enumerate(sorted(bench.read_truth(data).items())):
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
                         estimate.confidence, index,
                         measure.is_confidently_wrong(True, errors)))
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


def frontal_views(data: Path) -> list[tuple[int, float, float, bool]]:
    """The York photos as walls seen about frontally: their detected segments less those
    along the true wall normal (``bench_real_photos.estimates_without``), the focal length
    given. Per estimate whose frontal wall's normal is left with no segments of
    its own and that is not refused: the photo's index in sorted order, the logit of
    :func:`confidence_of` without the offset, the upright probability, and whether within 2
    degrees on both measures."""
    rows = []
    for index, (_, estimate, directions) in enumerate(bench.estimates_without(data, "wall")):
        if not estimate.ok or estimate.normal_seen:
            continue
        pose = estimate.pose
        errors = measure.image_errors(
            measure.directions_from_pose(pose.pan, pose.tilt, pose.roll), directions)
        chance = confidence_of(*confidence_features(estimate))  # no offset, no upright
        rows.append((index, float(np.log(chance / (1.0 - chance))), estimate.upright,
                     measure.is_within(errors)))
    return rows


def fit_offset(logits: np.ndarray, upright: np.ndarray, within: np.ndarray) -> float:
    """The offset ``d`` of the logits that makes ``upright / (1 + exp(-(logit + d)))`` most
    likely to give ``within`` (maximum likelihood over a grid of 0.01, -3 to 2)."""
    grid = np.linspace(-3.0, 2.0, 501)
    chance = upright[None, :] / (1.0 + np.exp(-(logits[None, :] + grid[:, None])))
    chance = np.clip(chance, 1e-12, 1.0 - 1e-12)
    likelihood = (within * np.log(chance) + (1.0 - within) * np.log(1.0 - chance)).sum(axis=1)
    return float(grid[int(np.argmax(likelihood))])


def main_frontal(data: Path) -> None:
    """``--frontal``: the offset over all the frontal views and over each half, and the
    calibration it gives."""
    rows = np.array(frontal_views(data), dtype=float)
    index, logits, upright, within = rows.T
    print(f"{len(rows)} walls seen frontally, not refused ({int(within.sum())} within "
          f"{measure.WITHIN_DEG:g} deg) on {data}")
    offset = fit_offset(logits, upright, within)
    print(f"UNSEEN_NORMAL_LOGIT = {offset:.2f}")
    for name, half in (("even", index % 2 == 0), ("odd", index % 2 == 1)):
        print(f"  fitted on the photos of {name} index only: "
              f"{fit_offset(logits[half], upright[half], within[half]):.2f}")
    for name, shift in (("without the offset", 0.0), ("with it", offset)):
        chance = upright / (1.0 + np.exp(-(logits + shift)))
        kept = chance >= DEFAULT_MIN_CONFIDENCE
        print(f"  {name}: {int(kept.sum())} accepted, mean confidence "
              f"{chance[kept].mean():.3f} against {within[kept].mean():.3f} within")


def reliability(confidences: list[float], within: list[bool]) -> str:
    return "\n".join(
        f"    {b.low:.1f}-{b.high:.1f}: n {b.count:3d}, mean {b.mean_confidence:.2f}, "
        f"within {b.fraction_within:.2f}"
        for b in measure.calibration_bins(confidences, within) if b.count)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", nargs="?", type=Path, default=bench.DEFAULT_DATA)
    parser.add_argument("--frontal", action="store_true",
                        help="fit the offset for walls seen frontally instead")
    arguments = parser.parse_args()
    data = arguments.data
    if not (data / "truth.csv").is_file():
        parser.exit(2, f"calibrate_confidence: no York Urban data at {data}\n")
    if arguments.frontal:
        main_frontal(data)
        return
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
    print(f"  two folds (accepted: probability >= {DEFAULT_MIN_CONFIDENCE:g}):")
    parity = np.array([row[4] % 2 for row in rows])
    wrong = np.array([row[5] for row in rows])
    runs = np.array([row[0] for row in rows])
    for held in (0, 1):
        w = fit_logistic(features[parity != held], within[parity != held])
        accepted = 1.0 / (1.0 + np.exp(-(w[0] + features @ w[1:]))) >= DEFAULT_MIN_CONFIDENCE
        print(f"    held out: {'even' if held == 0 else 'odd'} index: " + "; ".join(
            f"{run} {int((accepted & (parity == held) & (runs == run)).sum())} accepted, "
            f"{int((accepted & wrong & (parity == held) & (runs == run)).sum())} "
            f"confidently wrong" for run in ("focal given", "focal estimated")))


if __name__ == "__main__":
    main()
