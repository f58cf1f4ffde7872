"""The robot thread and the server's clock.

Every call to a simulated robot runs on one thread (:class:`RobotLoop`): the backends
are not thread-safe and MuJoCo's OpenGL context belongs to the thread that made it.
Callers queue jobs per caller and are served round-robin, so a client flooding the
server with calls delays the others by at most one call each.

:class:`SimClock` runs the simulation continuously at ``speed`` times real time. A
backend with a clock attached routes its time advance (one ALMotion cycle after a plain
call, many inside a blocking call) through :meth:`SimClock.advance`: a plain call no
longer advances time by itself, and a blocking call waits for the wall clock, one cycle
at a time, while the loop serves other clients' calls (so a second client's
``stopMove`` ends a blocking ``moveTo`` at once). Without a clock the backends keep
their deterministic time model (time advances only inside calls).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final, Protocol, runtime_checkable

from naoloc.errors import RobotError

MAX_PENDING_PER_CALLER: Final = 64  # queued calls per client before new ones are refused
MAX_NESTING: Final = 6  # blocking calls served inside blocking calls, at most
MAX_BURST_CYCLES: Final = 50  # a clock that falls further behind than this drops time


@runtime_checkable
class ClockHost(Protocol):
    """A simulated robot whose time can be driven by a :class:`SimClock`."""

    def attach_clock(self, clock: SimClock | None) -> tuple[Callable[[], None], float]:
        """Route time advance through ``clock`` (None = back to deterministic time).

        Returns:
            The function that runs one ALMotion cycle, and the cycle length in seconds.
        """
        ...


@dataclass
class _Job:
    function: Callable[..., Any]
    args: tuple[Any, ...]
    kwargs: dict[str, Any]
    done: threading.Event = field(default_factory=threading.Event)
    value: Any = None
    error: BaseException | None = None
    report: Callable[[BaseException], None] | None = None  # a submitted job's error goes here


class RobotLoop:
    """One thread that runs every robot call, fairly across callers, and drives the clock.

    Args:
        name: Thread name.
    """

    def __init__(self, name: str = "naoloc-robot") -> None:
        self._cond = threading.Condition()
        self._queues: dict[str, deque[_Job]] = {}
        self._order: deque[str] = deque()
        self._closed = False
        self._depth = 0
        self.clock: SimClock | None = None
        self._thread = threading.Thread(target=self._main, name=name, daemon=True)
        self._thread.start()

    @property
    def on_loop(self) -> bool:
        """True when called from the loop thread itself."""
        return threading.current_thread() is self._thread

    def run(
        self, function: Callable[..., Any], *args: Any, caller: str = "server", **kwargs: Any
    ) -> Any:
        """Run ``function(*args, **kwargs)`` on the loop thread; return its result or raise.

        Raises:
            RobotError: ``caller`` has too many calls queued, or the loop is closed.
        """
        if self.on_loop:
            return function(*args, **kwargs)
        job = _Job(function, args, kwargs)
        self._enqueue(job, caller)
        job.done.wait()
        if job.error is not None:
            raise job.error
        return job.value

    def submit(
        self,
        function: Callable[..., Any],
        *args: Any,
        caller: str = "server",
        report: Callable[[BaseException], None] | None = None,
    ) -> None:
        """Queue ``function(*args)`` behind ``caller``'s earlier calls and return at once.

        NAOqi's non-blocking calls (``move``, ``moveToward``) answer before the robot
        acts; the order of one caller's calls is kept. ``report`` gets the error, if any.

        Raises:
            RobotError: ``caller`` has too many calls queued, or the loop is closed.
        """
        job = _Job(function, args, {}, report=report)
        if self.on_loop:
            self._execute(job)
            return
        self._enqueue(job, caller)

    def _enqueue(self, job: _Job, caller: str) -> None:
        with self._cond:
            if self._closed:
                raise RobotError("the robot is closed")
            queue = self._queues.setdefault(caller, deque())
            if len(queue) >= MAX_PENDING_PER_CALLER:
                raise RobotError(
                    f"too many calls queued ({MAX_PENDING_PER_CALLER}); wait for answers"
                )
            queue.append(job)
            if len(queue) == 1:
                self._order.append(caller)
            self._cond.notify()

    def _next(self, timeout_s: float | None) -> _Job | None:
        with self._cond:
            if not self._order and not self._closed:
                self._cond.wait(timeout_s)
            if not self._order:
                return None
            caller = self._order.popleft()
            queue = self._queues[caller]
            job = queue.popleft()
            if queue:
                self._order.append(caller)
            else:
                del self._queues[caller]
            return job

    def _execute(self, job: _Job) -> None:
        clock = self.clock
        saved = clock.begin_call() if clock is not None else False
        self._depth += 1
        try:
            job.value = job.function(*job.args, **job.kwargs)
        except BaseException as err:  # handed to the caller's thread
            job.error = err
        finally:
            self._depth -= 1
            if clock is not None:
                clock.end_call(saved)
            job.done.set()
        if job.report is not None and job.error is not None:
            job.report(job.error)

    def serve_until(self, deadline: float) -> None:
        """Run queued jobs until ``deadline`` (time.monotonic); used inside blocking calls."""
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            if self._depth > MAX_NESTING:
                time.sleep(remaining)
                return
            job = self._next(remaining)
            if job is not None:
                self._execute(job)

    def _main(self) -> None:
        while True:
            clock = self.clock
            timeout = clock.next_due_in() if clock is not None else None
            job = self._next(timeout)
            if job is not None:
                self._execute(job)
                continue
            with self._cond:
                if self._closed and not self._order:
                    return
            clock = self.clock
            if clock is not None:
                clock.catch_up()

    def close(self) -> None:
        """Finish queued calls, then end the thread."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        if not self.on_loop:
            self._thread.join(timeout=10.0)


