"""The virtual NAOqi: a Robot served as ALMotion, ALVideoDevice and ALRobotPosture.

Calls from every client and service go through one lock, because the simulated
backends are not thread-safe and advance simulated time only inside service calls.
Ground truth and teleport are served under the separate name ``NaolocSim``; clients
keep the connection (and the dead-man) alive by calling ``NaolocWatchdog.ping``.

Dead-man stop: a thread checks every 50 ms of wall time whether the client that
started a lasting motion (``move``/``moveToward``) has been silent for more than
``deadman_s`` (0.5 s); then it stops the robot. On libqi the server cannot tell
clients apart, so there the last call from any client counts.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Final

from naoloc.backends.naoqi.session import Transport, new_session
from naoloc.backends.naoqi.signatures import (
    ENDS_MOTION,
    ROBOT_ATTRIBUTE,
    SERVICES,
    SIM,
    STARTS_MOTION,
    WATCHDOG,
    select_overload,
)

from naoloc.errors import BackendError, NaolocError, RobotError
from naoloc.robot import Robot

DEADMAN_S: Final = 0.5
_CHECK_EVERY_S: Final = 0.05


def _stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


class RobotThread:
    """One thread that runs every call to a robot, its creation and its closing included.

    Simulated backends are not thread-safe and MuJoCo's OpenGL context belongs to the
    thread that made it, while libqi calls services from a pool of threads.
    """

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="naoloc-robot")

    def run(self, function: Callable[..., Any], *args: Any) -> Any:
        """Run ``function(*args)`` on the robot thread; return its result or raise its error."""
        return self._pool.submit(function, *args).result()

    def close(self) -> None:
        """Finish queued calls and end the thread."""
        self._pool.shutdown(wait=True)


class ServedRobot:
    """Serializes calls to a robot and stops it when its driving client goes silent.

    Args:
        robot: The robot to serve (fake or MuJoCo backend).
        thread: The thread that runs every robot call (the one that created the robot);
            None = a new one.
        deadman_s: Wall-clock silence (s) after which a lasting motion is stopped.
        log: Where one-line notices go (stderr by default).
    """

    def __init__(
        self,
        robot: Robot,
        *,
        thread: RobotThread | None = None,
        deadman_s: float = DEADMAN_S,
        log: Callable[[str], None] = _stderr,
    ) -> None:
        self.robot = robot
        self.deadman_s = deadman_s
        self._log = log
        self._own_thread = thread is None
        self._robot_thread = thread or RobotThread()
        self._seen_lock = threading.Lock()
        self._last_seen: dict[str, float] = {}
        self._owner: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.calls = 0
        self.deadman_stops = 0

    def touch(self, caller: str) -> None:
        """Record that ``caller`` is alive now (wall clock)."""
        with self._seen_lock:
            self._last_seen[caller] = time.monotonic()

    def invoke(self, caller: str, service: str, method: str, args: list[Any]) -> Any:
        """Call ``robot.<service>.<method>(*args)`` on the robot thread.

        Raises:
            RobotError: Unknown service or method (or what the robot raises).
        """
        attribute = ROBOT_ATTRIBUTE.get(service)
        target = getattr(self.robot, attribute, None) if attribute else None
        if target is None:
            raise RobotError(f"service {service!r} is not served")
        function = getattr(target, method, None)
        if function is None or method.startswith("_"):
            raise RobotError(f"{service} has no method {method!r}")
        self.touch(caller)
        result = self._robot_thread.run(self._call, caller, (service, method), function, args)
        self.touch(caller)
        return result

    def _call(
        self, caller: str, key: tuple[str, str], function: Callable[..., Any], args: list[Any]
    ) -> Any:
        self.calls += 1
        result = function(*args)
        if key in STARTS_MOTION:
            moving = any(float(a) != 0.0 for a in args)
            self._owner = caller if moving else None
        elif key in ENDS_MOTION:
            self._owner = None
        return result

    def check_deadman(self) -> bool:
        """Stop the robot if its driving client is silent too long; True when it did."""
        owner = self._owner
        if owner is None:
            return False
        with self._seen_lock:
            silent = time.monotonic() - self._last_seen.get(owner, 0.0)
        if silent <= self.deadman_s:
            return False
        stopped: bool = self._robot_thread.run(self._deadman_stop, owner)
        if stopped:
            self.deadman_stops += 1
            self._log(f"naoloc serve: client silent for {silent:.2f} s: robot stopped (dead-man)")
        return stopped

    def _deadman_stop(self, owner: str) -> bool:
        if self._owner != owner:
            return False
        self._owner = None
        try:
            self.robot.motion.stopMove()
        except NaolocError as err:
            self._log(f"naoloc serve: dead-man stop failed: {err}")
            return False
        return True

    def _run_deadman(self) -> None:
        while not self._stop.wait(_CHECK_EVERY_S):
            self.check_deadman()

    def start(self) -> None:
        """Start the dead-man thread."""
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._run_deadman, name="naoloc-deadman", daemon=True
            )
            self._thread.start()

    def stop(self) -> None:
        """Stop the dead-man thread and the robot's motion (best effort)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self._robot_thread.run(self._final_stop)
        if self._own_thread:
            self._robot_thread.close()

    def _final_stop(self) -> None:
        self._owner = None
        try:
            self.robot.motion.stopMove()
        except NaolocError as err:
            self._log(f"naoloc serve: could not stop the robot: {err}")


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


