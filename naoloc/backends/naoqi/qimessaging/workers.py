"""The threads that run a QiServer's calls: fair across clients, with a lane for stops.

Ordinary calls go to a fixed set of daemon worker threads. Each client has a queue of
its own and at most :attr:`CallPool.per_client` calls running at once; free workers
take the next call round-robin across clients, so one client with many blocking calls
holds at most ``per_client`` workers and everybody else still gets served.

Urgent calls (``stopMove``, ``killMove``, ``rest``, a heartbeat) never wait behind
ordinary ones: each runs at once on a thread of its own (at most
:attr:`CallPool.urgent_per_client` per client and :attr:`CallPool.urgent_max` in
all), so no other client's work can keep a stop from reaching the robot.

Every thread is a daemon and :meth:`CallPool.close` waits a bounded time: a call that
never returns cannot keep the process from exiting (``ThreadPoolExecutor`` joins its
workers at interpreter exit, so a stuck call there meant a SIGKILL).
"""

from __future__ import annotations

import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field

Job = Callable[[], None]


@dataclass
class _Lane:
    jobs: deque[Job] = field(default_factory=deque)
    running: int = 0
    urgent: int = 0
    waiting: bool = False  # in the round-robin order


class CallPool:
    """Run jobs for many clients fairly on daemon threads.

    Args:
        workers: Threads of ordinary calls.
        per_client: Ordinary calls of one client running at once.
        urgent_per_client: Urgent calls of one client running at once.
        urgent_max: Urgent calls of every client running at once.
        name: Thread name prefix.
    """

    def __init__(
        self,
        workers: int = 16,
        *,
        per_client: int = 4,
        urgent_per_client: int = 2,
        urgent_max: int = 32,
        name: str = "naoloc-qim-call",
    ) -> None:
        self.per_client = max(1, per_client)
        self.urgent_per_client = urgent_per_client
        self.urgent_max = urgent_max
        self._name = name
        self._cond = threading.Condition()
        self._lanes: dict[Hashable, _Lane] = {}
        self._order: deque[Hashable] = deque()
        self._urgent = 0
        self._closed = False
        self._threads = [
            threading.Thread(target=self._work, name=f"{name}-{i}", daemon=True)
            for i in range(max(1, workers))
        ]
        for thread in self._threads:
            thread.start()

    def submit(self, client: Hashable, job: Job) -> bool:
        """Queue an ordinary call of ``client``; False when the pool is closed."""
        with self._cond:
            if self._closed:
                return False
            lane = self._lanes.setdefault(client, _Lane())
            lane.jobs.append(job)
            self._wake(client, lane)
            return True

    def submit_urgent(self, client: Hashable, job: Job) -> bool:
        """Run an urgent call of ``client`` now on its own thread; False over a limit."""
        with self._cond:
            lane = self._lanes.setdefault(client, _Lane())
            if self._closed or lane.urgent >= self.urgent_per_client:
                return False
            if self._urgent >= self.urgent_max:
                return False
            lane.urgent += 1
            self._urgent += 1

        def run() -> None:
            try:
                job()
            finally:
                with self._cond:
                    lane.urgent -= 1
                    self._urgent -= 1
                    self._forget(client, lane)

        threading.Thread(target=run, name=f"{self._name}-urgent", daemon=True).start()
        return True

    def running(self, client: Hashable) -> int:
        """Calls of ``client`` running or queued now."""
        with self._cond:
            lane = self._lanes.get(client)
            return 0 if lane is None else lane.running + lane.urgent + len(lane.jobs)

    def drop(self, client: Hashable) -> int:
        """Forget ``client``'s queued calls (it left); returns how many were dropped."""
        with self._cond:
            lane = self._lanes.get(client)
            if lane is None:
                return 0
            dropped = len(lane.jobs)
            lane.jobs.clear()
            self._forget(client, lane)
            return dropped

    def _wake(self, client: Hashable, lane: _Lane) -> None:
        if not lane.waiting and lane.jobs and lane.running < self.per_client:
            lane.waiting = True
            self._order.append(client)
            self._cond.notify()

    def _forget(self, client: Hashable, lane: _Lane) -> None:
        idle = not lane.jobs and not lane.running and not lane.urgent and not lane.waiting
        if idle and self._lanes.get(client) is lane:
            del self._lanes[client]

    def _next(self) -> tuple[Hashable, _Lane, Job] | None:
        with self._cond:
            while True:
                while not self._order and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return None
                client = self._order.popleft()
                lane = self._lanes[client]
                lane.waiting = False
                if lane.jobs:  # else dropped meanwhile (the client left)
                    break
                self._forget(client, lane)
            job = lane.jobs.popleft()
            lane.running += 1
            self._wake(client, lane)
            return client, lane, job

    def _work(self) -> None:
        while True:
            picked = self._next()
            if picked is None:
                return
            client, lane, job = picked
            try:
                job()
            except Exception:  # a job reports its own errors; the worker goes on
                pass
            finally:
                with self._cond:
                    lane.running -= 1
                    self._wake(client, lane)
                    self._forget(client, lane)

    def close(self, wait_s: float = 1.0) -> int:
        """Refuse new calls, drop queued ones, wait up to ``wait_s`` for running ones.

        Returns:
            How many threads were still running a call when the wait ended (daemons:
            they do not keep the process alive).
        """
        with self._cond:
            self._closed = True
            for lane in self._lanes.values():
                lane.jobs.clear()
            self._order.clear()
            self._cond.notify_all()
        deadline = time.monotonic() + wait_s
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))
        return sum(t.is_alive() for t in self._threads)


class Notices:
    """One line on stderr per kind of notice, at most one a second (the rest counted)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._last: dict[str, float] = {}
        self._skipped: dict[str, int] = {}

    def __call__(self, kind: str, text: str) -> None:
        now = time.monotonic()
        with self._lock:
            if now - self._last.get(kind, -1e9) < 1.0:
                self._skipped[kind] = self._skipped.get(kind, 0) + 1
                return
            self._last[kind] = now
            skipped = self._skipped.pop(kind, 0)
        more = f" (+{skipped} more since the last notice)" if skipped else ""
        print(f"naoloc serve: {text}{more}", file=sys.stderr, flush=True)
