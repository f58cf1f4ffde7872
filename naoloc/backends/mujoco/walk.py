"""The walk controller: turns moveTo goals and move velocities into a commanded base twist.

A pragmatic omnidirectional walk: the base is driven at a commanded velocity in FRAME_ROBOT
(within NAO's limits) and the physics decides where it really goes (walls and furniture stop
it). ``moveTo`` goals are tracked in FRAME_WORLD with feedback on the robot's own sensor
odometry, never on the truth: NAO's walk engine executes its footstep plan open-loop on its
odometry, so the body ends where the odometry error puts it. A move whose body stops making
progress for a second (blocked by an obstacle) or that runs out of time fails, as
``ALMotion/MoveFailed``.
No mujoco here: pure arithmetic, driven once per ALMotion cycle by the simulation.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from naoloc.constants import WALK_SPEED, WALK_SPEED_THETA, WALK_SPEED_Y
from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse

TURN_RADIUS = 0.15  # m, converts turning into a distance when measuring progress
STALL_WINDOW_S = 1.0  # s of history the stall detector looks at
STALL_MIN_CMD = 0.02  # m of commanded motion in the window before judging progress
STALL_RATIO = 0.3  # fail when the true motion is below this share of the commanded one


@dataclass(frozen=True)
class WalkLimits:
    """Velocity limits (m/s, m/s, rad/s) and goal tolerances (m, rad)."""

    vx: float = WALK_SPEED
    vy: float = WALK_SPEED_Y
    wz: float = WALK_SPEED_THETA
    tol_xy: float = 0.002
    tol_theta: float = 0.005
    approach_s: float = 0.3  # time constant of the final approach


class WalkController:
    """State of the current move task: idle, a velocity, or a list of goals.

    Frames: goals are robot poses in FRAME_WORLD (sensor odometry); commands are twists in
    FRAME_ROBOT.
    """

    def __init__(self, limits: WalkLimits, cycle_s: float) -> None:
        """Create an idle controller.

        Args:
            limits: Speed limits and tolerances.
            cycle_s: Control period in seconds (the ALMotion cycle).
        """
        self.limits = limits
        self.cycle_s = cycle_s
        self.mode = "idle"
        self.velocity = (0.0, 0.0, 0.0)
        self.goals: list[Pose2D] = []
        self.result: bool | None = None
        self.deadline_s = math.inf
        self._elapsed = 0.0
        n = max(1, round(STALL_WINDOW_S / cycle_s))
        self._history: deque[tuple[float, float]] = deque(maxlen=n)

    @property
    def active(self) -> bool:
        """True while a move task runs (a goal, or a non-zero velocity)."""
        return self.mode != "idle"

    def clip(self, vx: float, vy: float, wz: float) -> tuple[float, float, float]:
        """A twist limited to the walk's maximum speeds."""
        lim = self.limits
        return (
            max(-lim.vx, min(lim.vx, vx)),
            max(-lim.vy, min(lim.vy, vy)),
            max(-lim.wz, min(lim.wz, wz)),
        )

    def set_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Walk at a twist (m/s, m/s, rad/s; FRAME_ROBOT) until told otherwise."""
        self.velocity = self.clip(vx, vy, wz)
        self.goals = []
        self._history.clear()
        self.mode = "velocity" if any(v != 0.0 for v in self.velocity) else "idle"
        self.result = None

    def set_goals(self, goals: list[Pose2D], current: Pose2D) -> None:
        """Walk through goal poses (FRAME_WORLD) in order; set a time budget from the path.

        Args:
            goals: Robot poses to reach, FRAME_WORLD (sensor odometry).
            current: Sensor odometry now, FRAME_WORLD.
        """
        lim = self.limits
        budget, prev = 0.0, current
        for g in goals:
            rel = pose2DInverse(prev) * g
            budget += max(
                abs(rel.x) / lim.vx + abs(rel.y) / lim.vy, abs(modulo2PI(rel.theta)) / lim.wz
            )
            prev = g
        self.goals = list(goals)
        self.velocity = (0.0, 0.0, 0.0)
        self.mode = "target" if goals else "idle"
        self.result = None if goals else True
        self.deadline_s = 2.0 * budget + 5.0
        self._elapsed = 0.0
        self._history.clear()

    def stop(self) -> None:
        """End the current task; a pending goal counts as not reached."""
        if self.mode == "target":
            self.result = False
        self.mode = "idle"
        self.velocity = (0.0, 0.0, 0.0)
        self.goals = []

    def command(self, odometry: Pose2D) -> tuple[float, float, float]:
        """The twist to command for the next cycle (m/s, m/s, rad/s; FRAME_ROBOT).

        Args:
            odometry: Sensor odometry now, FRAME_WORLD.
        """
        if self.mode == "velocity":
            return self.velocity
        if self.mode != "target":
            return (0.0, 0.0, 0.0)
        lim = self.limits
        while self.goals:
            err = pose2DInverse(odometry) * self.goals[0]
            eth = modulo2PI(err.theta)
            if math.hypot(err.x, err.y) > lim.tol_xy or abs(eth) > lim.tol_theta:
                break
            self.goals.pop(0)
        if not self.goals:
            self.mode = "idle"
            self.result = True
            return (0.0, 0.0, 0.0)
        if self._elapsed > self.deadline_s:
            self.stop()
            return (0.0, 0.0, 0.0)
        # Synchronised approach: all three components arrive together; P-control at the end.
        need = max(abs(err.x) / lim.vx, abs(err.y) / lim.vy, abs(eth) / lim.wz, lim.approach_s)
        return self.clip(err.x / need, err.y / need, eth / need)

    def observe(self, commanded: tuple[float, float, float], moved: Pose2D) -> None:
        """Record one cycle's commanded twist and the true motion; fail a blocked goal.

        Args:
            commanded: The twist commanded during the cycle (FRAME_ROBOT).
            moved: The true motion during the cycle, in the robot frame at its start.
        """
        self._elapsed += self.cycle_s
        if self.mode != "target":
            return
        dt = self.cycle_s
        cmd = (math.hypot(commanded[0], commanded[1]) + TURN_RADIUS * abs(commanded[2])) * dt
        real = math.hypot(moved.x, moved.y) + TURN_RADIUS * abs(modulo2PI(moved.theta))
        self._history.append((cmd, real))
        if len(self._history) < (self._history.maxlen or 1):
            return
        total_cmd = sum(c for c, _ in self._history)
        total_real = sum(r for _, r in self._history)
        if total_cmd > STALL_MIN_CMD and total_real < STALL_RATIO * total_cmd:
            self.stop()
