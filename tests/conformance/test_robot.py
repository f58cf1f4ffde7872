"""Conformance: the Robot bundle (Protocols, close, simulator control)."""

from __future__ import annotations

import math
from types import ModuleType

import pytest

from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.registry import backend_names
from naoloc.robot import Motion, Posture, Robot, SimControl, VideoDevice, pose_of


def test_services_satisfy_the_protocols(robot: Robot) -> None:
    assert isinstance(robot.motion, Motion)
    assert isinstance(robot.video, VideoDevice)
    assert isinstance(robot.posture, Posture)
    assert robot.sim is None or isinstance(robot.sim, SimControl)
    assert robot.backend in backend_names()
    assert isinstance(robot.info, dict)


def test_close_is_idempotent_and_later_calls_raise(factory: ModuleType) -> None:
    with factory.make_robot() as robot:
        robot.close()
        robot.close()
        assert robot.closed
        with pytest.raises(NaolocError):
            robot.motion.getRobotPosition(False)
    robot.close()


def test_teleport_moves_the_truth_but_not_odometry(robot: Robot) -> None:
    if robot.sim is None:
        pytest.skip("no simulator control on this backend")
    sim = robot.sim
    sx, sy = sim.room_size()
    assert sim.is_free(sx / 2, sy / 2, 0.3) and not sim.is_free(0.05, sy / 2, 0.3)
    before = pose_of(robot.motion, use_sensors=False)
    t0 = sim.sim_time()
    sim.teleport(sx / 2, sy / 2, 1.0)
    x, y, theta = sim.true_pose()
    assert math.hypot(x - sx / 2, y - sy / 2) < 0.02 and abs(theta - 1.0) < 0.02
    after = pose_of(robot.motion, use_sensors=False)
    assert after.distance(before) < 0.02 and abs(after.theta - before.theta) < 0.02
    assert sim.sim_time() >= t0
    assert isinstance(Pose2D(*sim.true_pose()), Pose2D)
