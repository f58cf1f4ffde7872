"""Conformance: ``naoloc.robot.conformance.check_robot`` on every backend and transport.

The checks themselves live in :mod:`naoloc.robot.conformance` (shipped, like Gymnasium's
``check_env``); here they run on the fake and MuJoCo robots in-process and on a
virtual NAOqi (``naoloc serve``, real-time clock) over zmq and over libqi.
"""

from __future__ import annotations

from types import ModuleType

import pytest

from naoloc.constants import COLORSPACE_LAYERS
from naoloc.errors import NaolocError
from naoloc.robot import Robot
from naoloc.robot.conformance import CHECKS, ConformanceError, check_robot
from naoloc.robot.registry import backend_names


def test_check_robot_passes(robot: Robot, factory: ModuleType) -> None:
    assert robot.backend in backend_names()
    check_robot(
        robot,
        resolutions=getattr(factory, "RESOLUTIONS", (0, 1, 2)),
        colorspaces=getattr(factory, "COLORSPACES", tuple(sorted(COLORSPACE_LAYERS))),
    )


def test_close_is_idempotent_and_later_calls_raise(factory: ModuleType) -> None:
    with factory.make_robot() as robot:
        robot.close()
        robot.close()
        assert robot.closed
        with pytest.raises(NaolocError):
            robot.motion.getRobotPosition(False)
    robot.close()


class _Liar:
    """A robot whose moveTo claims success without walking: check_robot must catch it."""

    def __init__(self, robot: Robot) -> None:
        self._robot = robot

    def __getattr__(self, name: str) -> object:
        return getattr(self._robot.motion, name)

    def moveTo(self, *args: object) -> bool:
        return True


def test_check_robot_catches_a_backend_that_lies() -> None:
    import naoloc

    with naoloc.connect({"robot": {"backend": "fake"}}) as robot:
        liar = Robot(motion=_Liar(robot), video=robot.video, posture=robot.posture, sim=robot.sim)  # type: ignore[arg-type]
        with pytest.raises(ConformanceError, match="walk_forward: moveTo"):
            check_robot(liar)
    assert "walk_forward" in CHECKS
