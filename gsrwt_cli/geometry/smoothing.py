"""Poses smoothed over time: a robust, symmetric local fit of rotations, for poses estimated
frame by frame (``rectify VIDEO --auto --smooth SECONDS``).

Pure numpy, no I/O. Each sample's smoothed rotation comes from the samples within half a
window of it: a local linear fit (Cleveland's LOESS of degree 1) of their rotations in the
tangent space of a running mean, iterated:

1. start from their weighted mean rotation, in the sense of Markley et al., "Averaging
   Quaternions" (J. Guidance, Control, and Dynamics 30(4), 2007): the eigenvector of the
   largest eigenvalue of ``sum w_j q_j q_j^T`` (a quaternion's sign does not matter);
2. write each rotation as its rotation vector from the mean, ``log(M^-1 R_j)``, fit a line
   ``a + b (t_j - t)`` to them by weighted least squares, and turn the mean by ``exp(a)``;
3. weigh each rotation again by its distance from the line, and repeat.

The weights are a tricube kernel of the time apart, ``(1 - |dt / h|^3)^3`` for ``|dt| < h``
(``h`` half the window; LOESS's kernel), times the sample's own ``weight`` (an estimate's
confidence), times a Cauchy weight ``1 / (1 + (d / scale)^2)`` of its distance ``d`` from the
line: a frame whose estimate is far from what its neighbours' motion says (a wrong estimate,
not motion) hardly moves the fit. A line, not a mean: motion at a constant angular speed
comes back unchanged (no delay, no shrinking, up to the ends of the log), and only what
changes faster than the window is smoothed away: jitter of the estimates, and the peaks of
a motion that turns round within the window. The other numbers of a sample (a focal length
estimated with the pose) become their weighted median over the same samples and weights.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .rotations import quaternion_from_rotation, rotation_from_quaternion
from .timeline import PoseSample

#: Degrees: the Cauchy scale of the robust weights (:func:`smooth_samples`), the angle from
#: the mean at which a rotation counts half. Estimates of one pose scatter by a degree or
#: less (an estimate's confidence is of being within 2 degrees); a frame several scales off
#: is another answer, not noise.
ROBUST_SCALE_DEGREES = 2.0
#: Refits of the robust weights.
ROBUST_ITERATIONS = 4


def one_wall(pans: Sequence[float]) -> list[float]:
    """Pans (degrees, in time order) of frames whose walls were chosen one frame at a time,
    all made of one wall: the wall most of the frames chose.

    A frame's estimate finds three orthogonal directions and calls one horizontal the
    wall's normal; another frame of the same scene may call the other one so (a building's
    corner turning past 45 degrees, ``--wall dominant`` weighing its two faces), and its pan
    is then the same camera's by a multiple of 90 degrees: ``Rx(pan + 90) Ry(tilt) Rz(roll)``
    is the pose of the same camera against the wall beside. Each pan is moved by the
    multiple of 90 degrees that puts it within 45 degrees of the one before it (a camera
    turns less than that between two frames), and the whole sequence then by the multiple
    of 90 degrees that the most frames' own choices agree with (ties: the first frame's).
    """
    unwrapped: list[float] = []
    for pan in pans:
        if unwrapped:
            pan -= 90.0 * round((pan - unwrapped[-1]) / 90.0)
        unwrapped.append(float(pan))
    offsets = [round((own - moved) / 90.0) for own, moved in zip(pans, unwrapped)]
    if not offsets:
        return []
    votes = {offset: offsets.count(offset) for offset in offsets}
    chosen = max(votes, key=lambda offset: (votes[offset], offset == offsets[0]))
    return [pan + 90.0 * chosen for pan in unwrapped]


def _tricube(offsets: np.ndarray, half_window: float) -> np.ndarray:
    """Cleveland's tricube kernel of ``offsets`` (seconds) over ``half_window`` seconds."""
    u = np.clip(np.abs(offsets) / half_window, 0.0, 1.0)
    return (1.0 - u**3) ** 3


