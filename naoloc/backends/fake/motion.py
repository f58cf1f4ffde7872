"""ALMotion of the fake robot: kinematic walking, odometry, stiffness and head joints.

NAOqi semantics kept on purpose:

- The robot walks only when awake (leg stiffness on). ``moveTo`` on a robot at rest
  does not walk and returns False; ``move``/``moveToward`` at rest are ignored (NAOqi
  logs a warning and does nothing). ``wakeUp`` keeps the current posture; any walk
  first takes a walk-ready posture (StandInit) when the robot is not standing.
- ``moveTo`` blocks until the target is reached (True) or the walk fails (False): the
  robot's disc of radius 0.15 m would touch a wall, or the robot was put to rest.
  ``moveTo(..., _async=True)`` returns a libqi-like future instead.
- ``move``/``moveToward`` keep going until changed, ``stopMove`` or a wall;
  ``move(0, 0, 0)`` stops. Velocities above NAO's walk speeds are clipped.
- Joints move only while stiff; ``getAngles(names, False)`` gives the commanded angles,
  ``getAngles(names, True)`` the measured ones.

Every call that does not block advances simulated time by one 20 ms cycle.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from naoloc.backends.fake.walk import PathWalk, SpeedLimits, VelocityWalk
from naoloc.backends.fake.world import DEFAULT_LIMITS, FakeWorld
from naoloc.constants import (
    MAX_STEP_THETA,
    MAX_STEP_X,
    MAX_STEP_Y,
    WALK_SPEED,
    WALK_SPEED_THETA,
    WALK_SPEED_Y,
)
from naoloc.errors import MotionError, RobotError
from naoloc.geometry import Pose2D
from naoloc.robot import Angles, Names, expand_joint_names, rules
from naoloc.robot.kinematics import position6d

_IGNORED_MOVE_CONFIG = ("StepHeight", "TorsoWx", "TorsoWy")


class FakeFuture:
    """A libqi-like future of a blocking call started with ``_async=True``.

    Waiting on it runs the simulation; nothing happens in the background.
    """

    def __init__(
        self, world: FakeWorld, finished: Callable[[], bool], result: Callable[[], Any]
    ) -> None:
        self._world = world
        self._finished = finished
        self._result = result

    def value(self, timeout: int | None = None) -> Any:
        """Run the simulation until the call ends and return its result."""
        self._world.run_until(self._finished, "moveTo")
        return self._result()

    def wait(self, timeout: int | None = None) -> None:
        """Run the simulation until the call ends."""
        self._world.run_until(self._finished, "moveTo")

    def isFinished(self) -> bool:
        """True once the call ended (does not advance time)."""
        return self._finished()

    def hasError(self, timeout: int | None = None) -> bool:
        """Always False: a failed walk is a False result, not an error."""
        return False

    def cancel(self) -> None:
        """Stop the walk."""
        self._world.stop_walk()


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


def _as_floats(values: Angles, count: int, what: str) -> list[float]:
    return rules.per_joint(values, count, what)


def _fraction(value: float, what: str) -> float:
    return rules.fraction(value, f"{what}: speed fraction")


class FakeMotion:
    """ALMotion of the fake robot (see the module docstring for the semantics).

    Args:
        world: The shared robot state and clock.
    """

    def __init__(self, world: FakeWorld) -> None:
        self._world = world

    # -- stiffness and postures ------------------------------------------------------------

    def wakeUp(self) -> None:
        """Stiffen every joint and keep the current posture; blocking (about 1 s)."""
        w = self._world
        w.check_open()
        for name in w.stiffness:
            w.stiffness[name] = 1.0
        w.tick(round(1.0 / w.dt))

    def rest(self) -> None:
        """Stop walking, crouch, then relax every joint; blocking."""
        w = self._world
        w.check_open()
        w.stop_walk()
        w.go_to_posture("Crouch", 0.8)
        for name in w.stiffness:
            w.stiffness[name] = 0.0
        w.tick(1)

    def robotIsWakeUp(self) -> bool:
        """True when every leg joint is stiff."""
        self._world.tick()
        return self._world.awake

    def setStiffnesses(self, names: Names, stiffnesses: Angles) -> None:
        """Set stiffness in [0, 1] (clamped) of joints or chains; non-blocking."""
        w = self._world
        w.check_open()
        joints = expand_joint_names(names)
        values = _as_floats(stiffnesses, len(joints), "setStiffnesses")
        for joint, value in zip(joints, values, strict=True):
            w.stiffness[joint] = min(max(value, 0.0), 1.0)
        w.tick()

    def getStiffnesses(self, names: Names) -> list[float]:
        """Stiffness in [0, 1] of joints or chains."""
        w = self._world
        w.tick()
        return [float(w.stiffness[j]) for j in expand_joint_names(names)]

    def moveInit(self) -> None:
        """Take the walk-ready posture (StandInit) when awake; blocking. Does nothing at rest."""
        w = self._world
        w.check_open()
        if w.awake and w.posture != "StandInit":
            w.stop_walk()
            w.go_to_posture("StandInit", 1.0)
        w.tick()

    # -- walking -----------------------------------------------------------------------------

    def moveTo(self, *args: Any, **kwargs: Any) -> Any:
        """Walk to a pose in FRAME_ROBOT; blocking; True when reached.

        Forms: ``moveTo(x, y, theta)``, ``moveTo(x, y, theta, moveConfig)``,
        ``moveTo([[x, y, theta], ...])`` (control points, each in FRAME_ROBOT at the start),
        ``moveTo(points, moveConfig)``; metres and radians. ``_async=True`` returns a
        :class:`FakeFuture` whose ``value()`` is the bool.

        Returns:
            True when the target was reached; False when the walk could not finish
            (a wall, the robot is not awake, or another move replaced this one).

        Raises:
            RobotError: Malformed arguments.
        """
        w = self._world
        w.check_open()
        run_async = bool(kwargs.pop("_async", False))
        points, config = _parse_move_to(args, kwargs)
        if not w.awake:
            w.tick()
            if run_async:
                return FakeFuture(w, lambda: True, lambda: False)
            return False
        limits = _move_limits(config)
        start = w.command
        waypoints = [start * Pose2D(x, y, th) for x, y, th in points]
        task = PathWalk(waypoints, limits)
        w.start_walk(task)

        def finished() -> bool:
            return w.task is not task and w.sway.settled  # the walk ends with the body still

        def reached() -> bool:
            return task.done

        if run_async:
            w.tick()
            return FakeFuture(w, finished, reached)
        w.run_until(finished, "moveTo")
        return task.done

    def move(self, x: float, y: float, theta: float) -> None:
        """Walk at a velocity (m/s, m/s, rad/s, FRAME_ROBOT), clipped to NAO's walk speeds."""
        w = self._world
        w.check_open()
        vx = min(max(float(x), -WALK_SPEED), WALK_SPEED)
        vy = min(max(float(y), -WALK_SPEED_Y), WALK_SPEED_Y)
        wz = min(max(float(theta), -WALK_SPEED_THETA), WALK_SPEED_THETA)
        self._velocity(vx, vy, wz)

    def moveToward(self, x: float, y: float, theta: float) -> None:
        """Walk at a normalised velocity, each component in [-1, 1] of the maximum speed."""
        w = self._world
        w.check_open()
        (fx, fy, ft), _ = rules.velocity((x, y, theta), True, "moveToward")
        self._velocity(fx * WALK_SPEED, fy * WALK_SPEED_Y, ft * WALK_SPEED_THETA)

    def _velocity(self, vx: float, vy: float, wz: float) -> None:
        w = self._world
        if not all(math.isfinite(v) for v in (vx, vy, wz)):
            raise RobotError("move: velocities must be finite numbers")
        if vx == 0.0 and vy == 0.0 and wz == 0.0:
            w.stop_walk()
        elif w.awake:
            task = w.task
            if isinstance(task, VelocityWalk):
                task.vx, task.vy, task.wz = vx, vy, wz
            else:
                w.start_walk(VelocityWalk(vx, vy, wz))
        w.tick()

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the moveTo task ends.

        Raises:
            MotionError: A ``move()`` velocity command is active: it never ends by itself.
        """
        w = self._world
        w.check_open()
        if isinstance(w.task, VelocityWalk):
            raise MotionError("waitUntilMoveIsFinished would never return: move() is active")
        w.run_until(lambda: w.task is None and w.sway.settled, "waitUntilMoveIsFinished")

    def moveIsActive(self) -> bool:
        """True while a walk task runs."""
        self._world.tick()
        return self._world.task is not None

    def stopMove(self) -> None:
        """Stop walking at once (velocity zero)."""
        w = self._world
        w.check_open()
        w.stop_walk()
        w.tick()

    def getRobotPosition(self, useSensors: bool) -> list[float]:
        """``[x, y, theta]`` in FRAME_WORLD: True = sensor odometry (drifts), False = commands."""
        w = self._world
        w.tick()
        return (w.sensor if useSensors else w.command).normalized().to_list()

    def getNextRobotPosition(self) -> list[float]:
        """Where the current move ends (moveTo) or where it is in 0.5 s (move), FRAME_WORLD."""
        w = self._world
        w.tick()
        task = w.task
        if isinstance(task, PathWalk) and not task.done:
            return task.final.normalized().to_list()
        if isinstance(task, VelocityWalk):
            ahead = Pose2D(task.vx * 0.5, task.vy * 0.5, task.wz * 0.5)
            return (w.command * ahead).normalized().to_list()
        return w.command.normalized().to_list()

    def getRobotVelocity(self) -> list[float]:
        """``[vx, vy, wz]`` of the last cycle in FRAME_ROBOT, m/s and rad/s."""
        w = self._world
        w.tick()
        return list(w.velocity)

    # -- joints ------------------------------------------------------------------------------

    def _start_joints(
        self, names: Names, angles: Angles, fraction: float, caller: str
    ) -> list[str]:
        """Validate and set joint targets; limb joints leave the named posture."""
        w = self._world
        w.check_open()
        joints = expand_joint_names(names)
        speed = _fraction(fraction, caller)
        values = _as_floats(angles, len(joints), caller)
        w.set_joint_targets(dict(zip(joints, values, strict=True)), speed)
        if any(j.startswith(("L", "R")) for j in joints):
            w.posture = "Unknown"
        return joints

    def setAngles(self, names: Names, angles: Angles, fractionMaxSpeed: float) -> None:
        """Start moving joints toward angles (rad, clamped to limits); non-blocking."""
        self._start_joints(names, angles, fractionMaxSpeed, "setAngles")
        self._world.tick()

    def angleInterpolationWithSpeed(
        self, names: Names, targetAngles: Angles, maxSpeedFraction: float
    ) -> None:
        """Move joints to angles (rad, clamped) at a fraction of max speed; blocking."""
        caller = "angleInterpolationWithSpeed"
        joints = self._start_joints(names, targetAngles, maxSpeedFraction, caller)
        w = self._world
        w.run_until(lambda: w.joints_settled(joints), caller)
        w.tick()

    def getAngles(self, names: Names, useSensors: bool) -> list[float]:
        """Joint angles (rad) in the order of the expanded names; sensors or commands."""
        w = self._world
        w.tick()
        joints = expand_joint_names(names)
        source = w.joint_actual if useSensors else w.joint_cmd
        return [float(source[j]) for j in joints]

    def getPosition(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """``[x, y, z, wx, wy, wz]`` of an effector in a frame (m, rad; ``wy > 0`` looks down).

        Names: CameraTop, CameraBottom, Head, Torso, LLeg, RLeg; frames FRAME_TORSO 0,
        FRAME_WORLD 1, FRAME_ROBOT 2. From the joints' forward kinematics (naoloc.robot.kinematics).
        """
        self._world.tick()
        return position6d(self._world.fk_transform(str(name), int(frame), bool(useSensorValues)))

    def getTransform(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """The effector's 4x4 transform in a frame, 16 floats row-major (metres)."""
        self._world.tick()
        t = self._world.fk_transform(str(name), int(frame), bool(useSensorValues))
        return [float(v) for v in t.reshape(-1)]


def _parse_move_to(
    args: Sequence[Any], kwargs: dict[str, Any]
) -> tuple[list[tuple[float, float, float]], Any]:
    """Normalise moveTo arguments into control points (FRAME_ROBOT) and a moveConfig."""
    config = kwargs.pop("moveConfig", None)
    if kwargs:
        raise RobotError(f"moveTo: unexpected keyword arguments {sorted(kwargs)}")
    if config is not None:
        args = (*args, config)
    points, checked = rules.move_to_points(args)
    return [(p[0], p[1], p[2]) for p in points], checked or None
