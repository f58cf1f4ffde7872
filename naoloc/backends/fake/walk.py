"""Walk tasks of the fake robot: a path of poses (moveTo) or a velocity (move).

Both produce one body-frame increment per ALMotion cycle. The world applies it to the
commanded odometry, the ground truth and the drifting sensor odometry, unless the
robot's disc would touch a wall, in which case the task fails.

A path segment from pose ``A`` to ``B`` (both in FRAME_WORLD of the commanded
odometry) is walked as ``A * (s x, s y, s theta)`` with ``s`` going linearly from 0 to 1,
where ``(x, y, theta) = A^-1 B``: straight in ``A``'s frame while turning at a constant
rate. Its duration is the shortest that keeps the body-frame velocity within NAO's
walk speeds (scaled by the MaxStep* move config).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse


@dataclass(frozen=True, slots=True)
class SpeedLimits:
    """Maximum walk velocities in FRAME_ROBOT: m/s forward, m/s sideways, rad/s turning."""

    vx: float
    vy: float
    wz: float


def segment_duration(rel: Pose2D, limits: SpeedLimits, dt: float) -> float:
    """Shortest duration (s, a whole number of cycles) of a segment within the speed limits.

    Args:
        rel: The segment as ``A^-1 B``: metres, metres, radians.
        limits: Speed limits.
        dt: Cycle length in seconds.
    """
    duration = abs(rel.theta) / limits.wz
    # The body-frame velocity direction turns by theta along the segment: check a few angles.
    for k in range(9):
        phi = -rel.theta * k / 8.0
        c, s = math.cos(phi), math.sin(phi)
        bx, by = c * rel.x - s * rel.y, s * rel.x + c * rel.y
        duration = max(duration, abs(bx) / limits.vx, abs(by) / limits.vy)
    return max(dt, math.ceil(duration / dt - 1e-9) * dt)


@dataclass
class PathWalk:
    """A moveTo task: straight-and-turning segments through absolute waypoints.

    Attributes:
        waypoints: Target poses in FRAME_WORLD (commanded odometry), in order.
        limits: Speed limits for this task.
        start: Commanded pose when the current segment started.
        index: Index of the waypoint being walked to.
        progress: Fraction ``s`` of the current segment done, in [0, 1].
        duration: Duration of the current segment in seconds.
    """

    waypoints: list[Pose2D]
    limits: SpeedLimits
    start: Pose2D = field(default_factory=Pose2D)
    index: int = 0
    progress: float = 0.0
    duration: float = 0.0

    def begin(self, pose: Pose2D, dt: float) -> None:
        """Start the current segment at the commanded pose ``pose``."""
        self.start = pose
        self.progress = 0.0
        rel = self._rel()
        self.duration = segment_duration(rel, self.limits, dt)

    def _rel(self) -> Pose2D:
        target = self.waypoints[self.index]
        rel = pose2DInverse(self.start) * target
        return Pose2D(rel.x, rel.y, modulo2PI(target.theta - self.start.theta))

    def _at(self, s: float) -> Pose2D:
        rel = self._rel()
        return self.start * Pose2D(s * rel.x, s * rel.y, s * rel.theta)

    @property
    def done(self) -> bool:
        """True once the last waypoint is reached."""
        return self.index >= len(self.waypoints)

    @property
    def final(self) -> Pose2D:
        """The last waypoint (FRAME_WORLD, commanded odometry)."""
        return self.waypoints[-1]

    def step(self, pose: Pose2D, dt: float) -> Pose2D:
        """The body-frame increment of the next cycle, from commanded pose ``pose``."""
        if self.done:
            return Pose2D()
        if self.progress == 0.0:
            self.begin(pose, dt)
        before = self._at(self.progress)
        self.progress = min(1.0, self.progress + dt / self.duration)
        after = self._at(self.progress) if self.progress < 1.0 else self.waypoints[self.index]
        return pose2DInverse(before) * after

    def advance(self) -> None:
        """Call after a step was applied: move on when the segment is finished."""
        if self.progress >= 1.0:
            self.index += 1
            self.progress = 0.0


@dataclass
class VelocityWalk:
    """A move/moveToward task: constant body velocity until changed or stopped.

    Attributes:
        vx: Forward velocity, m/s, FRAME_ROBOT.
        vy: Sideways velocity, m/s, FRAME_ROBOT.
        wz: Turn rate, rad/s.
    """

    vx: float
    vy: float
    wz: float

    def step(self, dt: float) -> Pose2D:
        """The body-frame increment of one cycle (exact arc for a constant velocity)."""
        dth = self.wz * dt
        if abs(dth) < 1e-9:
            return Pose2D(self.vx * dt, self.vy * dt, 0.0)
        # Integrate the constant body twist over the cycle.
        s, c = math.sin(dth), math.cos(dth)
        fx, fy = s / self.wz, (1.0 - c) / self.wz
        return Pose2D(fx * self.vx - fy * self.vy, fy * self.vx + fx * self.vy, dth)
