"""SimControl of the fake robot: ground truth and teleport in the room frame."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from naoloc.backends.fake.world import ROBOT_RADIUS_M, FakeWorld
from naoloc.errors import RobotError
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.robot.kinematics import position6d


class FakeSim:
    """Ground truth, teleport and free-space queries (room frame, metres and radians).

    These calls do not advance simulated time. The fake room has walls only.

    Args:
        world: The shared robot state and clock.
    """

    def __init__(self, world: FakeWorld) -> None:
        self._world = world

    def true_pose(self) -> tuple[float, float, float]:
        """Ground-truth ``(x, y, theta)`` of FRAME_ROBOT's origin, room frame."""
        self._world.check_open()
        p = self._world.true_pose
        return (p.x, p.y, p.theta)

    def true_camera_pose(self, camera_index: int = 0) -> list[float]:
        """True ``[x, y, z, wx, wy, wz]`` of a camera, room frame (m, rad; ``wy > 0`` looks down).

        Raises:
            RobotError: For a camera index other than 0 (top) or 1 (bottom).
        """
        self._world.check_open()
        if camera_index not in (0, 1):
            raise RobotError(f"camera index {camera_index} does not exist (0 top, 1 bottom)")
        return position6d(self._world.camera_in_room(int(camera_index)))

    def teleport(self, x: float, y: float, theta: float) -> None:
        """Put the robot at ``(x, y, theta)`` (room frame); stops walking; odometry not told.

        Raises:
            RobotError: The robot's disc would overlap a wall, or a value is not finite.
        """
        w = self._world
        w.check_open()
        x, y, theta = float(x), float(y), float(theta)
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise RobotError(f"teleport target {[x, y, theta]} is not finite")
        if not w.is_free(x, y, ROBOT_RADIUS_M):
            raise RobotError(f"teleport target ({x:.2f}, {y:.2f}) is in or too close to a wall")
        w.stop_walk()
        w.true_pose = Pose2D(x, y, modulo2PI(theta))

    def room_size(self) -> tuple[float, float]:
        """Inner size of the room ``(x, y)`` in metres."""
        return self._world.size

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        """True when a disc of ``clearance`` m at ``(x, y)`` touches no wall."""
        return self._world.is_free(float(x), float(y), float(clearance))

    def sim_time(self) -> float:
        """Simulated seconds since the backend started."""
        return self._world.time_s

    def attach_clock(self, clock: Any) -> tuple[Callable[[], None], float]:
        """Let a real-time clock drive time (``naoloc serve``); None = deterministic again."""
        return self._world.attach_clock(clock)
