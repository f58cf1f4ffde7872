"""ALMotion's call surface for the simulated robots, written once.

:class:`SimulatedMotion` is the ALMotion of the fake and the MuJoCo robot, in process and
behind ``naoloc serve`` (whose front adds NAOqi's tasks, threads and clock on top:
:mod:`naoloc.backends.naoqi.emulation.motion`). It holds NAOqi's semantics: the argument
rules (:mod:`naoloc.robot.rules`), name expansion, the forms of ``moveTo``, ``move`` and
``moveToward`` (with the SDK examples' ``Frequency``), the libqi-like future of
``moveTo(..., _async=True)``, and the bookkeeping calls (flags, configs, body names). A
backend subclasses it and supplies the body only: walking, joints, stiffness, postures,
odometry and kinematics (the ``_`` methods a subclass implements).

NAOqi semantics kept on purpose:

- The robot walks only when awake (leg stiffness on). ``moveTo`` on a robot at rest does
  not walk and returns False; ``move``/``moveToward`` at rest are ignored (NAOqi logs a
  warning and does nothing); ``moveInit`` at rest raises.
- ``moveTo`` blocks until the target is reached (True) or the walk fails (False: blocked,
  the robot was put to rest, or another move replaced it). ``moveTo(..., _async=True)``
  returns a :class:`SimFuture` instead.
- ``move``/``moveToward`` keep going until changed, ``stopMove`` or an obstacle;
  ``move(0, 0, 0)`` stops. Velocities above the walk's speeds are clipped.
- ``getAngles(names, False)`` gives the commanded angles, ``getAngles(names, True)`` the
  measured ones.

Time: every call that reads or commands the body advances simulated time by one 20 ms
ALMotion cycle, after doing what it does and before reading what it returns, so a loop
polling ``moveIsActive()`` makes progress; blocking calls advance it by what they need;
bookkeeping calls (flags, configs, names) do not touch the body.
"""

from __future__ import annotations

import abc
from collections.abc import Sequence
from typing import Any, Final, Protocol

import numpy as np

from naoloc.constants import JOINT_NAMES
from naoloc.errors import MotionError, RobotError
from naoloc.geometry import Pose2D
from naoloc.robot import kinematics, rules

# NAO's step period (s) at MaxStepFrequency 0 and 1 (NAOqi's walk: about 0.6 s to 0.42 s).
STEP_PERIOD_SLOW_S: Final = 0.6
STEP_PERIOD_FAST_S: Final = 0.42

_CHAINS_WITH_FLAGS = ("LArm", "RArm", "Arms", "LLeg", "RLeg", "Legs", "Head", "Body", "All", "Move")


def _legacy_frequency(args: tuple[Any, ...]) -> tuple[tuple[Any, ...], float]:
    """Take ``["Frequency", f]`` out of a moveToward moveConfig; the rest and f (default 1).

    Raises:
        RobotError: Frequency is not a number in [0, 1].
    """
    if len(args) != 4 or not isinstance(args[3], list | tuple):
        return args, 1.0
    rest, frequency = [], 1.0
    for pair in args[3]:
        if isinstance(pair, list | tuple) and len(pair) == 2 and pair[0] == "Frequency":
            frequency = rules.finite(pair[1], "moveConfig Frequency")
            if not 0.0 <= frequency <= 1.0:
                raise RobotError(f"moveConfig Frequency must be in [0, 1], got {frequency}")
        else:
            rest.append(pair)
    return (*args[:3], rest), frequency