class SimClock:
    """Runs a simulation at ``speed`` times real time on a :class:`RobotLoop`.

    Args:
        loop: The robot loop (the clock steps on its thread).
        speed: Simulated seconds per wall-clock second (1.0 = a real NAO).
        log: Where one-line notices go.
    """

    def __init__(self, loop: RobotLoop, speed: float, log: Callable[[str], None] = print) -> None:
        if not (speed > 0 and speed < 1e4):
            raise RobotError(f"--speed must be in (0, 10000), got {speed}")
        self.speed = float(speed)
        self._loop = loop
        self._log = log
        self._step: Callable[[], None] | None = None
        self.cycle_s = 0.02
        self._wall0 = time.monotonic()
        self.cycles = 0
        self._free = False
        self.dropped_cycles = 0

    def attach(self, host: ClockHost) -> None:
        """Drive ``host``'s time from now on; run it on the loop thread (``loop.run``)."""
        self._step, self.cycle_s = host.attach_clock(self)
        self._wall0 = time.monotonic()
        self.cycles = 0
        self._loop.clock = self

    def detach(self, host: ClockHost) -> None:
        """Give ``host`` back its deterministic time; run it on the loop thread."""
        host.attach_clock(None)
        self._step = None
        if self._loop.clock is self:
            self._loop.clock = None

    def due(self) -> int:
        """Cycles the wall clock allows now that have not run yet (may be negative)."""
        allowed = int(self.speed * (time.monotonic() - self._wall0) / self.cycle_s)
        return allowed - self.cycles

    def next_due_in(self) -> float:
        """Wall seconds until the next cycle is due (0 when one is due already)."""
        at = self._wall0 + (self.cycles + 1) * self.cycle_s / self.speed
        return max(0.0, at - time.monotonic())

    def _one(self) -> None:
        if self._step is not None:
            self._step()
        self.cycles += 1

    def catch_up(self) -> None:
        """Run every cycle that is due (the idle loop's job)."""
        due = self.due()
        if due > MAX_BURST_CYCLES:  # the machine cannot keep up: let time slip
            self.dropped_cycles += due - MAX_BURST_CYCLES
            self.cycles += due - MAX_BURST_CYCLES
            due = MAX_BURST_CYCLES
        for _ in range(due):
            self._one()

    def begin_call(self) -> bool:
        """A service call starts: its first cycle of time is free; returns the old state."""
        saved, self._free = self._free, True
        return saved

    def end_call(self, saved: bool) -> None:
        """A service call ended: restore the enclosing call's state."""
        self._free = saved

    def advance(self, cycles: int) -> None:
        """A backend asks for ``cycles`` of time advance inside a service call.

        The first cycle of a call runs only when one is due (a plain call does not push
        time ahead); every further cycle waits for the wall clock, serving other calls.
        """
        for _ in range(cycles):
            if self._free:
                self._free = False
                if self.due() <= 0:
                    continue
            else:
                while self.due() <= 0:
                    self._loop.serve_until(time.monotonic() + self.next_due_in())
            self._one()
