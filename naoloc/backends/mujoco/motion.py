"""ALMotion and ALRobotPosture on the MuJoCo simulation: the body under the one call surface.

NAOqi's semantics are :class:`naoloc.backends.simulated.motion.SimulatedMotion`'s (time:
one ALMotion cycle per call, blocking calls what they need); the MuJoCo body walks with
its walk controller (a moveConfig is checked, then not used), wakes up to StandInit
unless standing, and settles joints within 30 simulated seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from naoloc.backends.mujoco.nao import POSTURES, STANDING_POSTURES
from naoloc.backends.mujoco.sim import Simulation
from naoloc.backends.simulated.motion import SimulatedMotion
from naoloc.constants import POSTURES as POSTURE_NAMES
from naoloc.geometry import Pose2D, pose2DInverse
from naoloc.robot import kinematics, rules

_SETTLE_CYCLES = 5  # cycles of standing still after a move, for the body to come to rest
_MAX_POSTURE_S = 30.0  # a posture change never takes longer than this (simulated s)


def _fraction(value: float, what: str) -> float:
    return rules.fraction(value, f"{what}: speed fraction")


class _TargetWalk:
    """A moveTo walk of the MuJoCo body."""

    def __init__(self, motion: MujocoMotion) -> None:
        self._motion = motion

    def finished(self) -> bool:
        return self._motion._sim.walk.mode != "target"

    def finish(self) -> bool:
        sim = self._motion._sim
        while sim.walk.mode == "target":
            sim.cycle()
        sim.cycle(_SETTLE_CYCLES)
        while not sim.sway.settled:  # the walk ends with the body still
            sim.cycle()
        return bool(sim.walk.result)

    def cancel(self) -> None:
        self._motion.stopMove()


class MujocoMotion(SimulatedMotion):
    """ALMotion of the simulated NAO (NAOqi's semantics: :class:`SimulatedMotion`)."""

    def __init__(self, sim: Simulation) -> None:
        """Serve ALMotion on a simulation."""
        super().__init__()
        self._sim = sim

    def _check_open(self) -> None:
        return None  # the simulation refuses calls by itself once closed

    def _advance(self, cycles: int = 1) -> None:
        self._sim.cycle(cycles)

    def _is_awake(self) -> bool:
        return self._sim.awake

    def _set_stiffness(self, joints: list[str], values: list[float]) -> None:
        for n, v in zip(joints, values, strict=True):
            self._sim.stiffness[self._sim.joint_index[n]] = v
        self._sim.apply_stiffness()

    def _stiffness(self, joints: list[str]) -> list[float]:
        return [float(self._sim.stiffness[self._sim.joint_index[n]]) for n in joints]

    def _wake_up(self) -> None:
        """Motors on; stand up to StandInit unless already standing."""
        sim = self._sim
        sim.stiffness[:] = 1.0
        sim.apply_stiffness()
        if sim.detect_posture() not in STANDING_POSTURES:
            self._go_to_posture("StandInit", 0.5)
        else:
            sim.cycle()

    def _rest(self) -> None:
        sim = self._sim
        self._stop_walk()
        if sim.awake:
            self._go_to_posture("Crouch", 0.5)
        sim.stiffness[:] = 0.0
        sim.apply_stiffness()
        sim.cycle()

    def _move_init(self) -> None:
        if self._sim.detect_posture() != "StandInit":
            self._go_to_posture("StandInit", 0.5)
        else:
            self._sim.cycle()

    def _stop_walk(self) -> None:
        walk = self._sim.walk
        if walk.active:
            walk.stop()
            self._sim.cycle(_SETTLE_CYCLES)

    def _ready_to_walk(self) -> bool:
        sim = self._sim
        if not sim.awake:
            return False
        if sim.detect_posture() not in STANDING_POSTURES:
            self._go_to_posture("StandInit", 0.5)
        return True

    def _start_path(self, goals: list[Pose2D], config: dict[str, float]) -> _TargetWalk:
        sim = self._sim  # the moveConfig is checked, then not used
        start = sim.sensor_odometry  # open loop on odometry, as NAO's walk
        sim.walk.set_goals([start * g for g in goals], start)
        return _TargetWalk(self)

    def _set_velocity(self, vx: float, vy: float, wz: float) -> None:
        self._sim.walk.set_velocity(vx, vy, wz)

    def _max_speeds(self) -> tuple[float, float, float]:
        lim = self._sim.walk.limits
        return lim.vx, lim.vy, lim.wz

    def _walk_mode(self) -> str:
        return self._sim.walk.mode

    def _finish_walks(self) -> None:
        sim = self._sim
        while sim.walk.mode == "target":
            sim.cycle()
        sim.cycle()
        while not sim.sway.settled:  # the walk ends with the body still
            sim.cycle()

    def _halt(self) -> None:
        self._sim.walk.stop()

    def _odometry(self, use_sensors: bool) -> Pose2D:
        return self._sim.sensor_odometry if use_sensors else self._sim.command_odometry

    def _next_position(self) -> Pose2D:
        sim = self._sim
        if sim.walk.mode == "target" and sim.walk.goals:
            rest = pose2DInverse(sim.sensor_odometry) * sim.walk.goals[-1]
            return sim.command_odometry * rest
        return sim.command_odometry

    def _velocity(self) -> Sequence[float]:
        return self._sim.command_velocity  # commanded

    def _set_joint_targets(self, joints: list[str], angles: list[float], fraction: float) -> None:
        self._sim.set_joint_targets(joints, angles, fraction)

    def _settle_joints(self, joints: list[str]) -> None:
        sim = self._sim
        limit = round(_MAX_POSTURE_S / sim.cycle_s)
        for _ in range(limit):
            sim.cycle()
            if sim.joints_settled(joints):
                break
        sim.posture_name = sim.detect_posture()

    def _joint_angles(self, joints: list[str], use_sensors: bool) -> list[float]:
        return self._sim.joint_angles(joints, use_sensors)

    def _transform(self, name: str, frame: int, use_sensors: bool) -> Any:
        sim = self._sim
        angles = sim.fk_angles(use_sensors)
        odometry = sim.sensor_odometry if use_sensors else sim.command_odometry
        offset = sim.sway.torso_offset() if use_sensors else None
        return kinematics.transform(name, frame, angles, odometry.to_list(), offset)

    def _go_to_posture(self, name: str, fraction: float) -> None:
        sim = self._sim
        self._stop_walk()
        angles = POSTURES[name]
        joints = list(angles)
        sim.set_joint_targets(joints, [angles[j] for j in joints], fraction)
        self._settle_joints(joints)
        sim.posture_name = name


class MujocoPosture:
    """ALRobotPosture: NAOqi's predefined postures on the simulated NAO."""

    def __init__(self, sim: Simulation, motion: MujocoMotion) -> None:
        """Serve ALRobotPosture on a simulation, moving joints through ``motion``."""
        self._sim = sim
        self._motion = motion

    def goToPosture(self, postureName: str, maxSpeedFraction: float) -> bool:
        """Go to a predefined posture; blocking; True when reached.

        Returns False when the robot is not awake (the joints cannot move).

        Raises:
            RobotError: For a name that is not a predefined posture.
        """
        rules.posture_name(postureName)
        frac = _fraction(maxSpeedFraction, "goToPosture")
        if not self._sim.awake:
            self._sim.cycle()
            return False
        self._motion._go_to_posture(postureName, frac)
        return self._sim.detect_posture() == postureName

    def getPosture(self) -> str:
        """Name of the current posture, or "Unknown"."""
        self._sim.cycle()
        return self._sim.detect_posture()

    def getPostureList(self) -> list[str]:
        """Names of the predefined postures."""
        return list(POSTURE_NAMES)

    def stopMove(self) -> None:
        """Stop a posture change (they are blocking here, so nothing is running)."""
        self._sim.cycle()
