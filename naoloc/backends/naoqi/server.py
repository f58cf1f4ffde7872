"""The virtual NAOqi: a simulated robot served as NAOqi's services, in real time.

:class:`ServedRobot` is the transport-independent core: ``invoke(caller, service,
method, args)`` checks the arguments against :mod:`.signatures`, runs the NAOqi
semantics of :mod:`naoloc.backends.naoqi.emulation` (argument rules, tasks, companion services) and
calls
the robot on its one thread (:class:`~naoloc.backends.naoqi.emulation.loop.RobotLoop`). A
:class:`~naoloc.backends.naoqi.emulation.loop.SimClock` runs the simulation continuously at
``speed``
times real time, so a client that sleeps sees the robot walk.

Dead-man stop, per client: the client that commands a walk (``move``, ``moveToward``,
or a blocking ``moveTo``) owns it. The walk is stopped at once when the owner's
connection closes, when a heartbeating owner (every zmq client; a libqi client
that calls ``NaolocWatchdog.ping``) is silent for more than ``deadman_s`` (0.4 s), and
when the owner of a velocity walk (``move``, ``moveToward``) makes no call for
``command_timeout_s`` (0.4 s) while none of its calls runs: a frozen client (SIGSTOP,
a hung script) leaves no robot walking, as the ROS 2 ``cmd_vel`` timeout. A real NAOqi
has no such timeout (``move`` walks until told otherwise); ``naoloc serve
--command-timeout 0`` serves that behaviour. Other clients' traffic never keeps a
silent owner alive.

When a client leaves, what it held is released: its walk stops, its posted tasks are
stopped, and its camera subscribers are unsubscribed :data:`RELEASE_GRACE_S` later
unless a reconnected client names them first.

Errors: one line ``"<Type>: <Service>.<method>: <problem>"``, never a traceback; a
failure answers that one request and the server goes on.
"""

from __future__ import annotations

import contextlib
import ctypes
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final

from naoloc.backends.naoqi.emulation import companions
from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.loop import ClockHost, RobotLoop, SimClock
from naoloc.backends.naoqi.emulation.motion import MotionFront
from naoloc.backends.naoqi.emulation.posture import PostureFront
from naoloc.backends.naoqi.emulation.video import VideoFront
from naoloc.backends.naoqi.session import Transport, new_session
from naoloc.backends.naoqi.signatures import (
    ANIMATED_SPEECH,
    ANIMATION_PLAYER,
    AWARENESS,
    BATTERY,
    BLOCKING_WALKS,
    ENDS_MOTION,
    FACE_DETECTION,
    LANDMARK_DETECTION,
    LEDS,
    LIFE,
    LOCALIZATION,
    MEMORY,
    MODULE_METHODS,
    MOTION,
    NAVIGATION,
    POSTURE,
    SERVICES,
    SIM,
    SONAR,
    SPEECH_RECOGNITION,
    STARTS_MOTION,
    SYSTEM,
    TOUCH,
    TRACKER,
    TTS,
    URGENT,
    VIDEO,
    VIDEO_RECORDER,
    WATCHDOG,
    select_overload,
)
from naoloc.errors import BackendError, NaolocError, RobotError
from naoloc.robot import Robot, rules

DEADMAN_S: Final = 0.4
COMMAND_TIMEOUT_S: Final = 0.4  # a velocity walk's owner silent this long: stop (frozen)
RELEASE_GRACE_S: Final = 2.0  # a left client's camera subscribers wait this long
_CHECK_EVERY_S: Final = 0.05
RobotThread = RobotLoop  # the robot's thread (kept under its old name for callers)
_WALK_METHODS: Final = frozenset(
    {"moveTo", "move", "moveToward", "waitUntilMoveIsFinished", "walkTo", "setWalkTargetVelocity"}
)
_JOINT_METHODS: Final = frozenset(
    {"angleInterpolation", "angleInterpolationWithSpeed", "openHand", "closeHand"}
)