def mean_rotation(quaternions: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The weighted mean of unit quaternions ``(n, 4)`` (Markley's: the eigenvector of the
    largest eigenvalue of ``sum w q q^T``), as a unit quaternion, sign fixed to ``w >= 0``."""
    matrix = (quaternions * weights[:, None]).T @ quaternions
    _, vectors = np.linalg.eigh(matrix)
    mean = vectors[:, -1]
    return mean if mean[0] >= 0 else -mean


def _relative_rotvecs(quaternions: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """``log(mean^-1 q_j)`` of each unit quaternion ``(n, 4)``: its rotation from ``mean`` as
    a rotation vector ``(n, 3)`` in radians (the shorter way, whatever the signs)."""
    w0, v0 = mean[0], mean[1:]
    w = quaternions[:, 0] * w0 + quaternions[:, 1:] @ v0  # conj(mean) * q, scalar part
    v = (w0 * quaternions[:, 1:] - quaternions[:, :1] * v0
         - np.cross(v0, quaternions[:, 1:]))
    flip = np.where(w < 0, -1.0, 1.0)
    w, v = w * flip, v * flip[:, None]
    norm = np.linalg.norm(v, axis=1)
    angle = 2.0 * np.arctan2(norm, w)
    scale = np.where(norm > 1e-15, angle / np.maximum(norm, 1e-300), 2.0)
    return v * scale[:, None]


def _turned(mean: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """``mean * exp(rotvec)`` as a unit quaternion."""
    angle = float(np.linalg.norm(rotvec))
    half = np.concatenate([[math.cos(angle / 2)],
                           (math.sin(angle / 2) / angle if angle > 1e-15 else 0.5) * rotvec])
    w0, v0, w1, v1 = mean[0], mean[1:], half[0], half[1:]
    product = np.concatenate([[w0 * w1 - v0 @ v1], w0 * v1 + w1 * v0 + np.cross(v0, v1)])
    return product / np.linalg.norm(product)


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The smallest value at which the weights below and at it reach half the total."""
    order = np.argsort(values, kind="stable")
    cumulative = np.cumsum(weights[order])
    index = int(np.searchsorted(cumulative, 0.5 * cumulative[-1]))
    return float(values[order][min(index, len(values) - 1)])


def smooth_samples(samples: Sequence[PoseSample], window: float,
                   weights: Sequence[float] | None = None) -> list[PoseSample]:
    """Each sample with its rotation (and other numbers) smoothed over the samples within
    ``window / 2`` seconds of it (see the module's docstring), in the order given.

    ``weights``: each sample's own weight (>= 0, say its confidence; default 1). ``window``
    0 gives the samples back unchanged. A sample with no neighbour of positive weight keeps
    its own pose.
    """
    if not (math.isfinite(window) and window >= 0):
        raise ValueError(f"the window must be a finite number of seconds >= 0, got {window!r}")
    count = len(samples)
    own = np.ones(count) if weights is None else np.asarray(weights, dtype=np.float64)
    if own.shape != (count,) or not np.all(np.isfinite(own)) or np.any(own < 0):
        raise ValueError("weights must be one finite number >= 0 per sample")
    if window == 0 or count < 2:
        return list(samples)
    times = np.array([sample.time for sample in samples], dtype=np.float64)
    quaternions = np.array([quaternion_from_rotation(sample.rotation) for sample in samples],
                           dtype=np.float64)
    half = window / 2
    smoothed = []
    for index, sample in enumerate(samples):
        near = np.flatnonzero(np.abs(times - times[index]) < half)
        base = _tricube(times[near] - times[index], half) * own[near]
        if not np.any(base > 0):
            smoothed.append(sample)
            continue
        group, offsets = quaternions[near], times[near] - times[index]
        design = np.column_stack([np.ones(len(near)), offsets])
        fitted = base
        mean = mean_rotation(group, base)
        for _ in range(ROBUST_ITERATIONS + 1):
            # A line in the tangent space at the mean, fitted by weighted least squares:
            # its value at this sample's time is the correction to the mean, and the
            # rotations' distances from the line (not from the mean) weigh them next time.
            residual = _relative_rotvecs(group, mean)
            root = np.sqrt(fitted)[:, None]
            line, *_ = np.linalg.lstsq(design * root, residual * root, rcond=None)
            if np.count_nonzero(fitted > 0) < 3:  # too few to tell a line: a mean
                line[1] = 0.0
                line[0] = np.average(residual, axis=0, weights=fitted)
            mean = _turned(mean, line[0])
            misfit = np.degrees(np.linalg.norm(residual - design @ line, axis=1))
            fitted = base / (1.0 + (misfit / ROBUST_SCALE_DEGREES) ** 2)
        numbers = {}
        for name in sample.numbers:
            having = [k for k, j in enumerate(near) if name in samples[j].numbers]
            values = np.array([samples[near[k]].numbers[name] for k in having])
            numbers[name] = _weighted_median(values, fitted[having])
        rotation = rotation_from_quaternion(*(float(c) for c in mean))
        smoothed.append(PoseSample(sample.time, rotation, numbers))
    return smoothed
