"""Poses over time: spherical linear interpolation of rotations, and the pose at any moment
of a log of timestamped samples.

Pure numpy, no I/O. A sample is a time (seconds), a rotation ``world_from_camera`` (thesis
frames, :mod:`~gsrwt_cli.geometry.rotations`) and any other numbers (a focal length, a
principal point); a frame's pose is the slerp of the two samples around its time, its other
numbers the linear interpolation of theirs.

Convention
----------
- ``slerp(R0, R1, u)``: the rotation a fraction ``u`` (0 to 1) of the way from ``R0`` to ``R1``
  along the shortest great arc, at constant angular speed: ``R0 · exp(u · log(R0^T R1))``,
  computed with unit quaternions (``q0`` and ``q1`` taken in the same hemisphere, so that the
  arc is the short one).
- Times are seconds on one clock (the pose log's); samples need not be sorted, two at the
  same time are an error (:class:`DuplicateTimeError`).
- ``max_gap``: a moment further than this from the nearest sample has no pose
  (:class:`PoseGapError`). Between the first and last samples, and within ``max_gap`` of the
  first or last, the pose is known; before the first (after the last) it is the first's
  (the last's): held, never extrapolated.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .rotations import quaternion_from_rotation, rotation_from_quaternion

Matrix = NDArray[np.float64]


class DuplicateTimeError(ValueError):
    """Two samples at the same time: ``first`` and ``second`` are their positions in the
    order given."""

    def __init__(self, time: float, first: int, second: int) -> None:
        self.time, self.first, self.second = time, first, second
        super().__init__(f"time {time:g} is given twice (samples {first} and {second})")


class PoseGapError(ValueError):
    """A moment further than ``max_gap`` seconds from the nearest sample."""

    def __init__(self, time: float, nearest: float | None, max_gap: float) -> None:
        self.time, self.nearest, self.max_gap = time, nearest, max_gap
        if nearest is None:
            text = "the pose log has no samples"
        else:
            text = (f"no pose within {max_gap:g} s of time {time:.6g} s (the nearest sample is "
                    f"{abs(time - nearest):.6g} s away, at {nearest:.6g} s)")
        super().__init__(text)


def _quaternion(rotation: ArrayLike) -> NDArray[np.float64]:
    return np.array(quaternion_from_rotation(rotation), dtype=np.float64)


def slerp(r0: ArrayLike, r1: ArrayLike, fraction: float) -> Matrix:
    """The rotation ``fraction`` of the way from ``r0`` to ``r1`` (3x3 rotation matrices) on
    the shorter arc, at constant angular speed (Shoemake's slerp of unit quaternions).

    ``fraction`` 0 gives ``r0``, 1 gives ``r1`` (to rounding); values outside 0-1 extrapolate
    along the same arc. Near-equal rotations (an angle below 1e-9 rad) are interpolated
    linearly and renormalized, where the sine's quotient would lose its digits.
    """
    if not math.isfinite(fraction):
        raise ValueError(f"the fraction must be finite, got {fraction!r}")
    q0, q1 = _quaternion(r0), _quaternion(r1)
    dot = float(q0 @ q1)
    if dot < 0:  # the same rotation as -q1, on the shorter arc
        q1, dot = -q1, -dot
    dot = min(1.0, dot)
    angle = math.acos(dot)  # half the turn between the two rotations
    if angle < 1e-9:
        q = q0 + fraction * (q1 - q0)
    else:
        sin_angle = math.sin(angle)
        q = (math.sin((1 - fraction) * angle) * q0 + math.sin(fraction * angle) * q1) / sin_angle
    q = q / np.linalg.norm(q)
    return rotation_from_quaternion(*(float(c) for c in q))


@dataclass(frozen=True)
class PoseSample:
    """One sample of a pose log: ``time`` (seconds), ``rotation`` (``world_from_camera``,
    3x3) and ``numbers`` (others, interpolated linearly: ``focal``, ``cx``, ...)."""

    time: float
    rotation: Matrix
    numbers: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class PoseAt:
    """The pose at one moment: its rotation, its other numbers, and the two samples it was
    interpolated between (their indices in the sorted log) with the fraction between them."""

    rotation: Matrix
    numbers: dict[str, float]
    before: int
    after: int
    fraction: float


class Timeline:
    """The samples of a pose log, sorted by time, and the pose at any moment (:meth:`at`).

    ``samples`` in any order; two at the same time raise :class:`DuplicateTimeError` naming
    their positions in the order given. A number that some samples give and others do not is
    interpolated between the samples that give it (the others are skipped for it).
    """

    def __init__(self, samples: Sequence[PoseSample], max_gap: float) -> None:
        if not (math.isfinite(max_gap) and max_gap >= 0):
            raise ValueError(f"max_gap must be a finite number of seconds >= 0, got {max_gap!r}")
        order = sorted(range(len(samples)), key=lambda index: samples[index].time)
        for left, right in zip(order, order[1:]):
            if samples[left].time == samples[right].time:
                first, second = sorted((left, right))
                raise DuplicateTimeError(samples[left].time, first, second)
        self.samples = [samples[index] for index in order]
        self.times = np.array([sample.time for sample in self.samples], dtype=np.float64)
        self.max_gap = float(max_gap)

    def __len__(self) -> int:
        return len(self.samples)

    def at(self, time: float) -> PoseAt:
        """The pose at ``time`` (seconds): slerp of the rotations of the samples around it,
        linear interpolation of their numbers; held at the first or last sample outside
        them. Raises :class:`PoseGapError` when no sample is within ``max_gap``."""
        if not self.samples:
            raise PoseGapError(time, None, self.max_gap)
        after = int(np.searchsorted(self.times, time, side="left"))
        candidates = [index for index in (after - 1, after) if 0 <= index < len(self.times)]
        nearest = min(candidates, key=lambda index: abs(self.times[index] - time))
        if abs(self.times[nearest] - time) > self.max_gap:
            raise PoseGapError(time, float(self.times[nearest]), self.max_gap)
        if after == 0 or after == len(self.times) or self.times[after] == time:
            index = min(after, len(self.times) - 1)
            sample = self.samples[index]
            return PoseAt(np.array(sample.rotation, dtype=np.float64), dict(sample.numbers),
                          index, index, 0.0)
        before = after - 1
        t0, t1 = self.times[before], self.times[after]
        fraction = float((time - t0) / (t1 - t0))
        rotation = slerp(self.samples[before].rotation, self.samples[after].rotation, fraction)
        return PoseAt(rotation, self._numbers(time, before, after), before, after, fraction)

    def _numbers(self, time: float, before: int, after: int) -> dict[str, float]:
        """Each number linearly interpolated between the nearest samples around ``time``
        that give it (held beyond the last that does)."""
        names = dict.fromkeys(name for sample in self.samples[before:after + 1]
                              for name in sample.numbers)
        values: dict[str, float] = {}
        for name in names:
            left = next((i for i in range(before, -1, -1) if name in self.samples[i].numbers),
                        None)
            right = next((i for i in range(after, len(self.samples))
                          if name in self.samples[i].numbers), None)
            if left is None or right is None or left == right:
                values[name] = float(self.samples[left if right is None else right]
                                     .numbers[name])
                continue
            t0, t1 = self.times[left], self.times[right]
            u = (time - t0) / (t1 - t0)
            v0, v1 = self.samples[left].numbers[name], self.samples[right].numbers[name]
            values[name] = float(v0 + u * (v1 - v0))
        return values
