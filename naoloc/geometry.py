"""2-D poses: ``Pose2D`` with almath semantics, and the SE(2) helpers of the mapping code.

Frames follow NAOqi: x forward, y left, theta counter-clockwise; metres and radians.
Composition ``p1 * p2`` expresses ``p2`` (given in the frame of ``p1``) in the frame
``p1`` is given in, exactly as libalmath does; theta is not normalised by composition.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
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


def midpose(a: Pose2D, b: Pose2D) -> Pose2D:
    """The pose halfway between ``a`` and ``b`` (same frame; the heading the short way)."""
    return Pose2D(
        0.5 * (a.x + b.x),
        0.5 * (a.y + b.y),
        modulo2PI(a.theta + 0.5 * modulo2PI(b.theta - a.theta)),
    )


def mid_transform(a: Sequence[float], b: Sequence[float]) -> list[float]:
    """The rigid transform halfway between two (16 floats, row-major 4 x 4, as ALMotion's
    ``getTransform``): the translations averaged, the rotations' mean projected back onto
    a rotation (SVD; exact for the small differences of one motion cycle)."""
    m = 0.5 * (np.asarray(a, np.float64).reshape(4, 4) + np.asarray(b, np.float64).reshape(4, 4))
    u, _, vt = np.linalg.svd(m[:3, :3])
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    m[:3, :3] = r
    m[3] = (0.0, 0.0, 0.0, 1.0)
    return [float(v) for v in m.reshape(-1)]


# --- SE(2) on numpy arrays: poses ``(3,)`` = (x, y, theta) in metres and radians. ---


def se2_matrix(pose: Sequence[float] | np.ndarray) -> np.ndarray:
    """The 3x3 homogeneous transform of a planar pose ``(x, y, theta)``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array([[c, -s, pose[0]], [s, c, pose[1]], [0.0, 0.0, 1.0]])


def se2_vector(t: np.ndarray) -> np.ndarray:
    """The pose ``(x, y, theta)`` of a 3x3 homogeneous planar transform."""
    return np.array([t[0, 2], t[1, 2], math.atan2(t[1, 0], t[0, 0])])


def se2_relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose ``b`` expressed in the frame of pose ``a`` (both ``(3,)``, same frame)."""
    return se2_vector(np.linalg.inv(se2_matrix(a)) @ se2_matrix(b))


def se2_compose_local(z: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``z (+) d``: the pose ``z`` moved by ``d`` expressed in its own frame."""
    c, s = math.cos(z[2]), math.sin(z[2])
    return np.array([z[0] + c * d[0] - s * d[1], z[1] + s * d[0] + c * d[1], z[2] + d[2]])


def robot_matrix(x: float, y: float, theta: float) -> np.ndarray:
    """``T_map_robot`` (4x4, z up) of a planar robot pose in the map frame."""
    c, s = math.cos(theta), math.sin(theta)
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    t[0, 3], t[1, 3] = x, y
    return t


def planar_pose(t_map_robot: np.ndarray) -> tuple[float, float, float]:
    """(x, y, theta) of a 4x4 robot transform projected on the floor (m, m, rad)."""
    return (
        float(t_map_robot[0, 3]),
        float(t_map_robot[1, 3]),
        math.atan2(float(t_map_robot[1, 0]), float(t_map_robot[0, 0])),
    )


def rotations_z(theta: np.ndarray) -> np.ndarray:
    """``(n, 3, 3)`` rotations about z by the angles ``theta`` (rad)."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.zeros((theta.size, 3, 3))
    r[:, 0, 0], r[:, 0, 1], r[:, 1, 0], r[:, 1, 1], r[:, 2, 2] = c, -s, s, c, 1.0
    return r


def circular_mean(angles: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Weighted mean direction of angles (rad), in (-pi, pi]; unweighted sums without weights."""
    if weights is None:
        return math.atan2(float(np.sin(angles).sum()), float(np.cos(angles).sum()))
    return math.atan2(
        float(np.sum(weights * np.sin(angles))), float(np.sum(weights * np.cos(angles)))
    )
