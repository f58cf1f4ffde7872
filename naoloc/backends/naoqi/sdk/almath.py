"""``almath`` of the old NAOqi Python SDK, in part: angle constants and 2D poses."""

from __future__ import annotations

import math
from typing import Any, Final

from naoloc.geometry import Pose2D as _Pose
from naoloc.geometry import modulo2PI

__all__ = ["PI", "PI_2", "TO_DEG", "TO_RAD", "Pose2D", "modulo2PI", "pose2DInverse"]

PI: Final = math.pi
PI_2: Final = math.pi / 2.0
TO_RAD: Final = math.pi / 180.0
TO_DEG: Final = 180.0 / math.pi


class Pose2D:
    """almath.Pose2D (mutable, as almath's): ``Pose2D(x, y, theta)``, ``Pose2D([x, y,
    theta])`` or ``Pose2D()``; ``a * b`` composes, metres and radians."""

    def __init__(self, *args: Any) -> None:
        values = list(args[0]) if len(args) == 1 else list(args)
        values = [float(v) for v in values] + [0.0] * (3 - len(values))
        self.x, self.y, self.theta = values[:3]

    def __mul__(self, other: Pose2D) -> Pose2D:
        return Pose2D(*(_Pose(*self.toVector()) * _Pose(*other.toVector())))

    def inverse(self) -> Pose2D:
        """The pose that undoes this one."""
        return pose2DInverse(self)

    def toVector(self) -> list[float]:
        """``[x, y, theta]``."""
        return [self.x, self.y, self.theta]

    def distance(self, other: Pose2D) -> float:
        """Distance between the two positions, m."""
        return math.hypot(self.x - other.x, self.y - other.y)

    def __repr__(self) -> str:
        return f"Pose2D(x={self.x:.4f}, y={self.y:.4f}, theta={self.theta:.4f})"


def pose2DInverse(pose: Pose2D) -> Pose2D:
    """The inverse of a pose, with almath's formula."""
    t = -pose.theta
    c, s = math.cos(t), math.sin(t)
    return Pose2D(-(pose.x * c - pose.y * s), -(pose.y * c + pose.x * s), t)
