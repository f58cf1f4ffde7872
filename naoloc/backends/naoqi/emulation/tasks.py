"""ALMotion's task model: every blocking or posted call is a task with an id.

``wait(id, timeoutPeriod)`` waits for a task (milliseconds, 0 = until it ends) and
returns True once it ended; ``isRunning(id)``; ``stop(id)`` asks the task to end (a walk
stops, a joint interpolation freezes where it is). Ids are positive and never reused.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from naoloc.errors import RobotError


@dataclass
class Task:
    """A running call.

    Attributes:
        id: Task id (positive).
        name: Method name, e.g. "moveTo".
        resources: Kind of body part it uses: "walk", "joints", "posture", "other".
        stop: Ends the task early (None = cannot be stopped early).
        caller: The client that started it.
        stopped: Set when someone asked it to stop.
        done: Set when it ended.
    """

    id: int
    name: str
    resources: str
    stop: Callable[[], None] | None
    caller: str
    stopped: threading.Event = field(default_factory=threading.Event)
    done: threading.Event = field(default_factory=threading.Event)


class TaskTable:
    """Running tasks by id (thread-safe)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self._tasks: dict[int, Task] = {}
        self._ended: set[int] = set()

    def start(
        self, name: str, resources: str, stop: Callable[[], None] | None, caller: str = ""
    ) -> Task:
        """Register a task that starts now."""
        with self._lock:
            task = Task(next(self._ids), name, resources, stop, caller)
            self._tasks[task.id] = task
        return task

    def end(self, task: Task) -> None:
        """Mark a task ended."""
        with self._lock:
            self._tasks.pop(task.id, None)
            self._ended.add(task.id)
            if len(self._ended) > 10_000:
                self._ended = set(sorted(self._ended)[-5_000:])
        task.done.set()

    def get(self, task_id: Any) -> Task | None:
        """The running task with this id, or None."""
        if isinstance(task_id, bool) or not isinstance(task_id, int):
            raise RobotError(f"a task id is an int, got {task_id!r}")
        with self._lock:
            return self._tasks.get(task_id)

    def is_running(self, task_id: Any) -> bool:
        """True while the task runs."""
        return self.get(task_id) is not None

    def wait(
        self, task_id: Any, timeout_ms: Any, cancelled: Callable[[], bool] | None = None
    ) -> bool:
        """Wait for a task to end; True when it ended (or never existed).

        Args:
            task_id: The id.
            timeout_ms: Longest wait in milliseconds; 0 = until it ends.
            cancelled: Ends the wait (False) once it returns True (the waiter left).
        """
        if isinstance(timeout_ms, bool) or not isinstance(timeout_ms, int) or timeout_ms < 0:
            raise RobotError(f"timeoutPeriod must be an int >= 0 (ms), got {timeout_ms!r}")
        task = self.get(task_id)
        if task is None:
            return True
        if cancelled is None:
            return task.done.wait(None if timeout_ms == 0 else timeout_ms / 1000.0)
        deadline = None if timeout_ms == 0 else time.monotonic() + timeout_ms / 1000.0
        while not cancelled():
            left = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
            if left <= 0 or task.done.wait(left):
                return task.done.is_set()
        return False

    def stop(self, task_id: Any) -> bool:
        """Ask a task to end; True when it was running."""
        task = self.get(task_id)
        if task is None:
            return False
        task.stopped.set()
        if task.stop is not None:
            task.stop()
        return True

    def running(self, resources: str | None = None) -> list[Task]:
        """Running tasks (of one kind of resource, or all)."""
        with self._lock:
            tasks = list(self._tasks.values())
        return [t for t in tasks if resources is None or t.resources == resources]

    def stop_all(self, resources: str | None = None) -> int:
        """Stop every running task (of one kind); returns how many."""
        tasks = self.running(resources)
        for task in tasks:
            self.stop(task.id)
        return len(tasks)

    def stop_of(self, caller: str) -> int:
        """Stop every running task ``caller`` started (it left); returns how many."""
        tasks = [t for t in self.running() if t.caller == caller]
        for task in tasks:
            self.stop(task.id)
        return len(tasks)
