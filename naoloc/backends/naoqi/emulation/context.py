"""What a service front needs from its host: the robot thread, the clock, tasks, a log.

The virtual NAOqi builds one :class:`FrontContext`; fronts call the backend only through
``run`` (the robot thread, on behalf of the calling client) and wait simulated time
with ``sleep_sim`` (wall time divided by the clock's speed).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from naoloc.backends.naoqi.emulation.tasks import TaskTable


@dataclass
class FrontContext:
    """Shared by the fronts of one served robot.

    Attributes:
        run: ``run(function, *args, **kwargs)`` on the robot thread for the current client.
        speed: Simulated seconds per wall second.
        clocked: True when a real-time clock drives the robot (blocking walks then wait
            off the robot thread).
        cycle_s: The robot's control cycle (s, simulated).
        log: One-line notices (stderr of ``naoloc serve``).
        tasks: The task table shared by every service.
        caller: The client of the current call (per thread).
        submit: ``submit(function, *args)`` queues a call on the robot thread for the
            current client and returns at once (None = run it and wait).
    """

    run: Callable[..., Any]
    submit: Callable[..., None] | None = None
    speed: float = 1.0
    clocked: bool = False
    cycle_s: float = 0.02
    log: Callable[[str], None] = print
    tasks: TaskTable = field(default_factory=TaskTable)
    _local: threading.local = field(default_factory=threading.local)
    _said: set[str] = field(default_factory=set)

    @property
    def caller(self) -> str:
        """The client of the call running on this thread ("" outside calls)."""
        return str(getattr(self._local, "caller", ""))

    @caller.setter
    def caller(self, value: str) -> None:
        self._local.caller = value

    def post(self, function: Callable[..., Any], *args: Any) -> None:
        """Run ``function(*args)`` on the robot thread without waiting for it (NAOqi's
        non-blocking calls); the calling client's order of calls is kept."""
        if self.submit is None:
            self.run(function, *args)
        else:
            self.submit(function, *args)

    def sleep_sim(self, seconds: float, stop: threading.Event | None = None) -> bool:
        """Wait ``seconds`` of simulated time; False when ``stop`` was set first."""
        wall = max(0.0, seconds) / self.speed
        if stop is None:
            threading.Event().wait(wall)
            return True
        return not stop.wait(wall)

    def not_simulated(self, what: str) -> None:
        """Log once per ``what`` that it is accepted but not simulated."""
        if what not in self._said:
            self._said.add(what)
            self.log(f"naoloc serve: {what} is not simulated; the call is accepted and ignored")


def forwarded(ctx: FrontContext, backend: Any, name: str) -> Callable[..., Any]:
    """``backend.<name>`` as a call that runs on the robot thread (a front's fallback).

    Raises:
        AttributeError: ``name`` is private, or not a callable of ``backend``.
    """
    if name.startswith("_"):
        raise AttributeError(name)
    target = getattr(backend, name)
    if not callable(target):
        raise AttributeError(name)

    def call(*args: Any) -> Any:
        return ctx.run(target, *args)

    call.__name__ = name
    return call