class ServiceEndpoint:
    """One served NAOqi service: checks arguments, then calls the robot.

    Args:
        core: The serialized robot.
        name: Service name, a key of :data:`~.signatures.SERVICES`.
    """

    def __init__(self, core: ServedRobot, name: str) -> None:
        self._core = core
        self._name = name

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        """Run ``method(*args)`` of this service for ``caller``."""
        checked = select_overload(self._name, method, list(args))
        return _plain(self._core.invoke(caller, self._name, method, checked))


class WatchdogEndpoint:
    """``NaolocWatchdog.ping()``: keeps the caller's dead-man alive; never touches the robot."""

    def __init__(self, core: ServedRobot) -> None:
        self._core = core

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        """Only ``ping()`` exists; returns True."""
        select_overload(WATCHDOG, method, list(args))
        self._core.touch(caller)
        return True


class VirtualNaoqi:
    """Serve a robot over libqi or zmq until :meth:`close`.

    Args:
        robot: The simulated robot to serve.
        url: Where to listen, e.g. ``tcp://127.0.0.1:9559`` (port 0 = any free port).
        transport: ``libqi`` or ``zmq``.
        curve_keys: zmq only: CURVE certificate folder (required off loopback).
        thread: The robot's thread (:class:`RobotThread`, the one that created it);
            None = a new one.
        deadman_s: Silence (s, wall clock) after which a lasting motion is stopped.
        log: Where one-line notices go.
    """

    def __init__(
        self,
        robot: Robot,
        url: str,
        transport: Transport,
        *,
        curve_keys: str | None = None,
        thread: RobotThread | None = None,
        deadman_s: float = DEADMAN_S,
        log: Callable[[str], None] = _stderr,
    ) -> None:
        self.core = ServedRobot(robot, thread=thread, deadman_s=deadman_s, log=log)
        self.transport = transport
        self._session: Any = new_session(transport, curve_keys=curve_keys)
        names = [n for n in SERVICES if n != SIM or robot.sim is not None]
        try:
            self._session.listenStandalone(url)
            for name in names:
                endpoint: Any = (
                    WatchdogEndpoint(self.core)
                    if name == WATCHDOG
                    else ServiceEndpoint(self.core, name)
                )
                if transport == "libqi":
                    from naoloc.backends.naoqi.libqi_transport import bind_service

                    endpoint = bind_service(name, endpoint)
                self._session.registerService(name, endpoint)
        except NaolocError:
            self._session.close()
            self.core.stop()
            raise
        except Exception as err:  # libqi raises RuntimeError for a bad or busy address
            self._session.close()
            self.core.stop()
            raise BackendError(f"cannot serve on {url}: {str(err).splitlines()[0]}") from None
        self.services = names
        self.core.start()

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
