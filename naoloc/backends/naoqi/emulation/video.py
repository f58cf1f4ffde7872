"""ALVideoDevice served: the simulated robot's own ALVideoDevice, on the robot thread.

NAOqi's semantics (argument rules, subscriber bookkeeping, the deprecated ``subscribe``,
frame rates 1-30, per-camera parameters) are the backend's
(:class:`naoloc.backends.simulated.video.SimulatedVideo`, the same in process and served);
this front runs each call on the robot thread for the calling client and logs the calls
that are accepted but not simulated.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from naoloc.backends.naoqi.emulation.context import FrontContext, forwarded


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

    def __getattr__(self, name: str) -> Callable[..., Any]:
        return forwarded(self._ctx, self._device, name)