def walk_fractions(args: tuple[Any, ...]) -> list[float]:
    """moveToward's arguments as fractions of the walk's maximum speeds, each in [-1, 1].

    ``(x, y, theta[, moveConfig])``. The moveConfig takes NAOqi's walk parameters and the
    SDK examples' ``Frequency`` (legacy name of ``MaxStepFrequency``, in [0, 1]). The step
    frequency scales the speed: the simulated walks keep their step period, so a fraction
    ``f`` walks at ``STEP_PERIOD_FAST_S / step period`` of full speed, the step period
    going from ``STEP_PERIOD_SLOW_S`` (f = 0) to ``STEP_PERIOD_FAST_S`` (f = 1). The other
    parameters are checked, then not used.

    Raises:
        RobotError: Wrong arguments (count, range, a moveConfig NAOqi does not know).
    """
    args, frequency = _legacy_frequency(args)
    values, config = rules.velocity(args, True, "moveToward")
    frequency = config.get("MaxStepFrequency", frequency)
    period = STEP_PERIOD_FAST_S + (STEP_PERIOD_SLOW_S - STEP_PERIOD_FAST_S) * (1.0 - frequency)
    scale = STEP_PERIOD_FAST_S / period
    return [v * scale for v in values]


def _chain(name: Any, what: str) -> str:
    if name not in _CHAINS_WITH_FLAGS:
        raise RobotError(
            f"{what}: unknown chain name {name!r}; valid: {', '.join(_CHAINS_WITH_FLAGS)}"
        )
    return str(name)


class Walk(Protocol):
    """A ``moveTo`` walk the body started."""

    def finished(self) -> bool:
        """True once the walk ended and the body is still (does not advance time)."""
        ...

    def finish(self) -> bool:
        """Run the simulation until the walk ends; True when the target was reached."""
        ...

    def cancel(self) -> None:
        """Stop the walk."""
        ...


class SimFuture:
    """A libqi-like future of ``moveTo(..., _async=True)``; waiting runs the simulation.

    Args:
        walk: The walk (None: the call ended at once with ``result``).
        result: The result of a call that ended at once.
    """

    def __init__(self, walk: Walk | None, result: bool = False) -> None:
        self._walk = walk
        self._result = result

    def isFinished(self) -> bool:
        """True once the walk ended (does not advance time)."""
        return self._walk is None or self._walk.finished()

    def value(self, timeout: int | None = None) -> bool:
        """Run the simulation until the walk ends; True when the target was reached."""
        return self._result if self._walk is None else self._walk.finish()

    def wait(self, timeout: int | None = None) -> None:
        """Run the simulation until the walk ends."""
        self.value()

    def hasError(self, timeout: int | None = None) -> bool:
        """Always False: a failed walk is a False result, not an error."""
        return False

    def cancel(self) -> None:
        """Stop the walk."""
        if self._walk is not None:
            self._walk.cancel()


