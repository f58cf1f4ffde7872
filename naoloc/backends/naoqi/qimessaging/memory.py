"""ALMemory.subscriber(key) over QiMessaging: objects whose ``signal`` fires on each event.

NAOqi scripts watch events with ``memory.subscriber("FrontTactilTouched").signal
.connect(callback)``. The served core's memory (anything with ``add_listener(fn)``
calling ``fn(key, value)`` on every event or data change) feeds a :class:`MemoryHub`;
each subscriber is served as an object of the ALMemory service (see
:meth:`~.server.QiServer._export`) and forgotten once no client holds it.
"""

from __future__ import annotations

import threading
import weakref
from typing import Any

from naoloc.backends.naoqi.session import Signal
from naoloc.errors import RobotError


class MemorySubscriber:
    """One ``ALMemory.subscriber(key)``: its ``signal`` carries each new value (``(m)``)."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.signal = Signal()
        self.signal.signature = "(m)"  # type: ignore[attr-defined]


class MemoryHub:
    """Routes memory events to the live subscribers of their key."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._subscribers: dict[str, weakref.WeakSet[MemorySubscriber]] = {}

    def new(self, key: Any) -> MemorySubscriber:
        """A subscriber of ``key``.

        Raises:
            RobotError: The key is not a non-empty string.
        """
        if not isinstance(key, str) or not key:
            raise RobotError("ALMemory.subscriber: the key must be a non-empty string")
        subscriber = MemorySubscriber(key)
        with self._lock:
            self._subscribers.setdefault(key, weakref.WeakSet()).add(subscriber)
        return subscriber

    def emit(self, key: str, value: Any) -> None:
        """Fire the signal of every live subscriber of ``key``."""
        with self._lock:
            live = list(self._subscribers.get(key, ()))
        for subscriber in live:
            subscriber.signal(value)
