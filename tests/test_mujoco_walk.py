"""MuJoCo backend: walking with NAOqi semantics, collisions, odometry, postures, time."""

from __future__ import annotations

import importlib.util
import math
from typing import Any

import pytest

if importlib.util.find_spec("mujoco") is None:
    pytest.skip("mujoco is not installed", allow_module_level=True)

from naoloc.backends.mujoco.sim import Simulation

import naoloc
from naoloc.errors import MotionError, RobotError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot import pose_of

pytestmark = pytest.mark.sim


def _sim(robot: naoloc.Robot) -> Simulation:
    assert isinstance(robot.sim, Simulation)
    return robot.sim


# The shipped paper room and rooms no config ships (other seeds and sizes).
ROOMS: list[dict[str, Any]] = [
    {"world": {"room": {"size_m": [6.0, 6.0], "seed": 0}, "start_pose": [1.0, 1.0, 0.0]}},
    {"world": {"room": {"size_m": [5.0, 4.5], "seed": 11, "posters_per_wall": 3}}},
    {"world": {"room": {"size_m": [3.2, 7.0], "seed": 23, "posters_per_wall": 2}},
     "survey": {"wall_offset_m": 0.6}},
]  # fmt: skip


def _connect(extra: dict[str, Any]) -> naoloc.Robot:
    return naoloc.connect({"robot": {"backend": "mujoco"}, **extra})


@pytest.mark.parametrize("room", ROOMS, ids=["paper", "seed11", "seed23"])
def test_move_to_one_metre_and_toward_a_wall(room: dict[str, Any]) -> None:
    with _connect(room) as robot:
        sim, motion = _sim(robot), robot.motion
        motion.wakeUp()
        start = Pose2D(*sim.true_pose())
        assert motion.getRobotPosition(False) == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)
        assert motion.moveTo(1.0, 0.0, 0.0) is True
        moved = relative_pose(start, Pose2D(*sim.true_pose()))
        assert moved.x == pytest.approx(1.0, abs=0.05)
        assert abs(moved.y) < 0.02 and abs(moved.theta) < 0.02
        assert motion.getRobotPosition(False) == pytest.approx([1.0, 0.0, 0.0], abs=0.01)
        # Toward the wall: the walk fails or stops short; the robot stays in the room.
        assert motion.moveTo(20.0, 0.0, 0.0) is False
        x, y, _ = sim.true_pose()
        sx, sy = sim.room_size()
        assert 0.1 < x < sx - 0.1 and 0.1 < y < sy - 0.1
        assert sim.warnings() == {}


def test_walking_into_furniture_is_blocked() -> None:
    room = ROOMS[0]
    with _connect(room) as robot:
        sim = _sim(robot)
        table = next(f for f in sim.layout.furniture if f.kind == "table")
        x0, y0, _, y1 = table.rect
        cy = (y0 + y1) / 2
        sim.teleport(x0 - 0.5, cy, 0.0)  # facing the table, 0.5 m before its edge
        assert robot.motion.moveTo(1.5, 0.0, 0.0) is False
        x, _, _ = sim.true_pose()
        assert x < x0 - 0.1  # the body (radius 0.15 m) stopped at the table's footprint
        assert not sim.is_free(x0 + 0.1, cy, 0.15)


def test_velocity_walk_stop_and_wait_semantics() -> None:
    with _connect(ROOMS[1]) as robot:
        motion, sim = robot.motion, _sim(robot)
        t0 = sim.sim_time()
        motion.moveToward(1.0, 0.0, 0.0)
        assert motion.moveIsActive() is True
        with pytest.raises(MotionError):
            motion.waitUntilMoveIsFinished()
        for _ in range(100):
            motion.getRobotVelocity()
        assert sim.sim_time() - t0 == pytest.approx(102 * 0.02, abs=1e-6)  # one cycle per call
        dist = pose_of(motion, False).x
        assert dist == pytest.approx(0.1 * 102 * 0.02, rel=0.05)
        motion.stopMove()
        assert motion.moveIsActive() is False
        assert motion.getRobotVelocity() == [0.0, 0.0, 0.0]
        # Control points, each in FRAME_ROBOT at the call: an L-shaped path.
        before = Pose2D(*sim.true_pose())
        assert motion.moveTo([[0.3, 0.0, 0.0], [0.3, 0.3, math.pi / 2]]) is True
        moved = relative_pose(before, Pose2D(*sim.true_pose()))
        assert [moved.x, moved.y, moved.theta] == pytest.approx([0.3, 0.3, math.pi / 2], abs=0.02)
        with pytest.raises(RobotError):
            motion.moveTo("far")


