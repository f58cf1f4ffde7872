"""ALMotion of the fake robot: the body under the one ALMotion call surface.

NAOqi's semantics are :class:`naoloc.backends.simulated.motion.SimulatedMotion`'s; the
fake body adds its kinematics: the walk is kinematic within NAO's walk speeds (a
moveConfig's MaxStepX/Y/Theta and MaxStepFrequency lower them) and stops where the
robot's disc of radius 0.15 m would touch a wall; ``wakeUp`` keeps the current posture
and a walk first takes StandInit when the robot is not standing; joints move only while
stiff.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from naoloc.backends.fake.walk import PathWalk, SpeedLimits, VelocityWalk
from naoloc.backends.fake.world import DEFAULT_LIMITS, FakeWorld
from naoloc.backends.simulated.motion import SimulatedMotion
from naoloc.constants import (
    MAX_STEP_THETA,
    MAX_STEP_X,
    MAX_STEP_Y,
    WALK_SPEED,
    WALK_SPEED_THETA,
    WALK_SPEED_Y,
)
from naoloc.errors import RobotError
from naoloc.geometry import Pose2D

_IGNORED_MOVE_CONFIG = ("StepHeight", "TorsoWx", "TorsoWy")


def _move_limits(config: Any) -> SpeedLimits:
    """Speed limits from a NAOqi moveConfig: ``[["MaxStepX", 0.06], ...]`` (or a dict)."""
    if config is None:
        return DEFAULT_LIMITS
    try:
        pairs = list(config.items()) if isinstance(config, dict) else [tuple(p) for p in config]
        values = {str(k): float(v) for k, v in pairs}
    except (TypeError, ValueError):
        raise RobotError(f"moveConfig must be [[name, value], ...], got {config!r}") from None
    vx, vy, wz = WALK_SPEED, WALK_SPEED_Y, WALK_SPEED_THETA
    freq = 1.0
    for name, value in values.items():
        if name == "MaxStepX":
            vx = WALK_SPEED * min(max(value, MAX_STEP_X[1]), MAX_STEP_X[2]) / MAX_STEP_X[0]
        elif name == "MaxStepY":
            vy = WALK_SPEED_Y * min(max(value, MAX_STEP_Y[1]), MAX_STEP_Y[2]) / MAX_STEP_Y[0]
        elif name == "MaxStepTheta":
            wz = WALK_SPEED_THETA * min(max(value, MAX_STEP_THETA[1]), MAX_STEP_THETA[2])
            wz /= MAX_STEP_THETA[0]
        elif name == "MaxStepFrequency":
            freq = min(max(value, 0.1), 1.0)
        elif name not in _IGNORED_MOVE_CONFIG:
            raise RobotError(f"unknown moveConfig parameter {name!r}")
    return SpeedLimits(vx * freq, vy * freq, wz * freq)


class _PathWalk:
    """A moveTo walk of the fake body."""

    def __init__(self, world: FakeWorld, task: PathWalk) -> None:
        self._world, self._task = world, task

    def finished(self) -> bool:
        return self._world.task is not self._task and self._world.sway.settled

    def finish(self) -> bool:
        self._world.run_until(self.finished, "moveTo")
        return self._task.done

    def cancel(self) -> None:
        self._world.stop_walk()


class FakeMotion(SimulatedMotion):
    """ALMotion of the fake robot (NAOqi's semantics: :class:`SimulatedMotion`).

    Args:
        world: The shared robot state and clock.
    """

    def __init__(self, world: FakeWorld) -> None:
        super().__init__()
        self._world = world

    def _check_open(self) -> None:
        self._world.check_open()

    def _advance(self, cycles: int = 1) -> None:
        self._world.tick(cycles)

    def _is_awake(self) -> bool:
        return self._world.awake

    def _set_stiffness(self, joints: list[str], values: list[float]) -> None:
        for joint, value in zip(joints, values, strict=True):
            self._world.stiffness[joint] = value

    def _stiffness(self, joints: list[str]) -> list[float]:
        return [float(self._world.stiffness[j]) for j in joints]

    def _wake_up(self) -> None:
        w = self._world
        for name in w.stiffness:
            w.stiffness[name] = 1.0
        w.tick(round(1.0 / w.dt))  # about 1 s; the posture is kept

    def _rest(self) -> None:
        w = self._world
        w.stop_walk()
        w.go_to_posture("Crouch", 0.8)
        for name in w.stiffness:
            w.stiffness[name] = 0.0
        w.tick(1)

    def _move_init(self) -> None:
        w = self._world
        if w.posture != "StandInit":
            w.stop_walk()
            w.go_to_posture("StandInit", 1.0)
        w.tick()

    def _ready_to_walk(self) -> bool:
        return self._world.awake  # start_walk takes StandInit first when not standing

    def _start_path(self, goals: list[Pose2D], config: dict[str, float]) -> _PathWalk:
        w = self._world
        start = w.command
        task = PathWalk([start * g for g in goals], _move_limits(config or None))
        w.start_walk(task)
        return _PathWalk(w, task)

    def _set_velocity(self, vx: float, vy: float, wz: float) -> None:
        w = self._world
        vx = min(max(vx, -WALK_SPEED), WALK_SPEED)
        vy = min(max(vy, -WALK_SPEED_Y), WALK_SPEED_Y)
        wz = min(max(wz, -WALK_SPEED_THETA), WALK_SPEED_THETA)
        if vx == 0.0 and vy == 0.0 and wz == 0.0:
            w.stop_walk()
        elif isinstance(w.task, VelocityWalk):
            w.task.vx, w.task.vy, w.task.wz = vx, vy, wz
        else:
            w.start_walk(VelocityWalk(vx, vy, wz))

    def _max_speeds(self) -> tuple[float, float, float]:
        return WALK_SPEED, WALK_SPEED_Y, WALK_SPEED_THETA

    def _walk_mode(self) -> str:
        task = self._world.task
        return (
            "idle" if task is None else "velocity" if isinstance(task, VelocityWalk) else "target"
        )

    def _finish_walks(self) -> None:
        w = self._world
        w.run_until(lambda: w.task is None and w.sway.settled, "waitUntilMoveIsFinished")

    def _halt(self) -> None:
        self._world.stop_walk()

    def _odometry(self, use_sensors: bool) -> Pose2D:
        return self._world.sensor if use_sensors else self._world.command

    def _next_position(self) -> Pose2D:
        """Where the current moveTo ends, or where a velocity walk is in 0.5 s."""
        w = self._world
        task = w.task
        if isinstance(task, PathWalk) and not task.done:
            return task.final
        if isinstance(task, VelocityWalk):
            return w.command * Pose2D(task.vx * 0.5, task.vy * 0.5, task.wz * 0.5)
        return w.command

    def _velocity(self) -> Sequence[float]:
        return self._world.velocity  # of the last cycle

    def _set_joint_targets(self, joints: list[str], angles: list[float], fraction: float) -> None:
        w = self._world
        w.set_joint_targets(dict(zip(joints, angles, strict=True)), fraction)
        if any(j.startswith(("L", "R")) for j in joints):
            w.posture = "Unknown"  # limb joints leave the named posture

    def _settle_joints(self, joints: list[str]) -> None:
        w = self._world
        w.run_until(lambda: w.joints_settled(joints), "angleInterpolationWithSpeed")
        w.tick()

    def _joint_angles(self, joints: list[str], use_sensors: bool) -> list[float]:
        source = self._world.joint_actual if use_sensors else self._world.joint_cmd
        return [float(source[j]) for j in joints]

    def _transform(self, name: str, frame: int, use_sensors: bool) -> np.ndarray:
        return self._world.fk_transform(name, frame, use_sensors)
