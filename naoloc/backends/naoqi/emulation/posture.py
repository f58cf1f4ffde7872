"""ALRobotPosture in front of a simulated backend: names, families, applyPosture."""

from __future__ import annotations

from typing import Any

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.constants import POSTURES
from naoloc.robot import rules


class PostureFront:
    """ALRobotPosture with NAOqi's rules in front of a backend's ``posture``.

    Args:
        backend: The backend's ALRobotPosture.
        motion_stop: Ends a walk (posture changes end walks, as NAOqi's do).
        ctx: The host's context.
    """

    def __init__(self, backend: Any, ctx: FrontContext) -> None:
        self._b = backend
        self._ctx = ctx
        self._tries = 3

    def _run(self, method: str, *args: Any) -> Any:
        return self._ctx.run(getattr(self._b, method), *args)

    def goToPosture(self, postureName: Any, maxSpeedFraction: Any) -> bool:
        """Go to a predefined posture; blocking; True when reached."""
        name = rules.posture_name(postureName)
        frac = rules.fraction(maxSpeedFraction)
        task = self._ctx.tasks.start(
            "goToPosture", "posture", lambda: self._run("stopMove"), self._ctx.caller
        )
        try:
            return bool(self._run("goToPosture", name, frac))
        finally:
            self._ctx.tasks.end(task)

    def applyPosture(self, postureName: Any, maxSpeedFraction: Any) -> bool:
        """Set the posture's joint angles (the simulator interpolates at full speed); True."""
        rules.fraction(maxSpeedFraction)
        return self.goToPosture(postureName, 1.0)

    def getPosture(self) -> str:
        """Name of the current posture, or "Unknown"."""
        return str(self._run("getPosture"))

    def getPostureList(self) -> list[str]:
        """The predefined postures."""
        return list(POSTURES)

    def getPostureFamily(self) -> str:
        """Family of the current posture (Standing, Sitting, Crouching, Lying..., Unknown)."""
        return rules.POSTURE_FAMILIES.get(self.getPosture(), "Unknown")

    def getPostureFamilyList(self) -> list[str]:
        """Every posture family."""
        return sorted(set(rules.POSTURE_FAMILIES.values()))

    def stopMove(self) -> None:
        """Stop a posture change and any walk."""
        self._run("stopMove")

    def setMaxTryNumber(self, pMaxTryNumber: Any) -> None:
        """Attempts before goToPosture gives up (stored; the simulator reaches postures at once)."""
        if (
            isinstance(pMaxTryNumber, bool)
            or not isinstance(pMaxTryNumber, int)
            or pMaxTryNumber < 1
        ):
            raise rules.RobotError(f"pMaxTryNumber must be an int >= 1, got {pMaxTryNumber!r}")
        self._tries = pMaxTryNumber
