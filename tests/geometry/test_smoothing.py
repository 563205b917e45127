"""Poses smoothed over time (geometry/smoothing.py), against scipy's rotations: jitter is
averaged down, motion at a constant speed is not delayed, a wrong frame is outvoted."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gsrwt_cli.geometry.smoothing import mean_rotation, smooth_samples
from gsrwt_cli.geometry.timeline import PoseSample

RATE = 30.0


def angle_degrees(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees((Rotation.from_matrix(a).inv() * Rotation.from_matrix(b))
                            .magnitude()))


def samples_of(rotations: Rotation, focal: np.ndarray | None = None) -> list[PoseSample]:
    return [PoseSample(index / RATE, matrix,
                       {} if focal is None else {"focal": float(focal[index])})
            for index, matrix in enumerate(rotations.as_matrix())]


def sweep(count: int) -> Rotation:
    """Pan from -20 to 20 degrees at a constant angular speed, tilt 10, roll 2."""
    pans = np.linspace(-20, 20, count)
    return Rotation.from_euler("XYZ", np.column_stack([pans, np.full(count, 10.0),
                                                       np.full(count, 2.0)]), degrees=True)


def jittered(truth: Rotation, degrees: float, seed: int) -> Rotation:
    rng = np.random.default_rng(seed)
    return truth * Rotation.from_rotvec(rng.normal(0, np.radians(degrees), (len(truth), 3)))


def test_the_mean_of_a_rotation_and_its_opposite_turn_is_the_middle():
    """The chordal mean of R·exp(+a) and R·exp(-a) is R, whatever the quaternions' signs."""
    middle = Rotation.from_euler("XYZ", [30, -10, 5], degrees=True)
    turn = Rotation.from_rotvec([0.0, 0.3, 0.1])
    pair = (middle * turn, middle * turn.inv())
    quaternions = np.array([r.as_quat(scalar_first=True) for r in pair])
    quaternions[1] *= -1  # the same rotation, the other sign
    mean = mean_rotation(quaternions, np.ones(2))
    assert angle_degrees(Rotation.from_quat(mean, scalar_first=True).as_matrix(),
                         middle.as_matrix()) < 1e-9


def test_jitter_is_averaged_down_and_motion_is_not_delayed():
    truth = sweep(90)  # 3 s at 30 frames per second, 13.3 degrees per second
    noisy = samples_of(jittered(truth, 0.5, seed=1))
    smoothed = smooth_samples(noisy, window=0.5)
    middle, ends = slice(8, -8), np.r_[0:8, 82:90]  # within half a window of an end
    before = np.array([angle_degrees(s.rotation, t) for s, t in zip(noisy, truth.as_matrix())])
    after = np.array([angle_degrees(s.rotation, t) for s, t in zip(smoothed, truth.as_matrix())])
    assert np.median(after[middle]) < 0.45 * np.median(before[middle])
    assert np.median(after[ends]) < 0.6 * np.median(before[ends])  # a line, not a mean
    # Exact motion at a constant speed comes back as it was: no lag, no shrinking.
    still = smooth_samples(samples_of(truth), window=0.5)
    assert max(angle_degrees(s.rotation, t)
               for s, t in zip(still[middle], truth.as_matrix()[middle])) < 1e-6


def test_a_wrong_frame_is_outvoted_by_its_neighbours():
    truth = sweep(60)
    rotations = list(truth)
    wrong = 30
    rotations[wrong] = truth[wrong] * Rotation.from_euler("Y", 15, degrees=True)
    samples = samples_of(Rotation.concatenate(rotations))
    smoothed = smooth_samples(samples, window=0.4)
    assert angle_degrees(samples[wrong].rotation, truth[wrong].as_matrix()) > 14.9
    assert max(angle_degrees(s.rotation, t.as_matrix())
               for s, t in zip(smoothed, truth)) < 0.1


def test_weights_and_numbers():
    """A weight-0 sample counts for nothing; a focal length is the weighted median."""
    truth = Rotation.from_euler("XYZ", np.tile([10.0, 5.0, 0.0], (9, 1)), degrees=True)
    rotations = list(truth)
    rotations[4] = truth[4] * Rotation.from_euler("X", 3, degrees=True)
    focal = np.array([800, 801, 799, 800, 2000, 802, 798, 800, 801], float)
    weights = [1.0] * 9
    weights[4] = 0.0
    smoothed = smooth_samples(samples_of(Rotation.concatenate(rotations), focal),
                              window=1.0, weights=weights)
    assert angle_degrees(smoothed[4].rotation, truth[4].as_matrix()) < 1e-6
    assert 798 <= smoothed[4].numbers["focal"] <= 802


def test_window_zero_and_bad_arguments():
    samples = samples_of(sweep(5))
    assert smooth_samples(samples, 0) == samples
    with pytest.raises(ValueError, match="window"):
        smooth_samples(samples, float("nan"))
    with pytest.raises(ValueError, match="weights"):
        smooth_samples(samples, 1.0, weights=[1.0, -1.0, 1.0, 1.0, 1.0])


def test_one_wall_keeps_the_wall_most_frames_chose():
    """A pan 90 degrees off is the same camera against the wall beside: turned back, unless
    most frames chose that wall; a turn past 45 degrees between frames is followed."""
    from gsrwt_cli.geometry.smoothing import one_wall

    assert one_wall([-10.0, -12.0, 77.0, -15.0]) == [-10.0, -12.0, -13.0, -15.0]
    assert one_wall([80.0, -5.0, -8.0]) == [-10.0, -5.0, -8.0]
    # A camera turning from 30 to 70 degrees: its frames past 45 call the other wall
    # theirs (pan 70 - 90); most do, so the whole video is of that wall.
    assert one_wall([30.0, 40.0, 50.0 - 90.0, 60.0 - 90.0, 70.0 - 90.0]) == [
        -60.0, -50.0, -40.0, -30.0, -20.0]
    assert one_wall([]) == []
