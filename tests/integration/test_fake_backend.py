"""The fake backend: determinism, drift, walls, NAOqi rest semantics, camera, acceptance."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from typing import Any

import cv2
import numpy as np
import pytest

import naoloc
from naoloc.backends.simulated.sway import SETTLE_TIME_S
from naoloc.constants import FRAME_ROBOT, kQVGA, kRGBColorSpace, kTopCamera
from naoloc.errors import HandleError, MotionError, RobotError
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.robot import Robot, SimControl, pose_of
from naoloc.robot.image import frame_from_naoqi

NO_DRIFT = {"profile": "ideal"}


def _robot(world: dict[str, Any] | None = None) -> Robot:
    return naoloc.connect({"robot": {"backend": "fake"}, "world": world or {}})


def _sim(robot: Robot) -> SimControl:
    assert robot.sim is not None
    return robot.sim


def _stand(robot: Robot) -> None:
    robot.motion.wakeUp()
    robot.posture.goToPosture("StandInit", 1.0)


def _grab(robot: Robot, resolution: int = kQVGA) -> np.ndarray:
    handle = robot.video.subscribeCamera("test", kTopCamera, resolution, kRGBColorSpace, 30)
    try:
        return frame_from_naoqi(robot.video.getImageRemote(handle)).pixels.copy()
    finally:
        robot.video.unsubscribe(handle)


def _session(world: dict[str, Any]) -> tuple[list[np.ndarray], list[list[float]]]:
    """A fixed script: frames and sensor odometry along a short walk."""
    frames, odometry = [], []
    with _robot(world) as robot:
        _stand(robot)
        for target in ((0.6, 0.1, 0.4), (0.3, -0.2, -1.0), (0.0, 0.0, 2.0)):
            robot.motion.setAngles("HeadYaw", 0.5, 0.3)
            assert robot.motion.moveTo(*target) is True
            frames.append(_grab(robot))
            odometry.append(robot.motion.getRobotPosition(True))
    return frames, odometry


def test_same_seeds_give_the_same_frames_and_odometry() -> None:
    world = {"room": {"seed": 3}, "odometry": {"seed": 5}, "camera_realism": {"noise_std": 3.0}}
    frames_a, odo_a = _session(world)
    frames_b, odo_b = _session(world)
    assert odo_a == odo_b
    for a, b in zip(frames_a, frames_b, strict=True):
        assert np.array_equal(a, b)
    frames_c, odo_c = _session({**world, "room": {"seed": 4}, "odometry": {"seed": 6}})
    assert odo_c != odo_a
    assert not np.array_equal(frames_c[0], frames_a[0])


def _square_walk(world: dict[str, Any]) -> tuple[Pose2D, Pose2D, Pose2D]:
    """Walk 2 m out, turn back, walk 2 m home; return (commanded, sensor, true) motion."""
    with _robot(world) as robot:
        _stand(robot)
        start = Pose2D(*_sim(robot).true_pose())
        for target in ((2.0, 0.0, 0.0), (0.0, 0.0, math.pi), (2.0, 0.0, 0.0)):
            assert robot.motion.moveTo(*target) is True
        truth = relative_pose(start, Pose2D(*_sim(robot).true_pose()))
        return pose_of(robot.motion, False), pose_of(robot.motion, True), truth


def test_walk_is_open_loop_on_odometry_and_strays_only_with_the_nao_profile() -> None:
    by_cmd, by_sensor, truth = _square_walk({"odometry": NO_DRIFT})
    assert by_cmd.distance(by_sensor) < 1e-9 and abs(by_cmd.theta - by_sensor.theta) < 1e-9
    assert truth.distance(by_cmd) < 1e-9 and abs(modulo2PI(truth.theta - by_cmd.theta)) < 1e-9
    by_cmd, by_sensor, truth = _square_walk({"odometry": {"seed": 1}})  # the default: nao
    assert by_cmd.distance(Pose2D()) < 1e-6  # the commands reach the target exactly...
    assert by_cmd.distance(by_sensor) < 0.02  # ...the sensors nearly (joint noise)...
    assert 0.02 < truth.distance(by_sensor) < 1.5  # ...and the body does not
    assert 0.002 < abs(modulo2PI(truth.theta - by_sensor.theta)) < 0.5


def test_odometry_error_terms_act_as_documented() -> None:
    scale = {"profile": "ideal", "scale_error": 0.1}
    with _robot({"odometry": scale}) as robot:
        _stand(robot)
        start = Pose2D(*_sim(robot).true_pose())
        robot.motion.moveTo(1.0, 0.0, 0.0)
        x, y, _ = robot.motion.getRobotPosition(True)
        assert x == pytest.approx(1.0, abs=1e-9) and y == pytest.approx(0.0, abs=1e-9)
        moved = relative_pose(start, Pose2D(*_sim(robot).true_pose()))
        assert moved.x == pytest.approx(1.0 / 1.1, abs=1e-9)  # odometry reads 10 % long
    turn = {"profile": "ideal", "turn_scale_error": -0.2}
    with _robot({"odometry": turn}) as robot:
        _stand(robot)
        robot.motion.moveTo(0.0, 0.0, 1.0)
        assert _sim(robot).true_pose()[2] == pytest.approx(1.0 / 0.8, abs=1e-9)
    bias = {"profile": "ideal", "heading_bias_rad_per_m": 0.02}
    with _robot({"odometry": bias}) as robot:
        _stand(robot)
        robot.motion.moveTo(1.5, 0.0, 0.0)
        assert robot.motion.getRobotPosition(True)[2] == pytest.approx(0.0, abs=1e-12)
        assert _sim(robot).true_pose()[2] == pytest.approx(-0.03, abs=1e-6)


def test_walls_block_walking() -> None:
    # About walls: exact odometry (profile ideal) so the true stop is easy to check.
    with _robot({"start_pose": [1.0, 3.0, 0.0], "odometry": NO_DRIFT}) as robot:
        _stand(robot)
        assert robot.motion.moveTo(6.0, 0.0, 0.0) is False
        x, y, _ = _sim(robot).true_pose()
        assert 5.7 < x <= 6.0 - 0.15 and y == pytest.approx(3.0, abs=1e-6)
        # The blocked step still counts in the odometry (the feet slip), one cycle's worth.
        counted = robot.motion.getRobotPosition(False)[0] - (x - 1.0)
        assert 0.0 < counted <= 0.1 * 0.02 + 1e-9
        assert robot.motion.moveIsActive() is False
        # A velocity walk into the wall stops by itself, too.
        robot.motion.moveTo(-0.5, 0.0, 0.0)
        robot.motion.move(0.1, 0.0, 0.0)
        for _ in range(500):
            if not robot.motion.moveIsActive():
                break
        assert robot.motion.moveIsActive() is False
        assert _sim(robot).true_pose()[0] <= 6.0 - 0.15
        assert robot.motion.getRobotVelocity() == [0.0, 0.0, 0.0]


def test_starts_standing_awake_by_default() -> None:
    with _robot() as robot:
        assert robot.motion.robotIsWakeUp() is True
        assert robot.posture.getPosture() == "StandInit"
        assert robot.motion.moveTo(0.3, 0.0, 0.0) is True


def test_robot_at_rest_does_not_walk_and_joints_hold() -> None:
    with _robot(world={"sim": {"start_awake": False}}) as robot:
        assert robot.motion.robotIsWakeUp() is False
        assert robot.posture.getPosture() == "Crouch"
        assert robot.motion.moveTo(0.5, 0.0, 0.0) is False
        robot.motion.move(0.1, 0.0, 0.0)
        assert robot.motion.moveIsActive() is False
        assert robot.motion.getRobotPosition(False) == [0.0, 0.0, 0.0]
        robot.motion.angleInterpolationWithSpeed("HeadYaw", 1.0, 1.0)
        assert robot.motion.getAngles("HeadYaw", False)[0] == pytest.approx(1.0)
        assert robot.motion.getAngles("HeadYaw", True)[0] == pytest.approx(0.0)
        robot.motion.wakeUp()
        assert robot.motion.robotIsWakeUp() is True
        assert robot.motion.getAngles("HeadYaw", True)[0] == pytest.approx(1.0)
        assert robot.motion.moveTo(0.2, 0.0, 0.0) is True
        assert robot.posture.getPosture() == "StandInit"  # walking takes StandInit first
        robot.motion.rest()
        assert robot.motion.robotIsWakeUp() is False
        assert robot.posture.getPosture() == "Crouch"


def test_walk_respects_nao_speed_limits_and_time() -> None:
    with _robot() as robot:
        _stand(robot)
        t0 = _sim(robot).sim_time()
        robot.motion.moveTo(0.5, 0.0, 0.0)
        # Walking time plus the body settling (moveTo returns with the sway died out).
        assert _sim(robot).sim_time() - t0 == pytest.approx(0.5 / 0.1 + SETTLE_TIME_S, abs=0.1)
        robot.motion.move(1.0, 0.0, 5.0)  # clipped to NAO's walk speeds
        vx, vy, wz = robot.motion.getRobotVelocity()
        assert vx == pytest.approx(0.1) and vy == 0.0 and wz == pytest.approx(0.5)
        assert robot.motion.getNextRobotPosition() != robot.motion.getRobotPosition(False)
        with pytest.raises(MotionError, match="move"):
            robot.motion.waitUntilMoveIsFinished()
        robot.motion.stopMove()
        slow: Any = robot.motion.moveTo(0.2, 0.0, 0.0, _async=True)
        assert slow.isFinished() is False
        assert robot.motion.moveIsActive() is True
        robot.motion.waitUntilMoveIsFinished()
        assert slow.isFinished() and slow.value() is True


def test_move_to_control_points_and_move_config() -> None:
    with _robot({"start_pose": [3.0, 3.0, 0.0]}) as robot:
        _stand(robot)
        start = pose_of(robot.motion, False)
        assert robot.motion.moveTo([[0.3, 0.0, 0.0], [0.3, 0.3, math.pi / 2]]) is True
        moved = relative_pose(start, pose_of(robot.motion, False))
        assert (moved.x, moved.y, moved.theta) == pytest.approx((0.3, 0.3, math.pi / 2))
        t0 = _sim(robot).sim_time()
        assert robot.motion.moveTo(0.2, 0.0, 0.0, [["MaxStepX", 0.02]]) is True
        assert _sim(robot).sim_time() - t0 == pytest.approx(0.2 / 0.05 + SETTLE_TIME_S, abs=0.1)
        with pytest.raises(RobotError, match="moveConfig"):
            robot.motion.moveTo(0.2, 0.0, 0.0, [["NoSuchThing", 1.0]])
        with pytest.raises(RobotError, match="moveTo"):
            robot.motion.moveTo("far")


def test_camera_follows_the_head_and_the_body() -> None:
    # About the camera: exact odometry, so the body's quarter turn is exact; StandZero, whose
    # upright torso makes a head turn and a body turn give the same view (in StandInit the
    # torso's forward lean becomes a roll of the image when the head looks sideways).
    with _robot({"start_pose": [3.0, 3.0, 0.0], "odometry": NO_DRIFT}) as robot:
        _stand(robot)
        robot.motion.angleInterpolationWithSpeed("HeadYaw", math.pi / 2, 1.0)
        roll = robot.motion.getPosition("CameraTop", FRAME_ROBOT, True)[3]
        assert roll == pytest.approx(0.1, abs=0.01)  # StandInit: the lean, seen sideways
        robot.motion.angleInterpolationWithSpeed("HeadYaw", 0.0, 1.0)
        robot.posture.goToPosture("StandZero", 1.0)
        ahead = _grab(robot)
        robot.motion.angleInterpolationWithSpeed("HeadYaw", math.pi / 2, 1.0)
        left_by_head = _grab(robot)
        robot.motion.angleInterpolationWithSpeed("HeadYaw", 0.0, 1.0)
        robot.motion.moveTo(0.0, 0.0, math.pi / 2)
        left_by_body = _grab(robot)
    assert not np.array_equal(ahead, left_by_head)
    # The same view whether the head or the body turned (the camera only moves a few cm).
    diff = np.abs(left_by_head.astype(int) - left_by_body.astype(int)).mean()
    assert diff < np.abs(ahead.astype(int) - left_by_body.astype(int)).mean() / 2


def test_camera_errors() -> None:
    with _robot() as robot:
        with pytest.raises(RobotError, match="camera index"):
            robot.video.subscribeCamera("x", 2, kQVGA, kRGBColorSpace, 30)
        with pytest.raises(RobotError, match="fps"):
            robot.video.subscribeCamera("x", 0, kQVGA, kRGBColorSpace, 31)  # NAOqi: 1-30
        with pytest.raises(HandleError, match="'nope'"):
            robot.video.getResolution("nope")


def test_closed_robot_raises_robot_is_closed() -> None:
    robot = _robot()
    robot.close()
    robot.close()
    for call in (
        lambda: robot.motion.moveTo(0.1, 0.0, 0.0),
        lambda: robot.video.subscribeCamera("x", 0, kQVGA, kRGBColorSpace, 30),
        lambda: robot.posture.getPosture(),
        lambda: _sim(robot).true_pose(),
    ):
        with pytest.raises(RobotError, match="robot is closed"):
            call()


def test_a_wall_seen_from_one_metre_has_at_least_100_akaze_keypoints() -> None:
    akaze = cv2.AKAZE_create()  # type: ignore[attr-defined]
    counts = []
    with _robot({"room": {"style": "posters"}}) as robot:  # posters in the camera's band
        _stand(robot)
        sx, sy = _sim(robot).room_size()
        for along in np.linspace(1.0, 5.0, 5):
            for x, y, theta in (
                (along, 1.0, -math.pi / 2),
                (sx - 1.0, along, 0.0),
                (along, sy - 1.0, math.pi / 2),
                (1.0, along, math.pi),
            ):
                _sim(robot).teleport(x, y, theta)
                gray = cv2.cvtColor(_grab(robot), cv2.COLOR_RGB2GRAY)
                counts.append(len(akaze.detect(gray)))
    assert np.median(counts) >= 150, counts
    assert np.mean(np.array(counts) >= 100) >= 0.8, counts


def test_views_of_different_wall_places_differ() -> None:
    with _robot({"room": {"style": "posters"}}) as robot:  # home walls are blank below 0.95 m
        _stand(robot)
        views = []
        for x in (1.5, 3.0, 4.5):
            _sim(robot).teleport(x, 1.0, -math.pi / 2)
            views.append(cv2.cvtColor(_grab(robot), cv2.COLOR_RGB2GRAY).astype(float))
    for i in range(3):
        for j in range(i + 1, 3):
            assert np.abs(views[i] - views[j]).mean() > 15.0


ACCEPTANCE = r"""
import json, sys
import naoloc
with naoloc.connect({"robot": {"backend": "fake"}}) as robot:
    handle = robot.video.subscribeCamera("acceptance", 0, 1, 11, 30)
    frame = naoloc.frame_from_naoqi(robot.video.getImageRemote(handle))
    reached = robot.motion.moveTo(0.5, 0.0, 0.0)
    x, y, theta = robot.motion.getRobotPosition(False)
    truth = robot.sim.true_pose()
heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("mujoco", "qi", "zmq"))
print(json.dumps({"shape": list(frame.pixels.shape), "reached": reached, "odometry": [x, y, theta],
                  "truth": list(truth), "heavy": heavy}))
"""


def test_issue_acceptance_in_a_fresh_interpreter() -> None:
    out = subprocess.run(
        [sys.executable, "-c", ACCEPTANCE], capture_output=True, text=True, timeout=120, check=True
    )
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["shape"] == [240, 320, 3]
    assert result["reached"] is True
    x, y, _ = result["odometry"]
    assert math.hypot(x - 0.5, y) < 0.05
    tx, ty, _ = result["truth"]
    assert math.hypot(tx - 1.5, ty - 1.0) < 0.05  # default start pose (1, 1, 0), room frame
    assert result["heavy"] == []