def test_sensor_odometry_drift_model_is_seeded_and_configurable() -> None:
    drift = {
        "scale_error": 0.1,
        "heading_bias_rad_per_m": 0.0,
        "random_walk_m_per_sqrt_m": 0.0,
        "heading_random_walk_rad_per_sqrt_rad": 0.0,
    }
    room = {**ROOMS[1], "world": {**ROOMS[1]["world"], "odometry": drift}}
    with _connect(room) as robot:
        assert robot.motion.moveTo(1.0, 0.0, 0.0) is True
        x, _, _ = robot.motion.getRobotPosition(True)
        assert x == pytest.approx(1.1, abs=0.01)  # 10 % scale error
    noisy = {**ROOMS[1], "world": {**ROOMS[1]["world"], "odometry": {"seed": 4}}}
    runs = []
    for _ in range(2):
        with _connect(noisy) as robot:
            assert robot.sim is not None
            start = Pose2D(*robot.sim.true_pose())
            robot.motion.moveTo(0.6, 0.0, 0.5)
            moved = relative_pose(start, Pose2D(*robot.sim.true_pose()))
            runs.append((robot.motion.getRobotPosition(True), moved))
    assert runs[0] == runs[1]  # same seed, same run
    sensor, moved = runs[0]
    assert sensor != pytest.approx([moved.x, moved.y, moved.theta], abs=1e-6)  # it drifts
    assert sensor == pytest.approx([moved.x, moved.y, moved.theta], abs=0.05)  # a little


def test_postures_stiffness_and_rest() -> None:
    with _connect(ROOMS[1]) as robot:
        motion, posture, sim = robot.motion, robot.posture, _sim(robot)
        assert motion.robotIsWakeUp() is True
        head_z = sim.data.camera("CameraTop").xpos[2]
        motion.rest()
        assert motion.robotIsWakeUp() is False
        assert posture.getPosture() == "Crouch"
        sim.prepare_render()
        assert sim.data.camera("CameraTop").xpos[2] < head_z - 0.05  # crouching is lower
        assert motion.moveTo(0.5, 0.0, 0.0) is False  # asleep: the walk does not start
        assert posture.goToPosture("StandInit", 1.0) is False
        motion.wakeUp()
        assert posture.getPosture() == "StandInit"
        assert motion.getAngles("LKneePitch", True)[0] == pytest.approx(0.716, abs=0.01)
        # The head shell limits HeadPitch at large HeadYaw (NAOqi: -18.9..11.5 deg at 87.5 deg).
        motion.angleInterpolationWithSpeed("Head", [math.radians(87.49), 0.5], 1.0)
        yaw, pitch = motion.getAngles("Head", True)
        assert math.degrees(yaw) == pytest.approx(87.49, abs=0.5)
        assert math.degrees(pitch) == pytest.approx(11.46, abs=0.5)
        motion.angleInterpolationWithSpeed("Head", [0.0, 0.5], 1.0)
        assert motion.getAngles("HeadPitch", True)[0] == pytest.approx(0.5, abs=0.01)
        motion.setStiffnesses("Head", 0.0)
        motion.angleInterpolationWithSpeed("HeadYaw", 0.5, 1.0)
        assert abs(motion.getAngles("HeadYaw", True)[0]) < 0.01  # limp joints do not move
        with pytest.raises(RobotError):
            posture.goToPosture("Handstand", 0.5)
        with pytest.raises(RobotError):
            sim.teleport(0.05, 1.0, 0.0)  # into the wall
