"""ALMotion served: the simulated robot's own ALMotion with NAOqi's tasks, threads and clock.

ALMotion's call surface and NAOqi's argument rules are the backend's
(:class:`naoloc.backends.simulated.motion.SimulatedMotion`, the same in process and
served): every call this front does not define runs there, on the robot thread. The
front adds what only a served robot has: blocking calls run as tasks other clients can
list and kill (see :mod:`.tasks`), ``move``/``moveToward`` answer at once and walk in the
caller's order, wakeUp/rest/posture changes take a NAO's time on the wall clock, calls
composed over time (angleInterpolation, stiffnessInterpolation), ALMotion/MoveFailed, and
the calls that are accepted but not simulated (logged once): whole-body balance (``wb*``)
and Cartesian control (``positionInterpolations``, ``transformInterpolations``,
``setPositions``, ``setTransforms``): they block for their duration without moving the
body.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from naoloc.backends.naoqi.emulation.context import FrontContext, forwarded
from naoloc.backends.naoqi.emulation.posture import REST_S, WAKE_UP_S, hold_until
from naoloc.backends.naoqi.emulation.tasks import Task
from naoloc.backends.simulated.motion import walk_fractions
from naoloc.constants import JOINT_NAMES
from naoloc.errors import RobotError
from naoloc.robot import rules


class MotionFront:
    """ALMotion of a served robot: the backend's ``motion`` with NAOqi's tasks and clock.

    Args:
        backend: The backend's ALMotion (fake or MuJoCo).
        ctx: The host's context (robot thread, clock speed, tasks, log).
    """

    def __init__(self, backend: Any, ctx: FrontContext) -> None:
        self._b = backend
        self._ctx = ctx
        self._lock = threading.Lock()
        self._walk_gen = 0
        self.on_move_failed: Any = None  # called with NAOqi's MoveFailed value on a failed walk

    def __getattr__(self, name: str) -> Callable[..., Any]:
        """Any other ALMotion call: the backend's, on the robot thread."""
        return forwarded(self._ctx, self._b, name)

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
        self._blocking("openHand", "joints", "openHand", handName)

    def closeHand(self, handName: Any) -> None:
        """Close a hand (LHand or RHand); blocking."""
        self._blocking("closeHand", "joints", "closeHand", handName)

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

        The moveConfig (with the SDK examples' ``Frequency``) scales the speed as
        :func:`naoloc.backends.simulated.motion.walk_fractions` says.
        """
        fractions = walk_fractions(args)  # errors reach the caller before anything is queued
        self._new_walk()
        self._ctx.post(self._b.moveToward, *fractions)

    def _posted_walks(self) -> list[Task]:
        """Walks started with ``post``/``pCall`` that are still running (or about to)."""
        return [t for t in self._ctx.tasks.running("post") if t.name in ("moveTo", "walkTo")]

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the moveTo task ends (also one just posted: ``post.moveTo``)."""
        for task in self._posted_walks():
            task.done.wait()
        self._blocking("waitUntilMoveIsFinished", "wait", "waitUntilMoveIsFinished")

    def moveIsActive(self) -> bool:
        """True while a walk runs (also one just posted)."""
        return bool(self._posted_walks()) or bool(self._run("moveIsActive"))

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

    # ------------------------------------------------------------------ Cartesian
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

    # ------------------------------------------------------------------ summary
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

    # ------------------------------------------------------------------ NAOqi 1.x names
    def walkTo(self, *args: Any) -> bool:
        """Deprecated NAOqi 1.x name of moveTo (old SDK scripts call it)."""
        return self.moveTo(*args)

    def walkInit(self) -> None:
        """Deprecated name of moveInit."""
        self.moveInit()

    def setWalkTargetVelocity(self, x: Any, y: Any, theta: Any, frequency: Any) -> None:
        """Deprecated: moveToward(x, y, theta, [["Frequency", frequency]])."""
        self.moveToward(x, y, theta, [["Frequency", frequency]])

    def waitUntilWalkIsFinished(self) -> None:
        """Deprecated name of waitUntilMoveIsFinished."""
        self.waitUntilMoveIsFinished()

    def walkIsActive(self) -> bool:
        """Deprecated name of moveIsActive."""
        return self.moveIsActive()

    def stopWalk(self) -> bool:
        """Deprecated name of stopMove."""
        return self.stopMove()

    def setWalkArmsEnabled(self, leftArmEnabled: Any, rightArmEnabled: Any) -> None:
        """Deprecated name of setMoveArmsEnabled."""
        self.setMoveArmsEnabled(leftArmEnabled, rightArmEnabled)

    def getWalkArmsEnabled(self) -> list[bool]:
        """Deprecated: ``[left, right]`` arm swing flags."""
        return [self.getMoveArmsEnabled("LArm"), self.getMoveArmsEnabled("RArm")]
