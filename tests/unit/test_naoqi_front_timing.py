"""NAOqi's timing in the served fronts (issue 32, build item 3).

moveToward's moveConfig with the SDK examples' ``Frequency``; move/moveToward answer at
once however long the robot thread takes; ``wait(id, 0)`` waits until the task ends;
posture changes, wakeUp and rest take a NAO's time and a stopMove ends them early.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.loop import RobotLoop
from naoloc.backends.naoqi.emulation.motion import MotionFront
from naoloc.backends.naoqi.emulation.posture import PostureFront, nao_posture_time_s
from naoloc.errors import RobotError

SPEED = 20.0  # simulated seconds per wall second: a NAO's seconds pass quickly


class SlowBody:
    """A backend whose calls take wall time on the robot thread, like a busy simulator."""

    def __init__(self, delay_s: float = 0.0) -> None:
        self.delay_s = delay_s
        self.calls: list[tuple[str, tuple[Any, ...]]] = []
        self.awake = False
        self.posture = "Crouch"

    def _log(self, name: str, *args: Any) -> None:
        time.sleep(self.delay_s)
        self.calls.append((name, args))

    def moveToward(self, *args: Any) -> None:
        self._log("moveToward", *args)

    def move(self, *args: Any) -> None:
        self._log("move", *args)

    def stopMove(self) -> None:
        self._log("stopMove")

    def robotIsWakeUp(self) -> bool:
        return self.awake

    def wakeUp(self) -> None:
        self.awake, self.posture = True, "StandInit"

    def rest(self) -> None:
        self.awake, self.posture = False, "Crouch"

    def getPosture(self) -> str:
        return self.posture

    def goToPosture(self, name: str, fraction: float) -> bool:
        self.posture = name
        return True


@pytest.fixture
def loop() -> Any:
    robot_loop = RobotLoop()
    yield robot_loop
    robot_loop.close()


def _ctx(loop: RobotLoop) -> FrontContext:
    def run(function: Any, *args: Any, **kwargs: Any) -> Any:
        return loop.run(function, *args, caller="c", **kwargs)

    def submit(function: Any, *args: Any) -> None:
        loop.submit(function, *args, caller="c")

    return FrontContext(run=run, submit=submit, speed=SPEED, log=lambda _: None)


def test_move_toward_answers_at_once_and_keeps_the_callers_order(loop: RobotLoop) -> None:
    body = SlowBody(delay_s=0.1)
    motion = MotionFront(body, _ctx(loop))
    started = time.monotonic()
    for _ in range(5):
        motion.moveToward(0.5, 0.0, 0.0)
    motion.move(0.1, 0.0, 0.0)
    assert time.monotonic() - started < 0.1  # five re-sends, each would take 0.1 s
    motion.stopMove()  # waits for the robot thread: everything before it ran, in order
    assert [name for name, _ in body.calls] == ["moveToward"] * 5 + ["move", "stopMove"]


def test_move_toward_takes_the_examples_frequency(loop: RobotLoop) -> None:
    body = SlowBody()
    motion = MotionFront(body, _ctx(loop))
    motion.moveToward(1.0, 0.0, 0.0, [["Frequency", 1.0]])
    motion.moveToward(1.0, 0.0, 0.0, [["Frequency", 0.0], ["MaxStepX", 0.06]])
    motion.moveToward(1.0, 0.0, 0.0, [["MaxStepFrequency", 0.0]])
    motion.stopMove()
    speeds = [args[0] for name, args in body.calls if name == "moveToward"]
    assert speeds[0] == pytest.approx(1.0)
    assert speeds[1] == pytest.approx(0.42 / 0.6) and speeds[2] == pytest.approx(0.42 / 0.6)
    for bad in ([["Frequency", 1.5]], [["Frequency", "fast"]], [["Frequence", 1.0]]):
        with pytest.raises(RobotError):
            motion.moveToward(1.0, 0.0, 0.0, bad)


def test_wait_with_timeout_zero_waits_until_the_task_ends(loop: RobotLoop) -> None:
    ctx = _ctx(loop)
    task = ctx.tasks.start("moveTo", "walk", None)
    threading.Timer(0.3, ctx.tasks.end, args=(task,)).start()
    started = time.monotonic()
    assert ctx.tasks.wait(task.id, 0) is True
    assert time.monotonic() - started >= 0.25
    assert ctx.tasks.wait(task.id, 0) is True  # an ended task: at once


def test_postures_wake_up_and_rest_take_a_naos_time(loop: RobotLoop) -> None:
    body = SlowBody()
    ctx = _ctx(loop)
    motion, posture = MotionFront(body, ctx), PostureFront(body, ctx)

    def timed(call: Any, *args: Any) -> float:
        started = time.monotonic()
        call(*args)
        return (time.monotonic() - started) * SPEED  # simulated seconds

    assert timed(motion.wakeUp) == pytest.approx(2.5, abs=0.4)
    assert timed(motion.wakeUp) < 0.4  # already awake
    assert timed(posture.goToPosture, "Sit", 0.5) == pytest.approx(4.5, abs=0.4)
    assert timed(posture.goToPosture, "Sit", 0.5) < 0.4  # already there
    assert timed(posture.goToPosture, "Stand", 1.0) == pytest.approx(2.25, abs=0.4)
    assert timed(motion.rest) == pytest.approx(3.0, abs=0.4)
    assert nao_posture_time_s("LyingBack", "Stand", 0.5) == 8.0
    assert nao_posture_time_s("Stand", "Crouch", 0.1) == 5.0  # slowest: 2.5 x


def test_stop_move_ends_a_posture_change_early(loop: RobotLoop) -> None:
    body = SlowBody()
    ctx = _ctx(loop)
    posture = PostureFront(body, ctx)
    result: list[bool] = []
    worker = threading.Thread(target=lambda: result.append(posture.goToPosture("Sit", 0.1)))
    started = time.monotonic()
    worker.start()
    time.sleep(0.1)
    posture.stopMove()
    worker.join(5.0)
    assert result == [False]
    assert time.monotonic() - started < 0.5  # a NAO's 11 s were cut short
