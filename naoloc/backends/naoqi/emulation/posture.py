"""ALRobotPosture in front of a simulated backend: names, families, a NAO's timing.

A NAO changes posture in seconds: ALRobotPosture plans through intermediate postures
(standing up from lying passes through kneeling and crouching) and moves at
``maxSpeedFraction`` of the joints' speed. The simulated backends reach a posture
faster (the fake one interpolates joints, MuJoCo sets them), so the front holds a
blocking posture call until a NAO's time has passed: :func:`nao_posture_time_s`, by
posture family, at fraction 0.5 (what scripts pass most) and inversely proportional
to the fraction within [0.5x, 2.5x]. ALMotion's ``wakeUp`` and ``rest`` use the same
rule. These are approximate durations of a NAO V5/V6, not measured on one here.
"""

from __future__ import annotations

import threading
import time
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.constants import POSTURES
from naoloc.robot import rules

# Seconds a NAO takes between posture families at maxSpeedFraction 0.5 (either order).
_FAMILY_TIME_S: Final[dict[frozenset[str], float]] = {
    frozenset({"Standing"}): 1.0,
    frozenset({"Standing", "Crouching"}): 2.0,
    frozenset({"Crouching"}): 1.0,
    frozenset({"Sitting"}): 1.5,
    frozenset({"Standing", "Sitting"}): 4.5,
    frozenset({"Crouching", "Sitting"}): 3.5,
}
_LIE_DOWN_S: Final = 4.0  # to a lying posture
_GET_UP_S: Final = 8.0  # from a lying posture (kneel, crouch, stand)
_OTHER_S: Final = 3.0  # from "Unknown"
WAKE_UP_S: Final = 2.5  # ALMotion.wakeUp from rest: stiffness on, crouch to StandInit
REST_S: Final = 3.0  # ALMotion.rest from standing: crouch, stiffness off


def nao_posture_time_s(start: str, goal: str, fraction: float) -> float:
    """How long a NAO takes from posture ``start`` to ``goal`` (s, simulated).

    Args:
        start: The current posture name ("Unknown" when between postures).
        goal: The predefined posture asked for.
        fraction: ALRobotPosture's maxSpeedFraction in (0, 1].

    Returns:
        0 when already there; otherwise the family-to-family time at fraction 0.5,
        scaled by ``0.5 / fraction`` clipped to [0.5, 2.5].
    """
    if start == goal:
        return 0.0
    a = rules.POSTURE_FAMILIES.get(start, "Unknown")
    b = rules.POSTURE_FAMILIES.get(goal, "Unknown")
    if a.startswith("Lying") and a != b:
        base = _GET_UP_S
    elif b.startswith("Lying"):
        base = _LIE_DOWN_S if a != b else 1.5
    else:
        base = _FAMILY_TIME_S.get(frozenset({a, b}), _OTHER_S)
    return base * min(2.5, max(0.5, 0.5 / max(fraction, 1e-3)))


def hold_until(ctx: FrontContext, started: float, seconds: float, stop: threading.Event) -> bool:
    """Wait until ``seconds`` of simulated time have passed since ``started`` (monotonic
    wall clock); False when ``stop`` was set first."""
    spent = (time.monotonic() - started) * ctx.speed
    return ctx.sleep_sim(seconds - spent, stop) if seconds > spent else not stop.is_set()


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
        """Go to a predefined posture; blocking for a NAO's time; True when reached.

        Returns:
            False when the posture was not reached or the call was stopped (stopMove).
        """
        name = rules.posture_name(postureName)
        frac = rules.fraction(maxSpeedFraction)
        task = self._ctx.tasks.start(
            "goToPosture", "posture", lambda: self._run("stopMove"), self._ctx.caller
        )
        try:
            started = time.monotonic()
            before = str(self._run("getPosture"))
            reached = bool(self._run("goToPosture", name, frac))
            seconds = nao_posture_time_s(before, name, frac)
            return hold_until(self._ctx, started, seconds, task.stopped) and reached
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
        self._ctx.tasks.stop_all("posture")
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
