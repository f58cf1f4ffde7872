"""Conformance: ALMotion and ALRobotPosture semantics (walking, odometry, head joints)."""

from __future__ import annotations

import math
import time

import pytest

from naoloc.constants import JOINT_LIMITS, JOINT_NAMES, POSTURES
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot import Robot, pose_of

POS_TOL_M = 0.05
ANGLE_TOL_RAD = math.radians(5.0)


def _ready(robot: Robot) -> None:
    robot.motion.wakeUp()
    assert robot.posture.goToPosture("StandInit", 0.8) is True


def _true(robot: Robot) -> Pose2D | None:
    return Pose2D(*robot.sim.true_pose()) if robot.sim is not None else None


def _clock(robot: Robot) -> float:
    return robot.sim.sim_time() if robot.sim is not None else time.monotonic()


def _check_move(robot: Robot, target: tuple[float, float, float]) -> None:
    """moveTo(target) reaches it by commanded odometry and, on simulators, by ground truth."""
    start = pose_of(robot.motion, use_sensors=False)
    true_start = _true(robot)
    assert robot.motion.moveTo(*target) is True
    true_end = _true(robot)
    checks = [("getRobotPosition(False)", relative_pose(start, pose_of(robot.motion, False)))]
    if true_start is not None and true_end is not None:
        checks.append(("ground truth", relative_pose(true_start, true_end)))
    for name, moved in checks:
        assert math.hypot(moved.x - target[0], moved.y - target[1]) < POS_TOL_M, (name, moved)
        assert abs(moved.theta - target[2]) < ANGLE_TOL_RAD, (name, moved)


def test_move_to_forward_reaches_target(robot: Robot) -> None:
    _ready(robot)
    _check_move(robot, (0.5, 0.0, 0.0))


def test_turn_reaches_target(robot: Robot) -> None:
    _ready(robot)
    _check_move(robot, (0.0, 0.0, math.pi / 2))


def test_odometry_by_sensors_and_by_commands_agree_on_a_short_move(robot: Robot) -> None:
    _ready(robot)
    start_cmd = pose_of(robot.motion, use_sensors=False)
    start_sensor = pose_of(robot.motion, use_sensors=True)
    assert robot.motion.moveTo(0.3, 0.0, 0.0) is True
    by_cmd = robot.motion.getRobotPosition(False)
    by_sensor = robot.motion.getRobotPosition(True)
    for value in (by_cmd, by_sensor):
        assert len(value) == 3 and all(math.isfinite(float(v)) for v in value)
    moved_cmd = relative_pose(start_cmd, Pose2D.from_list(by_cmd))
    moved_sensor = relative_pose(start_sensor, Pose2D.from_list(by_sensor))
    assert moved_cmd.x > 0.2 and moved_sensor.x > 0.2
    assert math.hypot(moved_cmd.x - moved_sensor.x, moved_cmd.y - moved_sensor.y) < POS_TOL_M
    assert abs(moved_cmd.theta - moved_sensor.theta) < ANGLE_TOL_RAD


def test_stop_move_stops_a_velocity_move(robot: Robot) -> None:
    _ready(robot)
    motion = robot.motion
    start = pose_of(motion, use_sensors=False)
    motion.move(0.08, 0.0, 0.0)
    try:
        moving = False
        for _ in range(25):
            if pose_of(motion, use_sensors=False).distance(start) > 0.005:
                moving = True
                break
        assert moving, "move() did not move the robot"
        assert motion.moveIsActive() is True
    finally:
        motion.stopMove()
    for _ in range(25):
        if not motion.moveIsActive():
            break
    assert motion.moveIsActive() is False
    assert all(abs(v) < 1e-3 for v in motion.getRobotVelocity())
    a = pose_of(motion, use_sensors=False)
    for _ in range(5):
        motion.getRobotVelocity()
    b = pose_of(motion, use_sensors=False)
    assert a.distance(b) < 1e-3 and abs(a.theta - b.theta) < 1e-3


@pytest.mark.parametrize("joint", ["HeadYaw", "HeadPitch"])
def test_head_angles_clamp_at_the_limits(robot: Robot, joint: str) -> None:
    _ready(robot)
    lo, hi, _ = JOINT_LIMITS[joint]
    for asked, limit in ((hi + 1.0, hi), (lo - 1.0, lo)):
        robot.motion.angleInterpolationWithSpeed(joint, asked, 1.0)
        (measured,) = robot.motion.getAngles(joint, True)
        (commanded,) = robot.motion.getAngles(joint, False)
        assert measured == pytest.approx(limit, abs=0.03), (asked, measured)
        assert lo - 1e-6 <= commanded <= hi + 1e-6


def test_set_angles_is_non_blocking_and_speed_bounded(robot: Robot) -> None:
    _ready(robot)
    motion = robot.motion
    motion.angleInterpolationWithSpeed("HeadYaw", -1.0, 1.0)
    fraction = 0.1
    max_speed = JOINT_LIMITS["HeadYaw"][2] * fraction
    t0 = _clock(robot)
    motion.setAngles("HeadYaw", 1.0, fraction)
    (first,) = motion.getAngles("HeadYaw", True)
    assert first < 0.5, "setAngles blocked until a far target was reached"
    previous, t_prev = -1.0, t0
    for _ in range(10):
        (angle,) = motion.getAngles("HeadYaw", True)
        now = _clock(robot)
        assert angle - previous <= max_speed * (now - t_prev) + 0.05, (angle, previous)
        previous, t_prev = angle, now
    motion.angleInterpolationWithSpeed("HeadYaw", 1.0, 1.0)
    assert motion.getAngles("HeadYaw", True)[0] == pytest.approx(1.0, abs=0.03)


def test_get_angles_expands_chains(robot: Robot) -> None:
    assert len(robot.motion.getAngles("Head", False)) == 2
    body = robot.motion.getAngles("Body", True)
    assert len(body) == len(JOINT_NAMES) and all(math.isfinite(v) for v in body)


def test_postures(robot: Robot) -> None:
    assert set(POSTURES) <= set(robot.posture.getPostureList())
    robot.motion.wakeUp()
    assert robot.motion.robotIsWakeUp() is True
    assert robot.posture.goToPosture("StandInit", 0.8) is True
    assert robot.posture.getPosture() == "StandInit"
