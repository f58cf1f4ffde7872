"""2-D poses with almath semantics: ``Pose2D``, ``pose2DInverse``, ``modulo2PI``.

Frames follow NAOqi: x forward, y left, theta counter-clockwise; metres and radians.
Composition ``p1 * p2`` expresses ``p2`` (given in the frame of ``p1``) in the frame
``p1`` is given in, exactly as libalmath does; theta is not normalised by composition.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np


def modulo2PI(angle: float) -> float:
    """Wrap an angle into (-pi, pi], like ``almath::modulo2PI``.

    Args:
        angle: Angle in radians.

    Returns:
        The same direction in (-pi, pi] radians.
    """
    wrapped = math.fmod(angle + math.pi, 2.0 * math.pi)
    if wrapped <= 0.0:
        wrapped += 2.0 * math.pi
    return wrapped - math.pi


def wrap_angles(angles: np.ndarray) -> np.ndarray:
    """Vectorised :func:`modulo2PI` for an array of radians, into (-pi, pi]."""
    a = np.asarray(angles, dtype=np.float64)
    return math.pi - np.mod(math.pi - a, 2.0 * math.pi)


@dataclass(frozen=True, slots=True)
class Pose2D:
    """A planar pose: position (m) and heading (rad, counter-clockwise from x).

    Attributes:
        x: Forward coordinate in metres.
        y: Left coordinate in metres.
        theta: Heading in radians.
    """

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

    @classmethod
    def from_list(cls, values: Iterable[float]) -> Pose2D:
        """Build from ``[x, y, theta]`` as NAOqi returns it."""
        x, y, theta = (float(v) for v in values)
        return cls(x, y, theta)

    def to_list(self) -> list[float]:
        """Return ``[x, y, theta]`` as NAOqi takes it."""
        return [self.x, self.y, self.theta]

    def __iter__(self) -> Iterator[float]:
        return iter((self.x, self.y, self.theta))

    def __mul__(self, other: Pose2D) -> Pose2D:
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.theta + other.theta,
        )

    def inverse(self) -> Pose2D:
        """The pose that undoes this one: ``p * p.inverse()`` is the identity."""
        return pose2DInverse(self)

    def normalized(self) -> Pose2D:
        """The same pose with theta wrapped into (-pi, pi]."""
        return Pose2D(self.x, self.y, modulo2PI(self.theta))

    def distance(self, other: Pose2D) -> float:
        """Euclidean distance between the two positions, in metres."""
        return math.hypot(self.x - other.x, self.y - other.y)


def pose2DInverse(pose: Pose2D) -> Pose2D:
    """Inverse of a pose with almath's formula.

    ``t' = -t; x' = -(x cos t' - y sin t'); y' = -(y cos t' + x sin t')``.
    """
    t = -pose.theta
    c, s = math.cos(t), math.sin(t)
    return Pose2D(-(pose.x * c - pose.y * s), -(pose.y * c + pose.x * s), t)


def relative_pose(start: Pose2D, end: Pose2D) -> Pose2D:
    """The odometry idiom ``pose2DInverse(start) * end`` with theta wrapped.

    Args:
        start: Pose at the start, in some fixed frame (e.g. FRAME_WORLD).
        end: Pose at the end, in the same frame.

    Returns:
        ``end`` expressed in the frame of ``start``.
    """
    return (pose2DInverse(start) * end).normalized()