class SimulatedMotion(abc.ABC):
    """ALMotion of a simulated NAO (see the module docstring); subclasses give the body."""

    def __init__(self) -> None:
        self._move_arms = {"LArm": True, "RArm": True}
        self._collision = {"LArm": True, "RArm": True}
        self._external = {"All": True, "Move": True, "Arms": True, "LArm": True, "RArm": True}
        self._flags: dict[str, bool] = {"fall": True, "smart": True}
        self._breath: dict[str, bool] = {}
        self._idle: dict[str, bool] = {}
        self._motion_config: dict[str, Any] = {}

    # ------------------------------------------------------------------ the body
    @abc.abstractmethod
    def _check_open(self) -> None:
        """Raise RobotError when the robot was closed."""

    @abc.abstractmethod
    def _advance(self, cycles: int = 1) -> None:
        """Advance simulated time by whole ALMotion cycles."""

    @abc.abstractmethod
    def _is_awake(self) -> bool:
        """True when the leg joints are stiff."""

    @abc.abstractmethod
    def _set_stiffness(self, joints: list[str], values: list[float]) -> None:
        """Set joints' stiffness (each in [0, 1])."""

    @abc.abstractmethod
    def _stiffness(self, joints: list[str]) -> list[float]:
        """Joints' stiffness in [0, 1]."""

    @abc.abstractmethod
    def _wake_up(self) -> None:
        """Motors on and the posture NAO takes on waking; blocking."""

    @abc.abstractmethod
    def _rest(self) -> None:
        """Stop walking, crouch, motors off; blocking."""

    @abc.abstractmethod
    def _move_init(self) -> None:
        """Take the walk-ready posture (StandInit) of an awake robot; blocking."""

    @abc.abstractmethod
    def _ready_to_walk(self) -> bool:
        """False at rest; an awake robot not standing takes StandInit first."""

    @abc.abstractmethod
    def _start_path(self, goals: list[Pose2D], config: dict[str, float]) -> Walk:
        """Start walking through ``goals`` (each FRAME_ROBOT at the call), checked config."""

    @abc.abstractmethod
    def _set_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Walk at a twist (m/s, m/s, rad/s; FRAME_ROBOT; clipped); all zero stops."""

    @abc.abstractmethod
    def _max_speeds(self) -> tuple[float, float, float]:
        """The walk's maximum speeds (m/s, m/s, rad/s), moveToward's 1.0."""

    @abc.abstractmethod
    def _walk_mode(self) -> str:
        """ "idle", "velocity" (move/moveToward) or "target" (moveTo)."""

    @abc.abstractmethod
    def _finish_walks(self) -> None:
        """Run the simulation until a moveTo walk ended and the body is still."""

    @abc.abstractmethod
    def _halt(self) -> None:
        """Stop walking now; a pending moveTo target counts as not reached."""

    @abc.abstractmethod
    def _odometry(self, use_sensors: bool) -> Pose2D:
        """Odometry in FRAME_WORLD: sensors (drifts) or integrated commands."""

    @abc.abstractmethod
    def _next_position(self) -> Pose2D:
        """Where the current move ends, FRAME_WORLD."""

    @abc.abstractmethod
    def _velocity(self) -> Sequence[float]:
        """``(vx, vy, wz)`` of the body, FRAME_ROBOT."""

    @abc.abstractmethod
    def _set_joint_targets(self, joints: list[str], angles: list[float], fraction: float) -> None:
        """Start moving joints toward angles (rad) at a fraction of their speed."""

    @abc.abstractmethod
    def _settle_joints(self, joints: list[str]) -> None:
        """Run the simulation until the joints reached their targets; blocking."""

    @abc.abstractmethod
    def _joint_angles(self, joints: list[str], use_sensors: bool) -> list[float]:
        """Joint angles (rad): measured or commanded."""

    @abc.abstractmethod
    def _transform(self, name: str, frame: int, use_sensors: bool) -> np.ndarray:
        """4x4 transform of an effector in a frame (naoloc.robot.kinematics)."""

    # ------------------------------------------------------------------ stiffness, posture
    def wakeUp(self) -> None:
        """Motors on; blocking."""
        self._check_open()
        self._wake_up()

    def rest(self) -> None:
        """Stop walking, crouch, then motors off; blocking."""
        self._check_open()
        self._rest()

    def robotIsWakeUp(self) -> bool:
        """True when the leg joints are stiff."""
        self._advance()
        return self._is_awake()

    def setStiffnesses(self, names: Any, stiffnesses: Any) -> None:
        """Stiffness in [0, 1] (clipped) of joints, chains or groups; non-blocking."""
        self._check_open()
        joints = rules.expand_names(names)
        values = rules.per_joint(stiffnesses, len(joints), "setStiffnesses")
        self._set_stiffness(joints, [min(1.0, max(0.0, v)) for v in values])
        self._advance()

    def getStiffnesses(self, names: Any) -> list[float]:
        """Stiffness in [0, 1] of each expanded joint."""
        joints = rules.expand_names(names)
        self._advance()
        return [float(v) for v in self._stiffness(joints)]

    def moveInit(self) -> None:
        """Take the walk-ready posture (StandInit) if not in it; blocking.

        Raises:
            MotionError: The robot is not awake.
        """
        self._check_open()
        if not self._is_awake():
            raise MotionError("moveInit: the robot is not awake (call wakeUp first)")
        self._move_init()

    # ------------------------------------------------------------------ walking
    def moveTo(self, *args: Any, **kwargs: Any) -> Any:
        """Walk to a pose in FRAME_ROBOT; blocking; True when reached.

        Forms: ``moveTo(x, y, theta)``, ``moveTo(x, y, theta, moveConfig)``,
        ``moveTo([[x, y, theta], ...])`` (control points, each in FRAME_ROBOT at the start),
        ``moveTo(points, moveConfig)``; metres and radians. ``_async=True`` returns a
        :class:`SimFuture` whose ``value()`` is the bool.

        Returns:
            True when the target was reached; False when the walk could not finish (an
            obstacle, the robot is not awake, or another move replaced this one).

        Raises:
            RobotError: Malformed arguments.
        """
        self._check_open()
        run_async = bool(kwargs.pop("_async", False))
        config = kwargs.pop("moveConfig", None)
        if kwargs:
            raise RobotError(f"moveTo: unexpected keyword arguments {sorted(kwargs)}")
        if config is not None:
            args = (*args, config)
        points, checked = rules.move_to_points(args)
        if not self._ready_to_walk():
            self._advance()
            return SimFuture(None, False) if run_async else False
        walk = self._start_path([Pose2D(*p) for p in points], checked)
        if run_async:
            self._advance()
            return SimFuture(walk)
        return walk.finish()

    def move(self, x: Any, y: Any, theta: Any) -> None:
        """Walk at a velocity (m/s, m/s, rad/s; FRAME_ROBOT), clipped to the walk's speeds."""
        self._check_open()
        values, _ = rules.velocity((x, y, theta), False, "move")
        self._walk_at(*values)

    def moveToward(self, *args: Any) -> None:
        """Walk at a normalised velocity, each component in [-1, 1] of the maximum speed.

        ``moveToward(x, y, theta[, moveConfig])``; see :func:`walk_fractions`.
        """
        self._check_open()
        fx, fy, ft = walk_fractions(args)
        sx, sy, st = self._max_speeds()
        self._walk_at(fx * sx, fy * sy, ft * st)

    def _walk_at(self, vx: float, vy: float, wz: float) -> None:
        if (vx or vy or wz) and not self._ready_to_walk():
            self._advance()  # at rest: NAOqi ignores the call
            return
        self._set_velocity(vx, vy, wz)
        self._advance()

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the moveTo walk ends.

        Raises:
            MotionError: A ``move()`` velocity walk is active: it never ends by itself (on
                a robot this call would block forever).
        """
        self._check_open()
        if self._walk_mode() == "velocity":
            raise MotionError(
                "waitUntilMoveIsFinished would never return: a move() velocity walk is "
                "active; call stopMove()"
            )
        self._finish_walks()

    def moveIsActive(self) -> bool:
        """True while a walk runs."""
        self._advance()
        return self._walk_mode() != "idle"

    def stopMove(self) -> None:
        """Stop walking (a blocking moveTo returns False)."""
        self._check_open()
        self._halt()
        self._advance()

    def killMove(self) -> None:
        """Stop walking at once (as stopMove in the simulator)."""
        self.stopMove()

    def getMoveConfig(self, config: Any) -> list[list[Any]]:
        """``[[name, value], ...]`` of the walk's "Default", "Min" or "Max" parameters."""
        column = {"Default": 0, "Min": 1, "Max": 2}.get(config)
        if column is None:
            raise RobotError(f"config must be Default, Min or Max, got {config!r}")
        return [[k, float(v[column])] for k, v in rules.MOVE_CONFIG_KEYS.items()]

    def setMoveArmsEnabled(self, leftArmEnabled: Any, rightArmEnabled: Any) -> None:
        """Whether the arms swing while walking (stored; the simulated arms do not swing)."""
        self._move_arms.update(LArm=bool(leftArmEnabled), RArm=bool(rightArmEnabled))

    def getMoveArmsEnabled(self, chainName: Any) -> bool:
        """Arm swing flag of "LArm", "RArm" or "Arms" (both)."""
        if chainName == "Arms":
            return all(self._move_arms.values())
        if chainName not in self._move_arms:
            raise RobotError(f"chain name must be LArm, RArm or Arms, got {chainName!r}")
        return self._move_arms[chainName]

    # ------------------------------------------------------------------ odometry
    def getRobotPosition(self, useSensors: Any) -> list[float]:
        """``[x, y, theta]`` in FRAME_WORLD: True = sensor odometry (drifts), False = commands."""
        self._advance()
        return self._odometry(bool(useSensors)).normalized().to_list()

    def getNextRobotPosition(self) -> list[float]:
        """Where the current move ends, ``[x, y, theta]`` in FRAME_WORLD."""
        self._advance()
        return self._next_position().normalized().to_list()

    def getRobotVelocity(self) -> list[float]:
        """``[vx, vy, wz]`` in FRAME_ROBOT, m/s and rad/s."""
        self._advance()
        return [float(v) for v in self._velocity()]

    # ------------------------------------------------------------------ joints
    def setAngles(self, names: Any, angles: Any, fractionMaxSpeed: Any) -> None:
        """Move joints toward angles (rad, clamped to their limits) at a speed fraction (one,
        or one per joint); non-blocking."""
        self._check_open()
        joints = rules.expand_names(names)
        values = rules.per_joint(angles, len(joints), "setAngles")
        if isinstance(fractionMaxSpeed, list | tuple):
            each = rules.per_joint(fractionMaxSpeed, len(joints), "speed fractions")
            fractions = [rules.fraction(f, "setAngles: speed fraction") for f in each]
        else:
            fractions = [rules.fraction(fractionMaxSpeed, "setAngles: speed fraction")]
            fractions *= len(joints)
        groups: dict[float, tuple[list[str], list[float]]] = {}
        for joint, value, frac in zip(joints, values, fractions, strict=True):
            group = groups.setdefault(frac, ([], []))
            group[0].append(joint)
            group[1].append(value)
        for frac, (js, vs) in groups.items():
            self._set_joint_targets(js, vs, frac)
        self._advance()

    def changeAngles(self, names: Any, changes: Any, fractionMaxSpeed: Any) -> None:
        """Move joints by ``changes`` (rad) from their commanded angles; non-blocking."""
        joints = rules.expand_names(names)
        deltas = rules.per_joint(changes, len(joints), "changes")
        now = self.getAngles(joints, False)
        self.setAngles(joints, [a + d for a, d in zip(now, deltas, strict=True)], fractionMaxSpeed)

    def angleInterpolationWithSpeed(
        self, names: Any, targetAngles: Any, maxSpeedFraction: Any
    ) -> None:
        """Move joints to angles (rad, clamped) at a fraction of max speed; blocking."""
        self._check_open()
        caller = "angleInterpolationWithSpeed"
        joints = rules.expand_names(names)
        values = rules.per_joint(targetAngles, len(joints), caller)
        frac = rules.fraction(maxSpeedFraction, f"{caller}: speed fraction")
        self._set_joint_targets(joints, values, frac)
        self._settle_joints(joints)

    def openHand(self, handName: Any) -> None:
        """Open a hand (LHand or RHand); blocking."""
        self.angleInterpolationWithSpeed([rules.hand_name(handName)], [1.0], 0.5)

    def closeHand(self, handName: Any) -> None:
        """Close a hand (LHand or RHand); blocking."""
        self.angleInterpolationWithSpeed([rules.hand_name(handName)], [0.0], 0.5)

    def getAngles(self, names: Any, useSensors: Any) -> list[float]:
        """Joint angles (rad) in the order of the expanded names; sensors or commands."""
        joints = rules.expand_names(names)
        self._advance()
        return [float(v) for v in self._joint_angles(joints, bool(useSensors))]

    # ------------------------------------------------------------------ Cartesian
    def getPosition(self, name: Any, frame: Any, useSensorValues: Any) -> list[float]:
        """``[x, y, z, wx, wy, wz]`` of an effector in a frame (m, rad; ``wy > 0`` looks down).

        Names: CameraTop, CameraBottom, Head, Torso, LLeg, RLeg; frames FRAME_TORSO 0,
        FRAME_WORLD 1, FRAME_ROBOT 2. From the joints' forward kinematics
        (naoloc.robot.kinematics).
        """
        self._advance()
        t = self._transform(str(name), int(frame), bool(useSensorValues))
        return kinematics.position6d(t)

    def getTransform(self, name: Any, frame: Any, useSensorValues: Any) -> list[float]:
        """The effector's 4x4 transform in a frame, 16 floats row-major (metres)."""
        self._advance()
        t = self._transform(str(name), int(frame), bool(useSensorValues))
        return [float(v) for v in t.reshape(-1)]

    # ------------------------------------------------------------------ reflexes, config
    def setCollisionProtectionEnabled(self, pChainName: Any, pEnable: Any) -> bool:
        """Self-collision protection of "LArm", "RArm" or "Arms"; True when set."""
        chain = _chain(pChainName, "setCollisionProtectionEnabled")
        for arm in ("LArm", "RArm") if chain == "Arms" else (chain,):
            if arm not in self._collision:
                return False
            self._collision[arm] = bool(pEnable)
        return True

    def getCollisionProtectionEnabled(self, pChainName: Any) -> bool:
        """Self-collision protection flag of an arm."""
        chain = _chain(pChainName, "getCollisionProtectionEnabled")
        if chain == "Arms":
            return all(self._collision.values())
        return self._collision.get(chain, False)

    def setExternalCollisionProtectionEnabled(self, pName: Any, pEnable: Any) -> None:
        """External-collision protection of "All", "Move", "Arms", "LArm" or "RArm" (stored)."""
        if pName not in self._external:
            raise RobotError(f"name must be one of {', '.join(self._external)}, got {pName!r}")
        for key in self._external if pName == "All" else (pName,):
            self._external[key] = bool(pEnable)

    def getExternalCollisionProtectionEnabled(self, pName: Any) -> bool:
        """External-collision protection flag."""
        if pName not in self._external:
            raise RobotError(f"name must be one of {', '.join(self._external)}, got {pName!r}")
        return self._external[pName]

    def setFallManagerEnabled(self, pEnable: Any) -> None:
        """Fall manager flag (stored; the simulated NAO does not fall)."""
        self._flags["fall"] = bool(pEnable)

    def getFallManagerEnabled(self) -> bool:
        """Fall manager flag."""
        return self._flags["fall"]

    def setSmartStiffnessEnabled(self, pEnable: Any) -> None:
        """Smart stiffness flag (stored)."""
        self._flags["smart"] = bool(pEnable)

    def getSmartStiffnessEnabled(self) -> bool:
        """Smart stiffness flag."""
        return self._flags["smart"]

    def setBreathEnabled(self, pChain: Any, pIsEnabled: Any) -> None:
        """Breathing animation flag of a chain (stored; not animated)."""
        self._breath[_chain(pChain, "setBreathEnabled")] = bool(pIsEnabled)

    def getBreathEnabled(self, pChain: Any) -> bool:
        """Breathing flag of a chain."""
        return self._breath.get(_chain(pChain, "getBreathEnabled"), False)

    def setIdlePostureEnabled(self, pChain: Any, pIsEnabled: Any) -> None:
        """Idle posture flag of a chain (stored)."""
        self._idle[_chain(pChain, "setIdlePostureEnabled")] = bool(pIsEnabled)

    def getIdlePostureEnabled(self, pChain: Any) -> bool:
        """Idle posture flag of a chain."""
        return self._idle.get(_chain(pChain, "getIdlePostureEnabled"), False)

    def setMotionConfig(self, config: Any) -> None:
        """Store ``[[name, value], ...]`` motion options (none changes the simulation)."""
        try:
            pairs = [(str(k), v) for k, v in config]
        except (TypeError, ValueError):
            raise RobotError(f"config must be [[name, value], ...], got {config!r}") from None
        self._motion_config.update(pairs)

    # ------------------------------------------------------------------ body facts
    def getBodyNames(self, name: Any) -> list[str]:
        """Joint names of a joint, chain or group ("Body", "JointActuators", ...)."""
        return rules.expand_names(name)

    def getJointNames(self, name: Any) -> list[str]:
        """As getBodyNames."""
        return rules.expand_names(name)

    def getSensorNames(self) -> list[str]:
        """Names of the joints with position sensors."""
        return list(JOINT_NAMES)
