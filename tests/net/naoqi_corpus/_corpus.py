"""What every corpus script shares: the qi module (injectable), the URL and the clock speed.

Scripts named ``oldsdk_*.py`` are written for the old SDK (``from naoqi import ALProxy``)
and run under ``python -m naoloc.run``; they take the robot as ``ip_port()``.

The scripts are written against the ``qi`` API as NAO programmers write them. The
module is ``qi`` unless ``NAOLOC_QI_MODULE`` names another one with the same API (for
example ``naoloc.qi``); the robot's URL is ``argv[1]`` (``--qi-url`` style default
``tcp://127.0.0.1:9559``); ``NAOLOC_SPEED`` is the server's ``--speed`` so that
expectations in simulated seconds can be turned into wall seconds.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any


def qi_module() -> Any:
    """The qi-compatible module under test."""
    return importlib.import_module(os.environ.get("NAOLOC_QI_MODULE", "qi"))


def url() -> str:
    """The robot's URL (first argument)."""
    return sys.argv[1] if len(sys.argv) > 1 else "tcp://127.0.0.1:9559"


def ip_port() -> tuple[str, int]:
    """The robot's address as the old SDK takes it: (ip, port)."""
    rest = url().split("://", 1)[-1]
    host, _, port = rest.rpartition(":")
    return host, int(port)


def speed() -> float:
    """Simulated seconds per wall second of the server."""
    return float(os.environ.get("NAOLOC_SPEED", "1.0"))


def session() -> Any:
    """A connected session."""
    s = qi_module().Session()
    s.connect(url())
    return s


def keep_place(s: Any) -> Any:
    """A function that puts the robot back where it is now, true pose and odometry heading.

    For scripts that teleport (NaolocSim): the scripts after them expect the robot where
    it was, facing the same way in FRAME_WORLD (teleporting does not tell odometry).
    """
    import math

    sim, motion = s.service("NaolocSim"), s.service("ALMotion")
    pose, heading = sim.true_pose(), motion.getRobotPosition(False)[2]

    def back() -> None:
        turn = heading - motion.getRobotPosition(False)[2]
        turn = math.atan2(math.sin(turn), math.cos(turn))
        if abs(turn) > 0.01:
            motion.moveTo(0.0, 0.0, turn)
        sim.teleport(*pose)

    return back


def expect_error(call: Any, *words: str) -> str:
    """Run ``call()``; it must raise a RuntimeError of one line containing ``words``."""
    try:
        call()
    except RuntimeError as err:
        text = str(err)
        assert "\n" not in text.strip(), f"a multi-line error: {text!r}"
        assert ".py" not in text and "Traceback" not in text, f"a server path: {text!r}"
        for word in words:
            assert word in text, f"{word!r} not in {text!r}"
        return text
    raise AssertionError(f"no error; expected one about {words}")