class _Trim:
    """Hands the heap a client's buffers left behind back to the OS (glibc's
    ``malloc_trim``) after clients leave, at most once a second: freed queues otherwise
    stay in RSS."""

    def __init__(self, every_s: float = 1.0) -> None:
        self._every_s, self._last, self._lock = every_s, 0.0, threading.Lock()
        self.pending = False
        try:
            self._libc: Any = ctypes.CDLL("libc.so.6") if sys.platform.startswith("linux") else None
        except OSError:
            self._libc = None

    def maybe(self) -> None:
        """Trim now if a client left since the last trim, unless trimmed within ``every_s``
        or not on glibc."""
        if self._libc is None or not self.pending or not self._lock.acquire(blocking=False):
            return
        try:
            if time.monotonic() - self._last >= self._every_s:
                self.pending = False
                self._libc.malloc_trim(0)
                self._last = time.monotonic()
        finally:
            self._lock.release()


def _stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _plain(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


class ServedRobot:
    """The served NAOqi: every service, the clock, the tasks and the dead-man.

    Args:
        robot: The simulated robot (fake or MuJoCo backend).
        thread: The robot's thread (the one that created it); None = a new one.
        speed: Simulated seconds per wall second; None = no clock (time advances only
            inside calls, as in-process).
        deadman_s: Silence (s, wall clock) of a heartbeating owner before its walk stops.
        command_timeout_s: Silence (s, wall clock) of any velocity walk's owner with no
            call running before the walk stops; None = never (NAOqi's behaviour).
        log: Where one-line notices go (stderr by default).
        robot_name: What ALSystem.robotName answers.
        cfg: The served config: with it, NaolocLocalization is served (its home map and
            survey are kept in ``record_dir``/home).
        record_dir: Where ALVideoRecorder's files and the home map go (default: a
            ``naoloc-serve`` folder in the system's temporary folder).
    """

    def __init__(
        self,
        robot: Robot,
        *,
        thread: RobotLoop | None = None,
        speed: float | None = 1.0,
        deadman_s: float = DEADMAN_S,
        command_timeout_s: float | None = COMMAND_TIMEOUT_S,
        log: Callable[[str], None] = _stderr,
        robot_name: str = "nao",
        cfg: Any = None,
        record_dir: Path | None = None,
    ) -> None:
        self.robot = robot
        self.deadman_s = deadman_s
        self.command_timeout_s = command_timeout_s
        self._log = log
        self._own_loop = thread is None
        self.loop = thread or RobotLoop()
        self.ctx = FrontContext(run=self._run, submit=self._submit, speed=speed or 1.0, log=log)
        self.clock: SimClock | None = None
        if speed is not None and isinstance(robot.sim, ClockHost):
            clock = SimClock(self.loop, speed, log)
            self.loop.run(clock.attach, robot.sim)
            self.clock = clock
            self.ctx.clocked, self.ctx.cycle_s = True, clock.cycle_s
        ctx = self.ctx
        self.motion = MotionFront(robot.motion, ctx)
        self.video = VideoFront(robot.video, ctx)
        self.posture = PostureFront(robot.posture, ctx)
        self.memory = companions.MemoryFront(ctx, self._joint_angles, self._stiffnesses)
        self.motion.on_move_failed = lambda value: self.memory.raiseEvent(
            "ALMotion/MoveFailed", value
        )
        tts = companions.TextToSpeechFront(ctx, self.memory)
        self.fronts: dict[str, Any] = {
            MOTION: self.motion,
            VIDEO: self.video,
            POSTURE: self.posture,
            MEMORY: self.memory,
            TTS: tts,
            ANIMATED_SPEECH: companions.AnimatedSpeechFront(ctx, tts),
            LEDS: companions.LedsFront(ctx),
            TOUCH: companions.TouchFront(),
            LIFE: companions.AutonomousLifeFront(ctx),
            AWARENESS: companions.BasicAwarenessFront(ctx),
            BATTERY: companions.BatteryFront(),
            SYSTEM: companions.SystemFront(robot_name),
            SPEECH_RECOGNITION: companions.SpeechRecognitionFront(ctx),
        }
        self._stopping = threading.local()  # .now: this thread runs a stop (URGENT)
        self._add_scripted_services(robot, cfg, record_dir)
        self._seen_lock = threading.Lock()
        self._trim = _Trim()
        self._last_seen: dict[str, float] = {}
        self._heartbeating: set[str] = set()
        self._gone: set[str] = set()
        self._busy: dict[str, int] = {}  # caller -> its calls running now
        self._owner: str | None = None
        self._velocity = False  # the owner's walk is a velocity walk (move, moveToward)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.calls = 0
        self.errors = 0
        self.deadman_stops = 0
        # Called with (caller, service, method) before each call runs (``serve --trace``).
        self.trace: Callable[[str, str, str], None] | None = None

    def _add_scripted_services(self, robot: Robot, cfg: Any, record_dir: Path | None) -> None:
        """The services NAO scripts open first (issue 32): sensors, navigation, media,
        vision stand-ins and NaolocLocalization."""
        from naoloc.backends.naoqi.emulation import media, navigation, sensors, vision

        ctx, folder = self.ctx, record_dir or Path(tempfile.gettempdir()) / "naoloc-serve"
        self.fronts[ANIMATION_PLAYER] = media.AnimationPlayerFront(ctx, self.motion)
        self.fronts[VIDEO_RECORDER] = media.VideoRecorderFront(ctx, self.video, folder)
        self.fronts[FACE_DETECTION] = vision.FaceDetectionFront(ctx, self.memory)
        self.fronts[LANDMARK_DETECTION] = vision.LandMarkDetectionFront(ctx, self.memory)
        self.fronts[TRACKER] = vision.TrackerFront(ctx, self.motion)
        inertial = sensors.InertialUnit(
            lambda: self.motion.getPosition("Torso", 1, True), ctx.speed
        )
        self.memory.add_provider(sensors.INERTIAL_KEYS, inertial.read)
        if robot.sim is not None:
            self.fronts[SONAR] = sensors.SonarFront(ctx, robot.sim, self.memory)
            self.fronts[NAVIGATION] = navigation.NavigationFront(ctx, robot.sim, self.motion)
        if cfg is not None:
            from naoloc.backends.naoqi.home import HomeLocalization, LocalizationFront

            home = HomeLocalization(robot, cfg, folder / "home")
            self.fronts[LOCALIZATION] = LocalizationFront(home, self._run)

    # ------------------------------------------------------------------ robot access
    def _run(self, function: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        self.calls += 1
        urgent = bool(getattr(self._stopping, "now", False))  # a stop jumps the queue
        return self.loop.run(
            function, *args, caller=self.ctx.caller or "server", urgent=urgent, **kwargs
        )

    def _submit(self, function: Callable[..., Any], *args: Any) -> None:
        self.calls += 1
        name = getattr(function, "__name__", "call")
        self.loop.submit(
            function,
            *args,
            caller=self.ctx.caller or "server",
            report=lambda err: self._log(f"naoloc serve: {name} failed on the robot: {err}"),
        )

    def _joint_angles(self, names: list[str], use_sensors: bool) -> list[float]:
        return [float(v) for v in self._run(self.robot.motion.getAngles, names, use_sensors)]

    def _stiffnesses(self, names: list[str]) -> list[float]:
        getter = getattr(self.robot.motion, "getStiffnesses", None)
        if getter is None:
            raise RobotError("stiffness cannot be read on this backend")
        return [float(v) for v in self._run(getter, names)]

    # ------------------------------------------------------------------ liveness
    def touch(self, caller: str, *, heartbeat: bool = False) -> None:
        """Record that ``caller`` is alive now (wall clock); ``heartbeat``: it pings."""
        with self._seen_lock:
            self._last_seen[caller] = time.monotonic()
            if heartbeat:
                self._heartbeating.add(caller)
            self._gone.discard(caller)

    def gone(self, caller: str) -> None:
        """``caller``'s connection closed: stop its walk and tasks, orphan its cameras."""
        with self._seen_lock:
            self._gone.add(caller)
            self._last_seen.pop(caller, None)
            self._heartbeating.discard(caller)
            if len(self._gone) > 10_000:  # ids are never reused; keep the newest
                self._gone = {caller, *(o for o in (self._owner,) if o)}
        self.check_deadman()
        self.ctx.left(caller)
        self.ctx.tasks.stop_of(caller)
        self.video.orphan(caller)
        self._trim.pending = True
        self._trim.maybe()

    @property
    def services(self) -> list[str]:
        """Names of the served services."""
        names = [*self.fronts, WATCHDOG]
        if self.robot.sim is not None:
            names.append(SIM)
        return names

    # ------------------------------------------------------------------ calls
    def invoke(self, caller: str, service: str, method: str, args: list[Any]) -> Any:
        """Run ``service.method(*args)`` for ``caller``; the one dispatch of every transport.

        Raises:
            NaolocError: One line ``"<Service>.<method>: <problem>"`` (its type kept).
        """
        self.touch(caller, heartbeat=service == WATCHDOG)
        if self.trace is not None:
            self.trace(caller, service, method)
        with self._seen_lock:
            self._busy[caller] = self._busy.get(caller, 0) + 1
        self._stopping.now = (service, method) in URGENT
        try:
            checked = select_overload(service, method, list(args))
            result = self._dispatch(caller, service, method, checked)
        except NaolocError as err:
            self.errors += 1
            message = rules.error_line(service, method, err).split(": ", 1)[1]
            raise type(err)(message) from None
        except Exception as err:  # a server bug answers this one call and is logged
            self.errors += 1
            line = rules.error_line(service, method, err)
            self._log(f"naoloc serve: {line}")
            raise RobotError(line.split(": ", 1)[1]) from None
        finally:
            self._stopping.now = False
            with self._seen_lock:
                left = self._busy.pop(caller, 1) - 1
                if left:
                    self._busy[caller] = left
            self.touch(caller)
        return _plain(result)

    def _dispatch(self, caller: str, service: str, method: str, args: list[Any]) -> Any:
        if service == WATCHDOG:
            return True
        if service == SIM:
            if self.robot.sim is None:
                raise RobotError(f"{SIM} is not served by this robot")
            self.ctx.caller = caller
            return self._run(getattr(self.robot.sim, method), *args)
        front = self.fronts.get(service)
        if front is None:
            raise RobotError(f"service {service!r} is not served")
        self.ctx.caller = caller
        if method in MODULE_METHODS and not hasattr(front, method):
            return self._module_method(caller, service, method, args)
        function = getattr(front, method, None)
        if function is None:
            raise RobotError(f"{service} has no method {method!r} in this simulator")
        key = (service, method)
        if key in BLOCKING_WALKS or (key in STARTS_MOTION and any(args[:3])):
            self._owner, self._velocity = caller, key in STARTS_MOTION
        elif key in STARTS_MOTION:
            self._owner = None
        try:
            return function(*args)
        finally:
            if (key in BLOCKING_WALKS and self._owner == caller) or key in ENDS_MOTION:
                self._owner = None

    def _module_method(self, caller: str, service: str, method: str, args: list[Any]) -> Any:
        tasks = self.ctx.tasks
        if method == "ping":
            return True
        if method == "version":
            return rules.NAOQI_VERSION
        if method == "getBrokerName":
            return "NAOqi"
        if method == "getMethodList":
            return sorted(SERVICES[service])
        if method == "wait":
            return tasks.wait(args[0], args[1], self.ctx.cancelled)
        if method == "isRunning":
            return tasks.is_running(args[0])
        if method == "stop":
            tasks.stop(args[0])
            return None
        return self._post(caller, service, args)

    def _post(self, caller: str, service: str, args: list[Any]) -> int:
        """``pCall(method, *args)``: run a call in the background; returns its task id."""
        method, rest = args[0], list(args[1:])
        if not isinstance(method, str) or method in MODULE_METHODS:
            raise RobotError(f"pCall needs the name of a {service} method, got {method!r}")
        checked = select_overload(service, method, rest)
        stop: Callable[[], None] | None = None
        if service == MOTION and method in _WALK_METHODS:
            stop = lambda: self.invoke("server", MOTION, "stopMove", [])  # noqa: E731
        elif service == MOTION and method in _JOINT_METHODS:
            stop = lambda: self.invoke("server", MOTION, "killAll", [])  # noqa: E731
        task = self.ctx.tasks.start(method, "post", stop, caller)

        def body() -> None:
            try:
                self.invoke(caller, service, method, checked)
            except NaolocError as err:
                self._log(f"naoloc serve: posted {err}")
            finally:
                self.ctx.tasks.end(task)

        threading.Thread(target=body, name=f"naoloc-post-{task.id}", daemon=True).start()
        return task.id

    # ------------------------------------------------------------------ dead-man
    def check_deadman(self) -> bool:
        """Stop the walk if its owner is gone or silent too long; True when it did."""
        owner = self._owner
        if owner is None:
            return False
        with self._seen_lock:
            gone = owner in self._gone
            silent = time.monotonic() - self._last_seen.get(owner, 0.0)
            beating = owner in self._heartbeating
            busy = self._busy.get(owner, 0) > 0
        timeout = self.command_timeout_s
        frozen = self._velocity and timeout is not None and not busy and silent > timeout
        if not gone and not (beating and silent > self.deadman_s) and not frozen:
            return False
        if self._owner != owner:
            return False
        self._owner = None
        try:
            self.loop.run(self.robot.motion.stopMove, caller="deadman", urgent=True)
        except NaolocError as err:
            self._log(f"naoloc serve: dead-man stop failed: {err}")
            return False
        self.deadman_stops += 1
        why = "disconnected" if gone else f"silent for {silent:.2f} s"
        self._log(f"naoloc serve: client {owner[:12]} {why}: robot stopped (dead-man)")
        return True

    def _run_deadman(self) -> None:
        while not self._stop.wait(_CHECK_EVERY_S):
            self.check_deadman()
            self._trim.maybe()
            try:
                self.video.release_orphans(RELEASE_GRACE_S)
            except NaolocError as err:
                self._log(f"naoloc serve: releasing a left client's camera failed: {err}")

    def start(self) -> None:
        """Start the dead-man thread."""
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._run_deadman, name="naoloc-deadman", daemon=True
            )
            self._thread.start()

    def stop(self) -> None:
        """Stop the dead-man thread, the robot's motion, and the clock. Safe to call twice."""
        self._stop.set()
        for front in self.fronts.values():  # sonar thread, a running recording
            close = getattr(front, "close", None)
            if callable(close):
                try:
                    close()
                except NaolocError as err:
                    self._log(f"naoloc serve: {err}")
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        with contextlib.suppress(NaolocError):
            self.loop.run(self._final_stop, caller="server")
        if self._own_loop:
            self.loop.close()

    def _final_stop(self) -> None:
        self._owner = None
        try:
            self.robot.motion.stopMove()
        except NaolocError as err:
            self._log(f"naoloc serve: could not stop the robot: {err}")
        if self.clock is not None and isinstance(self.robot.sim, ClockHost):
            self.clock.detach(self.robot.sim)
            self.clock = None


class ServiceEndpoint:
    """One served service as a transport sees it: ``invoke(caller, method, args)``.

    Args:
        core: The served robot.
        name: Service name, a key of :data:`~.signatures.SERVICES`.
    """

    def __init__(self, core: ServedRobot, name: str) -> None:
        self._core = core
        self._name = name

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        """Run ``method(*args)`` of this service for ``caller``."""
        return self._core.invoke(caller, self._name, method, args)


WatchdogEndpoint = ServiceEndpoint  # NaolocWatchdog.ping goes through the same core


class VirtualNaoqi:
    """Serve a robot over libqi, zmq or qimessaging until :meth:`close`.

    Args:
        robot: The simulated robot to serve.
        url: Where to listen, e.g. ``tcp://127.0.0.1:9559`` (port 0 = any free port).
        transport: ``libqi``, ``zmq`` or ``qimessaging``.
        curve_keys: zmq only: CURVE certificate folder (required off loopback).
        thread: The robot's thread (the one that created it); None = a new one.
        speed: Simulated seconds per wall second (None = no clock).
        deadman_s: Silence (s, wall clock) after which a heartbeating client's walk stops.
        command_timeout_s: Silence (s) after which any client's velocity walk stops;
            None = never (NAOqi's behaviour).
        log: Where one-line notices go.
        users: qimessaging only: logins ``{user: password}`` (None = no login asked).
        certfile: qimessaging only: PEM certificate (and key) for ``tcps://``.
        keyfile: qimessaging only: PEM key when not inside ``certfile``.
        cfg: The served config (serves NaolocLocalization).
        record_dir: Where recordings and the home map go.
    """

    def __init__(
        self,
        robot: Robot,
        url: str,
        transport: Transport,
        *,
        curve_keys: str | None = None,
        thread: RobotLoop | None = None,
        speed: float | None = 1.0,
        deadman_s: float = DEADMAN_S,
        command_timeout_s: float | None = COMMAND_TIMEOUT_S,
        log: Callable[[str], None] = _stderr,
        users: dict[str, str] | None = None,
        certfile: str | None = None,
        keyfile: str | None = None,
        cfg: Any = None,
        record_dir: Path | None = None,
    ) -> None:
        self.core = ServedRobot(
            robot,
            thread=thread,
            speed=speed,
            deadman_s=deadman_s,
            command_timeout_s=command_timeout_s,
            log=log,
            cfg=cfg,
            record_dir=record_dir,
        )
        self.transport = transport
        self._relay: Any = None
        self._session: Any = None
        names = self.core.services
        try:
            if transport == "libqi":
                from naoloc.backends.naoqi.libqi_transport import LibqiServer

                self._session = LibqiServer(self.core, url, names, log=log)
            elif transport == "qimessaging":
                from naoloc.backends.naoqi.qimessaging.server import QiServer

                self._session = QiServer(users=users, certfile=certfile, keyfile=keyfile)
                self._session.listen(url)
                self._session.set_core(self.core)
                for name in names:
                    self._session.register(name, ServiceEndpoint(self.core, name))
            else:
                self._session = new_session(transport, curve_keys=curve_keys)
                self._session.listenStandalone(url)
                if hasattr(self._session, "set_core"):  # liveness per client
                    self._session.set_core(self.core)
                for name in names:
                    self._session.registerService(name, ServiceEndpoint(self.core, name))
        except NaolocError:
            self._abandon()
            raise
        except Exception as err:  # libqi raises RuntimeError for a bad or busy address
            self._abandon()
            raise BackendError(f"cannot serve on {url}: {str(err).splitlines()[0]}") from None
        self.services = names
        self.core.start()

    def _abandon(self) -> None:
        self.core.stop()
        session, self._session = self._session, None
        if session is not None:
            with contextlib.suppress(Exception):
                session.close()

    @property
    def endpoint(self) -> str:
        """The URL clients connect to (with the real port)."""
        endpoints = [str(e) for e in self._session.endpoints()]
        tcp = [e for e in endpoints if e.startswith("tcp://")]
        return (tcp or endpoints or [""])[0]

    def close(self) -> None:
        """Stop serving and stop the robot's motion. Safe to call twice."""
        self.core.stop()
        session, self._session = self._session, None
        if session is not None:
            session.close()

    def __enter__(self) -> VirtualNaoqi:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
