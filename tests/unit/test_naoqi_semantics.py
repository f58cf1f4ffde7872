"""Units of naoloc.backends.naoqi.emulation: NAOqi's argument rules, the task table and the
real-time clock."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import pytest

from naoloc.backends.naoqi.emulation.loop import RobotLoop, SimClock
from naoloc.backends.naoqi.emulation.tasks import TaskTable
from naoloc.errors import RobotError
from naoloc.robot import rules


def test_names_expand_joints_chains_groups_and_lists() -> None:
    assert rules.expand_names("HeadYaw") == ["HeadYaw"]
    assert rules.expand_names("Head") == ["HeadYaw", "HeadPitch"]
    assert len(rules.expand_names("Body")) == 26
    assert "RHipYawPitch" not in rules.expand_names("JointActuators")
    assert len(rules.expand_names(["LArm", "HeadYaw"])) == 7
    for bad in ("Tail", ["HeadYaw", 3], [], 5):
        with pytest.raises(RobotError):
            rules.expand_names(bad)


def test_numbers_fractions_and_move_configs() -> None:
    assert rules.per_joint(0.5, 3, "angles") == [0.5, 0.5, 0.5]
    assert rules.per_joint([0.1], 2, "angles") == [0.1, 0.1]
    with pytest.raises(RobotError, match="2 joint names but 3 angles"):
        rules.per_joint([1, 2, 3], 2, "angles")
    with pytest.raises(RobotError, match="finite"):
        rules.per_joint(float("nan"), 1, "angles")
    assert rules.fraction(1) == 1.0
    for bad in (0, 1.5, True, "0.5"):
        with pytest.raises(RobotError):
            rules.fraction(bad)
    assert rules.move_config([["MaxStepX", 0.04]]) == {"MaxStepX": 0.04}
    with pytest.raises(RobotError, match="unknown moveConfig"):
        rules.move_config([["MaxStepZ", 1]])
    with pytest.raises(RobotError, match=r"\[0.001, 0.08\]"):
        rules.move_config({"MaxStepX": 1.0})
    assert rules.move_to_points((0.1, 0, 0)) == ([[0.1, 0.0, 0.0]], {})
    assert rules.move_to_points(([0.1, 0, 0],))[0] == [[0.1, 0.0, 0.0]]
    points, config = rules.move_to_points(([[0.1, 0, 0], [0.2, 0, 1]], [["MaxStepY", 0.12]]))
    assert len(points) == 2 and config == {"MaxStepY": 0.12}
    with pytest.raises(RobotError, match="moveTo takes"):
        rules.move_to_points(("far",))


def test_video_rules_accept_any_rate_from_1_to_30() -> None:
    assert rules.subscription(1, 11, 7) == (1, 11, 7)
    for res, cs, fps in ((1, 11, 0), (1, 11, 31), (99, 11, 5), (1, 99, 5), (1, 11, 5.0)):
        with pytest.raises(RobotError):
            rules.subscription(res, cs, fps)
    assert rules.backend_fps(7) == 5 and rules.backend_fps(24) == 30
    with pytest.raises(RobotError, match="camera index 2"):
        rules.camera_index(2)


def test_key_frames_follow_naoqi_shapes() -> None:
    one = rules.keyframes(["HeadYaw"], [0.5, 0.0], [1.0, 2.0], "angleInterpolation")
    assert one == [[(1.0, 0.5), (2.0, 0.0)]]
    per_joint = rules.keyframes(["HeadYaw", "HeadPitch"], [1.0, -0.5], [1.0, 1.2], "a")
    assert per_joint == [[(1.0, 1.0)], [(1.2, -0.5)]]
    shared = rules.keyframes(["HeadYaw", "HeadPitch"], 1.0, 0.5, "stiffnessInterpolation")
    assert shared == [[(0.5, 1.0)], [(0.5, 1.0)]]
    nested = rules.keyframes(["HeadYaw", "HeadPitch"], [[0.1, 0.2], [0.3]], [[1, 2], [1]], "a")
    assert nested == [[(1.0, 0.1), (2.0, 0.2)], [(1.0, 0.3)]]
    with pytest.raises(RobotError, match="increasing"):
        rules.keyframes(["HeadYaw"], [0.1, 0.2], [1.0, 0.5], "a")


def test_error_lines_name_the_method_once_and_hide_internals() -> None:
    line = rules.error_line("ALMotion", "setAngles", RobotError("setAngles: bad"))
    assert line == "RobotError: ALMotion.setAngles: bad"
    internal = rules.error_line("ALMotion", "moveTo", KeyError("x\nTraceback"))
    assert internal.startswith("RobotError: ALMotion.moveTo: internal error (KeyError")
    assert "\n" not in internal


def test_task_table_waits_stops_and_forgets() -> None:
    tasks = TaskTable()
    stopped: list[int] = []
    task = tasks.start("moveTo", "walk", lambda: stopped.append(1))
    assert tasks.is_running(task.id) and tasks.wait(task.id, 30) is False
    threading.Timer(0.05, tasks.end, args=(task,)).start()
    assert tasks.wait(task.id, 0) is True and not tasks.is_running(task.id)
    other = tasks.start("angleInterpolation", "joints", None)
    assert tasks.stop(other.id) is True and other.stopped.is_set()
    assert tasks.stop(12345) is False and tasks.wait(12345, 10) is True
    walk = tasks.start("moveTo", "walk", lambda: stopped.append(2))
    assert tasks.stop_all("walk") == 1 and stopped == [2]
    tasks.end(walk)
    with pytest.raises(RobotError):
        tasks.wait(other.id, -1)


class _Host:
    """A ClockHost that counts cycles."""

    def __init__(self) -> None:
        self.cycles = 0
        self.clock: SimClock | None = None

    def attach_clock(self, clock: SimClock | None) -> tuple[Callable[[], None], float]:
        self.clock = clock
        return self._step, 0.02

    def _step(self) -> None:
        self.cycles += 1

    def blocking(self, cycles: int) -> int:
        """A backend's blocking call: ``cycles`` of time through the clock."""
        assert self.clock is not None
        start = self.cycles
        self.clock.advance(cycles)
        return self.cycles - start


def test_clock_runs_at_speed_and_paces_blocking_calls_while_serving_others() -> None:
    loop = RobotLoop()
    try:
        host = _Host()
        clock = SimClock(loop, speed=5.0)
        loop.run(clock.attach, host)
        time.sleep(0.4)  # 2 simulated seconds = 100 cycles
        idle = loop.run(lambda: host.cycles)
        assert 80 <= idle <= 110, idle
        assert loop.run(host.blocking, 1) <= 1  # a plain call does not push time ahead
        done: list[float] = []
        started = time.monotonic()
        worker = threading.Thread(
            target=lambda: done.append(loop.run(host.blocking, 50, caller="a"))
        )
        worker.start()
        time.sleep(0.05)
        t0 = time.monotonic()
        assert loop.run(lambda: "served", caller="b") == "served"  # during the blocking call
        assert time.monotonic() - t0 < 0.1
        worker.join(5)
        took = time.monotonic() - started
        assert done and 0.15 < took < 0.5, took  # 50 cycles = 1 s simulated = 0.2 s wall
    finally:
        loop.run(clock.detach, host)
        loop.close()
