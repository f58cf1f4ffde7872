"""ALVideoDevice served: the simulated robot's own ALVideoDevice, on the robot thread.

NAOqi's semantics (argument rules, subscriber bookkeeping, the deprecated ``subscribe``,
frame rates 1-30, per-camera parameters) are the backend's
(:class:`naoloc.backends.simulated.video.SimulatedVideo`, the same in process and served);
this front runs each call on the robot thread for the calling client and logs the calls
that are accepted but not simulated.

It also knows which client took each subscriber: when a client leaves, its subscribers
are orphaned and unsubscribed :func:`release_orphans` later (at once when the table is
full), unless a client names one first (a reconnected client adopts it).
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from typing import Any

from naoloc.backends.naoqi.emulation.context import FrontContext, forwarded
from naoloc.errors import RobotError
from naoloc.robot import rules


class VideoFront:
    """ALVideoDevice of a served robot: every public method of ``device``, run by ``ctx``.

    Args:
        device: The backend's ALVideoDevice (fake or MuJoCo).
        ctx: The host's context.
    """

    def __init__(self, device: Any, ctx: FrontContext) -> None:
        self._device = device
        self._ctx = ctx
        if hasattr(device, "on_not_simulated"):
            device.on_not_simulated = ctx.not_simulated
        self._lock = threading.Lock()
        self._owners: dict[str, str] = {}  # handle -> the client that subscribed
        self._orphaned: dict[str, float] = {}  # handle -> when its owner left (monotonic)

    def __getattr__(self, name: str) -> Callable[..., Any]:
        call = forwarded(self._ctx, self._device, name)

        def adopting(*args: Any) -> Any:
            if args and isinstance(args[0], str):
                self._adopt(args[0])
            return call(*args)

        adopting.__name__ = name
        return adopting

    def subscribeCamera(self, *args: Any) -> str:
        """Subscribe (the backend's rules), remembering the calling client as the owner."""
        return self._subscribe("subscribeCamera", args)

    def subscribe(self, *args: Any) -> str:
        """The deprecated form (the active camera), remembering the owner too."""
        return self._subscribe("subscribe", args)

    def unsubscribe(self, nameId: Any) -> bool:
        """Drop a subscriber (any client may, as on a NAO)."""
        done = bool(self._ctx.run(self._device.unsubscribe, nameId))
        with self._lock:
            self._owners.pop(str(nameId), None)
            self._orphaned.pop(str(nameId), None)
        return done

    def _subscribe(self, method: str, args: tuple[Any, ...]) -> str:
        if self._orphaned:  # subscribers of clients that left make room at once
            taken = len(self._ctx.run(self._device.getSubscribers))
            if taken >= rules.MAX_SUBSCRIBERS:
                self.release_orphans()
        handle = str(self._ctx.run(getattr(self._device, method), *args))
        with self._lock:
            self._owners[handle] = self._ctx.caller
            self._orphaned.pop(handle, None)
        return handle

    def _adopt(self, handle: str) -> None:
        caller = self._ctx.caller
        with self._lock:
            if caller and handle in self._orphaned:
                del self._orphaned[handle]
                self._owners[handle] = caller

    def orphan(self, caller: str) -> int:
        """``caller`` left: its subscribers wait for :meth:`release_orphans`."""
        now = time.monotonic()
        with self._lock:
            mine = [h for h, owner in self._owners.items() if owner == caller]
            for handle in mine:
                self._orphaned.setdefault(handle, now)
        return len(mine)

    def release_orphans(self, older_than_s: float = 0.0) -> int:
        """Unsubscribe the subscribers whose owner left more than ``older_than_s`` ago."""
        now = time.monotonic()
        with self._lock:
            gone = [h for h, t in self._orphaned.items() if now - t >= older_than_s]
            for handle in gone:
                del self._orphaned[handle]
                self._owners.pop(handle, None)
        for handle in gone:
            with contextlib.suppress(RobotError):
                self._ctx.run(self._device.unsubscribe, handle)
        return len(gone)
