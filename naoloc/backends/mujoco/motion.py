"""ALMotion and ALRobotPosture on the MuJoCo simulation, with NAOqi's names and semantics.

Blocking calls (moveTo, waitUntilMoveIsFinished, wakeUp, rest, moveInit, goToPosture,
angleInterpolationWithSpeed) advance simulated time by what they need; every other call
advances it by one ALMotion cycle (20 ms), after doing what it does and before reading
what it returns, so a loop polling ``moveIsActive()`` makes progress.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from naoloc.backends.mujoco.nao import POSTURES, STANDING_POSTURES
from naoloc.backends.mujoco.sim import Simulation
from naoloc.constants import POSTURES as POSTURE_NAMES
from naoloc.errors import MotionError, RobotError
from naoloc.geometry import Pose2D, pose2DInverse
from naoloc.robot import Angles, Names, expand_joint_names, kinematics, rules

_SETTLE_CYCLES = 5  # cycles of standing still after a move, for the body to come to rest
_MAX_POSTURE_S = 30.0  # a posture change never takes longer than this (simulated s)


def _floats(values: Angles, count: int, what: str) -> list[float]:
    return rules.per_joint(values, count, what)


def _fraction(value: float, what: str) -> float:
    return rules.fraction(value, f"{what}: speed fraction")


class _WalkFuture:
    """A libqi-like future of ``moveTo(..., _async=True)``; waiting runs the simulation."""

    def __init__(self, motion: MujocoMotion, reached: bool | None) -> None:
        self._motion = motion
        self._immediate = reached

    def isFinished(self) -> bool:
        """True once the walk ended (does not advance time)."""
        return self._immediate is not None or self._motion._sim.walk.mode != "target"

    def value(self, timeout: int | None = None) -> bool:
        """Run the simulation until the walk ends; True when the target was reached."""
        if self._immediate is not None:
            return self._immediate
        return self._motion._finish_walk()

    def wait(self, timeout: int | None = None) -> None:
        """Run the simulation until the walk ends."""
        self.value()

    def hasError(self, timeout: int | None = None) -> bool:
        """Always False: a failed walk is a False result."""
        return False

    def cancel(self) -> None:
        """Stop the walk."""
        self._motion.stopMove()


class MujocoMotion:
    """ALMotion: walking, joints, stiffness and odometry of the simulated NAO."""

    def __init__(self, sim: Simulation) -> None:
        """Serve ALMotion on a simulation."""
        self._sim = sim

    # ------------------------------------------------------------------ stiffness, posture
    def wakeUp(self) -> None:
        """Motors on; stand up to StandInit unless already standing; blocking."""
        sim = self._sim
        sim.stiffness[:] = 1.0
        sim.apply_stiffness()
        if sim.detect_posture() not in STANDING_POSTURES:
            self._go_to_posture("StandInit", 0.5)
        else:
            sim.cycle()

    def rest(self) -> None:
        """Stop walking, crouch, motors off; blocking."""
        sim = self._sim
        self._stop_walk()
        if sim.awake:
            self._go_to_posture("Crouch", 0.5)
        sim.stiffness[:] = 0.0
        sim.apply_stiffness()
        sim.cycle()

    def robotIsWakeUp(self) -> bool:
        """True when the leg joints are stiff."""
        self._sim.cycle()
        return self._sim.awake

    def setStiffnesses(self, names: Names, stiffnesses: Angles) -> None:
        """Set joint stiffness in [0, 1] (values are clipped); non-blocking."""
        joints = expand_joint_names(names)
        values = _floats(stiffnesses, len(joints), "setStiffnesses")
        for n, v in zip(joints, values, strict=True):
            self._sim.stiffness[self._sim.joint_index[n]] = min(1.0, max(0.0, v))
        self._sim.apply_stiffness()
        self._sim.cycle()

    def getStiffnesses(self, names: Names) -> list[float]:
        """Stiffness of joints in [0, 1]."""
        joints = expand_joint_names(names)
        self._sim.cycle()
        return [float(self._sim.stiffness[self._sim.joint_index[n]]) for n in joints]

    def moveInit(self) -> None:
        """Take the walk-ready posture (StandInit legs) if not in it; blocking."""
        if not self._sim.awake:
            raise MotionError("moveInit: the robot is not awake (call wakeUp first)")
        if self._sim.detect_posture() != "StandInit":
            self._go_to_posture("StandInit", 0.5)
        else:
            self._sim.cycle()

    # ------------------------------------------------------------------ walking
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

    def moveTo(self, *args: Any, **kwargs: Any) -> bool:
        """Walk to a pose given in FRAME_ROBOT; blocks until done.

        Forms: ``moveTo(x, y, theta)``, ``moveTo(x, y, theta, moveConfig)`` (the config is
        accepted and ignored), ``moveTo([[x, y, theta], ...])`` (control points, each in
        FRAME_ROBOT at the call). Metres and radians.

        Returns:
            True when the last pose was reached; False when the robot is not awake, was
            blocked by an obstacle for a second, or ran out of time.

        Raises:
            RobotError: For arguments that are not one of the forms above.
        """
        run_async = bool(kwargs.pop("_async", False))
        if kwargs:
            raise RobotError(f"moveTo: unexpected keyword arguments {sorted(kwargs)}")
        points = self._parse_move_to(args)
        sim = self._sim
        if not self._ready_to_walk():
            sim.cycle()
            return _WalkFuture(self, False) if run_async else False  # type: ignore[return-value]
        start = sim.sensor_odometry  # open loop on odometry, as NAO's walk
        sim.walk.set_goals([start * p for p in points], start)
        if run_async:
            sim.cycle()
            return _WalkFuture(self, None)  # type: ignore[return-value]
        return self._finish_walk()

    def _finish_walk(self) -> bool:
        sim = self._sim
        while sim.walk.mode == "target":
            sim.cycle()
        sim.cycle(_SETTLE_CYCLES)
        while not sim.sway.settled:  # the walk ends with the body still
            sim.cycle()
        return bool(sim.walk.result)

    @staticmethod
    def _parse_move_to(args: Sequence[Any]) -> list[Pose2D]:
        points, _ = rules.move_to_points(args)  # the moveConfig is checked, then not used
        return [Pose2D(*p) for p in points]

    def move(self, x: float, y: float, theta: float) -> None:
        """Walk at a velocity (m/s, m/s, rad/s; FRAME_ROBOT), clipped to the walk's limits."""
        vals = [float(x), float(y), float(theta)]
        if not all(math.isfinite(v) for v in vals):
            raise RobotError("move: the velocity must be finite")
        if any(vals) and not self._ready_to_walk():
            self._sim.cycle()
            return
        self._sim.walk.set_velocity(*vals)
        self._sim.cycle()

    def moveToward(self, x: float, y: float, theta: float) -> None:
        """Walk at a normalised velocity, each component in [-1, 1]; non-blocking."""
        vals, _ = rules.velocity((x, y, theta), True, "moveToward")
        lim = self._sim.walk.limits
        self.move(vals[0] * lim.vx, vals[1] * lim.vy, vals[2] * lim.wz)

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the current move task ends.

        Raises:
            MotionError: When the task is a velocity walk (move/moveToward), which never
                ends by itself: on a robot this call would block forever.
        """
        sim = self._sim
        if sim.walk.mode == "velocity":
            raise MotionError(
                "waitUntilMoveIsFinished: a move() velocity never ends by itself; call stopMove()"
            )
        while sim.walk.mode == "target":
            sim.cycle()
        sim.cycle()
        while not sim.sway.settled:  # the walk ends with the body still
            sim.cycle()

    def moveIsActive(self) -> bool:
        """True while a move task runs."""
        self._sim.cycle()
        return self._sim.walk.active

    def stopMove(self) -> None:
        """Stop walking; the robot comes to rest within a few cycles."""
        self._sim.walk.stop()
        self._sim.cycle()

    def killMove(self) -> None:
        """Stop walking at once (same as stopMove in the simulator)."""
        self.stopMove()

    # ------------------------------------------------------------------ odometry
    def getRobotPosition(self, useSensors: bool) -> list[float]:
        """``[x, y, theta]`` in FRAME_WORLD: sensor odometry (drifts) or integrated commands."""
        sim = self._sim
        sim.cycle()
        pose = sim.sensor_odometry if useSensors else sim.command_odometry
        return [float(v) for v in pose.normalized().to_list()]

    def getNextRobotPosition(self) -> list[float]:
        """Where the current move will end, ``[x, y, theta]`` in FRAME_WORLD (commands)."""
        sim = self._sim
        sim.cycle()
        if sim.walk.mode == "target" and sim.walk.goals:
            rest = pose2DInverse(sim.sensor_odometry) * sim.walk.goals[-1]
            return (sim.command_odometry * rest).normalized().to_list()
        return sim.command_odometry.normalized().to_list()

    def getRobotVelocity(self) -> list[float]:
        """The commanded ``[vx, vy, wz]`` in FRAME_ROBOT, m/s and rad/s."""
        self._sim.cycle()
        return [float(v) for v in self._sim.command_velocity]

    # ------------------------------------------------------------------ joints
    def setAngles(self, names: Names, angles: Angles, fractionMaxSpeed: float) -> None:
        """Move joints toward angles (rad) at a fraction of their max speed; non-blocking."""
        joints = expand_joint_names(names)
        values = _floats(angles, len(joints), "setAngles")
        self._sim.set_joint_targets(joints, values, _fraction(fractionMaxSpeed, "setAngles"))
        self._sim.cycle()

    def angleInterpolationWithSpeed(
        self, names: Names, targetAngles: Angles, maxSpeedFraction: float
    ) -> None:
        """Move joints to angles (rad) at a fraction of max speed; blocks until there."""
        joints = expand_joint_names(names)
        values = _floats(targetAngles, len(joints), "angleInterpolationWithSpeed")
        frac = _fraction(maxSpeedFraction, "angleInterpolationWithSpeed")
        self._sim.set_joint_targets(joints, values, frac)
        self._run_until_settled(joints)

    def getAngles(self, names: Names, useSensors: bool) -> list[float]:
        """Joint angles in radians (measured, or commanded), in the order of the names."""
        joints = expand_joint_names(names)
        self._sim.cycle()
        return self._sim.joint_angles(joints, bool(useSensors))

    def getPosition(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """``[x, y, z, wx, wy, wz]`` of an effector in a frame (m, rad; ``wy > 0`` looks down).

        Names: CameraTop, CameraBottom, Head, Torso, LLeg, RLeg; frames FRAME_TORSO 0,
        FRAME_WORLD 1, FRAME_ROBOT 2. From the joints' forward kinematics (naoloc.robot.kinematics).
        """
        self._sim.cycle()
        return kinematics.position6d(self._transform(name, frame, useSensorValues))

    def getTransform(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """The effector's 4x4 transform in a frame, 16 floats row-major (metres)."""
        self._sim.cycle()
        t = self._transform(name, frame, useSensorValues)
        return [float(v) for v in t.reshape(-1)]

    def _transform(self, name: str, frame: int, use_sensors: bool) -> Any:
        sim, sensors = self._sim, bool(use_sensors)
        angles = sim.fk_angles(sensors)
        odometry = sim.sensor_odometry if sensors else sim.command_odometry
        offset = sim.sway.torso_offset() if sensors else None
        return kinematics.transform(str(name), int(frame), angles, odometry.to_list(), offset)

    def getBodyNames(self, name: str) -> list[str]:
        """Joint names of a chain ("Body", "Head", "LArm", ...) or of one joint."""
        return expand_joint_names(name)

    def _run_until_settled(self, joints: list[str]) -> None:
        sim = self._sim
        limit = round(_MAX_POSTURE_S / sim.cycle_s)
        for _ in range(limit):
            sim.cycle()
            if sim.joints_settled(joints):
                break
        sim.posture_name = sim.detect_posture()

    def _go_to_posture(self, name: str, fraction: float) -> None:
        sim = self._sim
        self._stop_walk()
        angles = POSTURES[name]
        joints = list(angles)
        sim.set_joint_targets(joints, [angles[j] for j in joints], fraction)
        self._run_until_settled(joints)
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
