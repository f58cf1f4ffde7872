"""ALRobotPosture of the fake robot."""

from __future__ import annotations

from naoloc.backends.fake.joints import posture_names
from naoloc.backends.fake.world import FakeWorld
from naoloc.errors import RobotError


class FakePosture:
    """ALRobotPosture: predefined postures reached by joint interpolation.

    ``goToPosture`` stiffens the body (as NAOqi does), stops any walk, blocks for the
    time the joints need at ``maxSpeedFraction`` and returns True. An unknown posture
    name raises :class:`~naoloc.errors.RobotError`, as NAOqi raises.

    Args:
        world: The shared robot state and clock.
    """

    def __init__(self, world: FakeWorld) -> None:
        self._world = world

    def goToPosture(self, postureName: str, maxSpeedFraction: float) -> bool:
        """Go to a predefined posture; blocking; True when reached."""
        w = self._world
        w.check_open()
        if postureName not in posture_names():
            raise RobotError(
                f"unknown posture {postureName!r}; known: {', '.join(posture_names())}"
            )
        fraction = float(maxSpeedFraction)
        if not 0.0 < fraction <= 1.0:
            raise RobotError(f"goToPosture: speed fraction must be in (0, 1], got {fraction}")
        w.stop_walk()
        w.go_to_posture(postureName, fraction)
        return True

    def getPosture(self) -> str:
        """Name of the last posture reached, or "Unknown" after arm or leg joint commands."""
        self._world.tick()
        return self._world.posture

    def getPostureList(self) -> list[str]:
        """Names of the predefined postures."""
        self._world.tick()
        return posture_names()

    def stopMove(self) -> None:
        """Stop a posture change (postures here complete inside goToPosture) and any walk."""
        w = self._world
        w.check_open()
        w.stop_walk()
        w.tick()
