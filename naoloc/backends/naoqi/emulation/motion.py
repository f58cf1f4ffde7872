"""ALMotion in front of a simulated backend: NAOqi's arguments, errors, tasks and coverage.

The backend (``robot.motion`` of the fake or MuJoCo robot) supplies walking, joints,
stiffness and odometry; this front checks every argument with :mod:`.rules`, expands
names, runs blocking calls as tasks (see :mod:`.tasks`), and adds the methods that are
pure bookkeeping (flags, configs, summaries) or composed of backend calls
(angleInterpolation, stiffnessInterpolation, openHand...). Not simulated, accepted and
logged once: whole-body balance (``wb*``) and Cartesian control
(``positionInterpolations``, ``transformInterpolations``, ``setPositions``,
``setTransforms``): they block for their duration without moving the body.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.posture import REST_S, WAKE_UP_S, hold_until
from naoloc.backends.naoqi.emulation.tasks import Task
from naoloc.constants import JOINT_NAMES
from naoloc.errors import RobotError
from naoloc.robot import rules

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


def _chain(name: Any, what: str) -> str:
    if name not in _CHAINS_WITH_FLAGS:
        raise RobotError(
            f"{what}: unknown chain name {name!r}; valid: {', '.join(_CHAINS_WITH_FLAGS)}"
        )
    return str(name)


class MotionFront:
    """ALMotion with NAOqi's rules in front of a backend's ``motion``.

    Args:
        backend: The backend's ALMotion (fake or MuJoCo).
        ctx: The host's context (robot thread, clock speed, tasks, log).
    """

    def __init__(self, backend: Any, ctx: FrontContext) -> None:
        self._b = backend
        self._ctx = ctx
        self._lock = threading.Lock()
        self._walk_gen = 0
        self._move_arms = {"LArm": True, "RArm": True}
        self._collision = {"LArm": True, "RArm": True}
        self._external = {"All": True, "Move": True, "Arms": True, "LArm": True, "RArm": True}
        self._flags: dict[str, bool] = {"fall": True, "smart": True}
        self._breath: dict[str, bool] = {}
        self._idle: dict[str, bool] = {}
        self._motion_config: dict[str, Any] = {}
        self.on_move_failed: Any = None  # called with NAOqi's MoveFailed value on a failed walk

    # ------------------------------------------------------------------ helpers
    def _run(self, method: str, *args: Any) -> Any:
        return self._ctx.run(getattr(self._b, method), *args)

    def _new_walk(self) -> int:
        with self._lock:
            self._walk_gen += 1
            return self._walk_gen

    def _blocking(self, name: str, resources: str, method: str, *args: Any) -> tuple[Any, Task]:
        task = self._ctx.tasks.start(name, resources, self._stopper(resources), self._ctx.caller)
        try:
            return self._run(method, *args), task
        finally:
            self._ctx.tasks.end(task)

    def _stopper(self, resources: str) -> Any:
        if resources == "walk":
            return lambda: self._run("stopMove")
        if resources == "joints":
            return self._freeze_joints
        return None

    def _freeze_joints(self) -> None:
        angles = self._run("getAngles", list(JOINT_NAMES), False)
        self._run("setAngles", list(JOINT_NAMES), angles, 1.0)

    # ------------------------------------------------------------------ stiffness
    def _timed(self, name: str, seconds: float) -> None:
        """Run the backend's ``name`` as a posture task held for a NAO's ``seconds``."""
        task = self._ctx.tasks.start(name, "posture", self._stopper("walk"), self._ctx.caller)
        try:
            started = time.monotonic()
            self._run(name)
            hold_until(self._ctx, started, seconds, task.stopped)
        finally:
            self._ctx.tasks.end(task)

    def wakeUp(self) -> None:
        """Motors on, walk-ready posture; blocking (a NAO's 2.5 s from rest, else at once)."""
        awake = bool(self._run("robotIsWakeUp"))
        self._timed("wakeUp", 0.0 if awake else WAKE_UP_S)

    def rest(self) -> None:
        """Stop, crouch, motors off; blocking (a NAO's 3 s when awake, else at once)."""
        self._new_walk()
        awake = bool(self._run("robotIsWakeUp"))
        self._timed("rest", REST_S if awake else 0.0)

    def robotIsWakeUp(self) -> bool:
        """True when the leg joints are stiff."""
        return bool(self._run("robotIsWakeUp"))

    def setStiffnesses(self, names: Any, stiffnesses: Any) -> None:
        """Stiffness in [0, 1] (clipped) of joints, chains or groups; non-blocking."""
        joints = rules.expand_names(names)
        values = rules.per_joint(stiffnesses, len(joints), "stiffnesses")
        self._run("setStiffnesses", joints, [min(1.0, max(0.0, v)) for v in values])

    def getStiffnesses(self, jointName: Any) -> list[float]:
        """Stiffness in [0, 1] of each expanded joint."""
        joints = rules.expand_names(jointName)
        if not hasattr(self._b, "getStiffnesses"):
            raise RobotError("getStiffnesses is not available on this backend")
        return [float(v) for v in self._run("getStiffnesses", joints)]

    def stiffnessInterpolation(self, names: Any, stiffnessLists: Any, timeLists: Any) -> None:
        """Set stiffness at key times (s); blocking for the last time."""
        joints = rules.expand_names(names)
        keys = rules.keyframes(joints, stiffnessLists, timeLists, "stiffnessInterpolation")
        task = self._ctx.tasks.start("stiffnessInterpolation", "stiffness", None, self._ctx.caller)
        try:
            events = sorted({t for k in keys for t, _ in k})
            now = 0.0
            for t in events:
                if not self._ctx.sleep_sim(t - now, task.stopped):
                    return
                now = t
                pairs = [
                    (j, v) for j, k in zip(joints, keys, strict=True) for kt, v in k if kt == t
                ]
                self._run(
                    "setStiffnesses",
                    [j for j, _ in pairs],
                    [min(1.0, max(0.0, v)) for _, v in pairs],
                )
        finally:
            self._ctx.tasks.end(task)

    # ------------------------------------------------------------------ joints
    def setAngles(self, names: Any, angles: Any, fractionMaxSpeed: Any) -> None:
        """Move joints toward angles (rad) at a speed fraction (one, or one per joint)."""
        joints = rules.expand_names(names)
        values = rules.per_joint(angles, len(joints), "angles")
        if isinstance(fractionMaxSpeed, list | tuple):
            fractions = [
                rules.fraction(f)
                for f in rules.per_joint(fractionMaxSpeed, len(joints), "speed fractions")
            ]
        else:
            fractions = [rules.fraction(fractionMaxSpeed)] * len(joints)
        groups: dict[float, tuple[list[str], list[float]]] = {}
        for joint, value, frac in zip(joints, values, fractions, strict=True):
            group = groups.setdefault(frac, ([], []))
            group[0].append(joint)
            group[1].append(value)
        for frac, (js, vs) in groups.items():
            self._run("setAngles", js, vs, frac)

    def changeAngles(self, names: Any, changes: Any, fractionMaxSpeed: Any) -> None:
        """Move joints by ``changes`` (rad) from their commanded angles; non-blocking."""
        joints = rules.expand_names(names)
        deltas = rules.per_joint(changes, len(joints), "changes")
        now = self._run("getAngles", joints, False)
        self.setAngles(joints, [a + d for a, d in zip(now, deltas, strict=True)], fractionMaxSpeed)

    def getAngles(self, names: Any, useSensors: Any) -> list[float]:
        """Joint angles (rad) in the order of the expanded names."""
        joints = rules.expand_names(names)
        return [float(v) for v in self._run("getAngles", joints, bool(useSensors))]

    def angleInterpolationWithSpeed(
        self, names: Any, targetAngles: Any, maxSpeedFraction: Any
    ) -> None:
        """Move joints to angles (rad) at a speed fraction; blocking."""
        joints = rules.expand_names(names)
        values = rules.per_joint(targetAngles, len(joints), "target angles")
        frac = rules.fraction(maxSpeedFraction)
        self._blocking(
            "angleInterpolationWithSpeed",
            "joints",
            "angleInterpolationWithSpeed",
            joints,
            values,
            frac,
        )

    def angleInterpolation(
        self, names: Any, angleLists: Any, timeLists: Any, isAbsolute: Any
    ) -> None:
        """Go through key angles (rad) at key times (s from now); blocking.

        Each segment is run at the speed that reaches its key at its time (NAOqi uses
        Bezier curves; the simulated path is piecewise linear). ``isAbsolute`` False:
        angles are relative to the commanded angles at the call.
        """
        joints = rules.expand_names(names)
        keys = rules.keyframes(joints, angleLists, timeLists, "angleInterpolation")
        start = self._run("getAngles", joints, False)
        if not bool(isAbsolute):
            keys = [[(t, s + v) for t, v in k] for k, s in zip(keys, start, strict=True)]
        task = self._ctx.tasks.start(
            "angleInterpolation", "joints", self._freeze_joints, self._ctx.caller
        )
        try:
            cursor = [0] * len(joints)
            last = list(start)
            last_t = [0.0] * len(joints)
            now = 0.0
            while True:
                commands: dict[float, tuple[list[str], list[float]]] = {}
                for i, joint in enumerate(joints):
                    if cursor[i] >= len(keys[i]):
                        continue
                    t, a = keys[i][cursor[i]]
                    speed = abs(a - last[i]) / max(1e-3, t - last_t[i])
                    frac = min(1.0, max(1e-3, speed / rules.JOINT_MAX_SPEED[joint]))
                    group = commands.setdefault(frac, ([], []))
                    group[0].append(joint)
                    group[1].append(a)
                if not commands:
                    break
                for frac, (js, vs) in commands.items():
                    self._run("setAngles", js, vs, frac)
                upcoming = min(
                    keys[i][cursor[i]][0] for i in range(len(joints)) if cursor[i] < len(keys[i])
                )
                if not self._ctx.sleep_sim(upcoming - now, task.stopped):
                    return
                now = upcoming
                for i in range(len(joints)):
                    if cursor[i] < len(keys[i]) and keys[i][cursor[i]][0] <= now + 1e-9:
                        last_t[i], last[i] = keys[i][cursor[i]]
                        cursor[i] += 1
        finally:
            self._ctx.tasks.end(task)

    def openHand(self, handName: Any) -> None:
        """Open a hand (LHand or RHand); blocking."""
        hand = rules.hand_name(handName)
        self._blocking("openHand", "joints", "angleInterpolationWithSpeed", [hand], [1.0], 0.5)

    def closeHand(self, handName: Any) -> None:
        """Close a hand (LHand or RHand); blocking."""
        hand = rules.hand_name(handName)
        self._blocking("closeHand", "joints", "angleInterpolationWithSpeed", [hand], [0.0], 0.5)

    # ------------------------------------------------------------------ walking
    def moveInit(self) -> None:
        """Walk-ready posture; blocking."""
        self._blocking("moveInit", "posture", "moveInit")

    def moveTo(self, *args: Any) -> bool:
        """Walk to a pose (FRAME_ROBOT) or through control points; blocking.

        Returns:
            True when reached; False when the robot is not awake, hit something, or the
            walk was stopped or replaced (stopMove, killMove, move, a new moveTo, rest).
        """
        points, config = rules.move_to_points(args)
        gen = self._new_walk()
        bargs: tuple[Any, ...] = (
            (points, [[k, v] for k, v in config.items()]) if config else (points,)
        )
        result, task = self._blocking("moveTo", "walk", "moveTo", *bargs)
        with self._lock:
            replaced = gen != self._walk_gen
        if not result and not replaced and not task.stopped.is_set() and self.on_move_failed:
            # NAOqi raises ALMotion/MoveFailed: [cause, status, [x, y, theta] where it stopped]
            where = self._run("getRobotPosition", False)
            self.on_move_failed(["Internal stop", 1, [float(v) for v in where]])
        return bool(result) and not replaced and not task.stopped.is_set()

    def _walk_on_the_clock(self, bargs: tuple[Any, ...]) -> tuple[Any, Task]:
        """Start the walk, then wait on this thread while the clock walks it.

        The robot thread stays free, so other clients' calls (and their blocking calls)
        run while this moveTo waits, as on NAOqi.
        """
        task = self._ctx.tasks.start("moveTo", "walk", self._stopper("walk"), self._ctx.caller)
        try:
            future = self._ctx.run(self._b.moveTo, *bargs, _async=True)
            while not self._ctx.run(future.isFinished):
                self._ctx.sleep_sim(self._ctx.cycle_s)
            return self._ctx.run(future.value), task
        finally:
            self._ctx.tasks.end(task)

    def move(self, *args: Any) -> None:
        """Walk at a velocity (m/s, m/s, rad/s; FRAME_ROBOT) until changed; non-blocking.

        Returns at once, as NAOqi does: the walk starts on the robot thread after the
        answer, in the order of the caller's calls. The moveConfig of ``move(x, y,
        theta, moveConfig)`` is checked, then not used.
        """
        values, _ = rules.velocity(args, False, "move")
        self._new_walk()
        self._ctx.post(self._b.move, *values)

    def moveToward(self, *args: Any) -> None:
        """Walk at a normalised velocity (each in [-1, 1]); non-blocking, returns at once.

        moveConfig takes NAOqi's walk parameters and the SDK examples' ``Frequency``
        (legacy name of ``MaxStepFrequency``, in [0, 1]). The step frequency scales the
        speed: the simulated walk keeps its step period, so a fraction ``f`` walks at
        ``STEP_PERIOD_FAST_S / step period`` of full speed, the step period going from
        ``STEP_PERIOD_SLOW_S`` (f = 0) to ``STEP_PERIOD_FAST_S`` (f = 1). The other
        parameters are checked, then not used.
        """
        args, frequency = _legacy_frequency(args)
        values, config = rules.velocity(args, True, "moveToward")
        frequency = config.get("MaxStepFrequency", frequency)
        period = STEP_PERIOD_SLOW_S + (STEP_PERIOD_FAST_S - STEP_PERIOD_SLOW_S) * frequency
        scale = STEP_PERIOD_FAST_S / period
        self._new_walk()
        self._ctx.post(self._b.moveToward, *(v * scale for v in values))

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the moveTo task ends."""
        self._blocking("waitUntilMoveIsFinished", "wait", "waitUntilMoveIsFinished")

    def moveIsActive(self) -> bool:
        """True while a walk runs."""
        return bool(self._run("moveIsActive"))

    def stopMove(self) -> bool:
        """End the walk now (a blocking moveTo returns False); True."""
        self._new_walk()
        self._run("stopMove")
        return True

    def killMove(self) -> None:
        """End the walk at once (as stopMove in the simulator)."""
        self._new_walk()
        self._run("stopMove")

    def killAll(self) -> None:
        """Stop every motion task: walks, joint interpolations and posture changes."""
        self._new_walk()
        self._run("stopMove")
        self._ctx.tasks.stop_all("joints")
        self._ctx.tasks.stop_all("posture")

    def killTask(self, motionTaskID: Any) -> bool:
        """Stop one task by id; True when it was running."""
        return self._ctx.tasks.stop(motionTaskID)

    def getTaskList(self) -> list[list[Any]]:
        """``[[name, id, groupId, priority, isRunning, isBlocking], ...]`` of running tasks."""
        return [[t.name, t.id, 0, 0, True, True] for t in self._ctx.tasks.running()]

    def areResourcesAvailable(self, resourceNames: Any) -> bool:
        """True when no running task uses the named joints."""
        rules.expand_names(resourceNames)
        return not self._ctx.tasks.running("joints")

    def getRobotPosition(self, useSensors: Any) -> list[float]:
        """``[x, y, theta]`` in FRAME_WORLD (odometry)."""
        return [float(v) for v in self._run("getRobotPosition", bool(useSensors))]

    def getNextRobotPosition(self) -> list[float]:
        """Where the current move ends, FRAME_WORLD."""
        return [float(v) for v in self._run("getNextRobotPosition")]

    def getRobotVelocity(self) -> list[float]:
        """``[vx, vy, wz]`` in FRAME_ROBOT."""
        return [float(v) for v in self._run("getRobotVelocity")]

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

    # ------------------------------------------------------------------ Cartesian
    def getPosition(self, name: Any, frame: Any, useSensorValues: Any) -> list[float]:
        """6D position ``[x, y, z, wx, wy, wz]`` of a chain, sensor or joint in a frame."""
        if not hasattr(self._b, "getPosition"):
            raise RobotError("getPosition is not available on this backend yet")
        return [float(v) for v in self._run("getPosition", name, frame, bool(useSensorValues))]

    def getTransform(self, name: Any, frame: Any, useSensorValues: Any) -> list[float]:
        """4x4 transform (row-major, 16 floats) of a chain, sensor or joint in a frame."""
        if not hasattr(self._b, "getTransform"):
            raise RobotError("getTransform is not available on this backend yet")
        return [float(v) for v in self._run("getTransform", name, frame, bool(useSensorValues))]

    def _cartesian(self, method: str, times: Any) -> None:
        self._ctx.not_simulated(f"ALMotion.{method} (Cartesian control)")
        flat: list[float] = []
        stack = [times]
        while stack:
            item = stack.pop()
            if isinstance(item, int | float) and not isinstance(item, bool):
                flat.append(rules.finite(item, f"{method} time"))
            elif isinstance(item, list | tuple):
                stack.extend(item)
        task = self._ctx.tasks.start(method, "joints", None, self._ctx.caller)
        try:
            self._ctx.sleep_sim(max(flat, default=0.0), task.stopped)
        finally:
            self._ctx.tasks.end(task)

    def transformInterpolations(
        self, effectorNames: Any, frames: Any, paths: Any, axisMasks: Any, relativeTimes: Any
    ) -> None:
        """Not simulated: blocks for the last time; the body does not move."""
        self._cartesian("transformInterpolations", relativeTimes)

    def positionInterpolations(
        self, effectorNames: Any, frames: Any, paths: Any, axisMasks: Any, relativeTimes: Any
    ) -> None:
        """Not simulated: blocks for the last time; the body does not move."""
        self._cartesian("positionInterpolations", relativeTimes)

    def setTransforms(self, *args: Any) -> None:
        """Not simulated: accepted and ignored."""
        self._ctx.not_simulated("ALMotion.setTransforms (Cartesian control)")

    def setPositions(self, *args: Any) -> None:
        """Not simulated: accepted and ignored."""
        self._ctx.not_simulated("ALMotion.setPositions (Cartesian control)")

    # ------------------------------------------------------------------ whole body
    def wbEnable(self, isEnabled: Any) -> None:
        """Not simulated (no whole-body balancer); accepted."""
        self._ctx.not_simulated("ALMotion.wbEnable (whole-body balance)")

    def wbFootState(self, stateName: Any, supportLeg: Any) -> None:
        """Not simulated; accepted."""
        self._ctx.not_simulated("ALMotion.wbFootState (whole-body balance)")

    def wbEnableBalanceConstraint(self, isEnable: Any, supportLeg: Any) -> None:
        """Not simulated; accepted."""
        self._ctx.not_simulated("ALMotion.wbEnableBalanceConstraint (whole-body balance)")

    def wbGoToBalance(self, supportLeg: Any, duration: Any) -> None:
        """Not simulated; blocks for ``duration`` s."""
        self._ctx.not_simulated("ALMotion.wbGoToBalance (whole-body balance)")
        self._ctx.sleep_sim(rules.finite(duration, "duration"))

    def wbEnableEffectorControl(self, effectorName: Any, isEnabled: Any) -> None:
        """Not simulated; accepted."""
        self._ctx.not_simulated("ALMotion.wbEnableEffectorControl (whole-body balance)")

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
        if pName == "All":
            for key in self._external:
                self._external[key] = bool(pEnable)
        else:
            self._external[pName] = bool(pEnable)

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

    def getSummary(self) -> str:
        """A text summary: joint angles and stiffness, running tasks."""
        angles = self._run("getAngles", list(JOINT_NAMES), True)
        try:
            stiff = self._run("getStiffnesses", list(JOINT_NAMES))
        except (AttributeError, RobotError):
            stiff = [float("nan")] * len(JOINT_NAMES)
        lines = [
            "---------------------- Model ----------------------",
            "  Name            Angle(rad)  Stiffness",
        ]
        for name, a, s in zip(JOINT_NAMES, angles, stiff, strict=True):
            lines.append(f"  {name:<15} {a:+10.4f}  {s:9.2f}")
        lines.append("---------------------- Tasks ----------------------")
        tasks = self._ctx.tasks.running()
        lines += [f"  {t.name} (id {t.id})" for t in tasks] or ["  none"]
        return "\n".join(lines)
