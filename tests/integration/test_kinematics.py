"""Forward kinematics, ALMotion getPosition/getTransform, true camera pose and walk sway."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import naoloc
from naoloc.constants import FRAME_ROBOT, FRAME_TORSO, FRAME_WORLD
from naoloc.errors import RobotError
from naoloc.robot import kinematics as kin
from naoloc.robot.keyframe import standinit_angles


def test_standinit_puts_the_top_camera_where_a_nao_has_it() -> None:
    t = kin.transform("CameraTop", FRAME_ROBOT, standinit_angles())
    x, y, z, wx, wy, wz = kin.position6d(t)
    assert [x, y, z] == pytest.approx([0.087, 0.0, 0.504], abs=0.002)
    assert math.degrees(wy) == pytest.approx(6.9, abs=0.1) and abs(wx) < 1e-9 and abs(wz) < 1e-9
    # Upright legs (StandZero): the camera sits above the torso, 1.2 deg down.
    upright = kin.position6d(kin.transform("CameraTop", FRAME_ROBOT, {}))
    assert upright[0] == pytest.approx(0.05871) and math.degrees(upright[4]) == pytest.approx(1.2)
    assert kin.position6d(kin.transform_from_6d([0.1, 0.2, 0.3, 0.1, -0.2, 0.3])) == pytest.approx(
        [0.1, 0.2, 0.3, 0.1, -0.2, 0.3]
    )
    with pytest.raises(RobotError):
        kin.transform("Tail", FRAME_ROBOT, {})
    with pytest.raises(RobotError):
        kin.transform("Head", 7, {})


def _backends() -> list[str]:
    found = ["fake"]
    if importlib.util.find_spec("mujoco") is not None:
        found.append("mujoco")
    return found


@pytest.mark.parametrize("backend", _backends())
def test_get_position_agrees_with_the_true_camera_pose(backend: str) -> None:
    cfg = {"robot": {"backend": backend}, "world": {"start_pose": [1.5, 2.0, 0.7]}}
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        robot.posture.goToPosture("StandInit", 1.0)
        for yaw, pitch in ((0.0, 0.0), (0.8, -0.2), (-1.2, 0.1)):
            robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [yaw, pitch], 1.0)
            for index, name in ((0, "CameraTop"), (1, "CameraBottom")):
                got = kin.transform_from_6d(robot.motion.getPosition(name, FRAME_ROBOT, True))
                true_room = kin.transform_from_6d(robot.sim.true_camera_pose(index))
                true = np.linalg.inv(kin.world_to_robot(robot.sim.true_pose())) @ true_room
                assert np.abs(got[:3, 3] - true[:3, 3]).max() < 0.005
                cos = (np.trace(got[:3, :3].T @ true[:3, :3]) - 1) / 2
                assert math.degrees(math.acos(min(1.0, cos))) < 0.5
        robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [0.0, 0.0], 1.0)
        wy = robot.motion.getPosition("CameraTop", FRAME_ROBOT, True)[4]
        assert 2.0 <= math.degrees(wy) <= 12.0  # StandInit leans: the camera looks down
        flat = robot.motion.getTransform("Head", FRAME_TORSO, False)
        assert len(flat) == 16 and flat[15] == 1.0 and flat[11] == pytest.approx(0.1265)
        world = robot.motion.getPosition("Torso", FRAME_WORLD, True)
        odo = robot.motion.getRobotPosition(True)
        assert world[5] == pytest.approx(odo[2], abs=1e-4)


@pytest.mark.parametrize("backend", _backends())
def test_the_camera_sways_while_walking_and_settles(backend: str) -> None:
    cfg = {"robot": {"backend": backend}, "world": {"room": {"furniture": False}}}
    with naoloc.connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        lateral, roll = [], []
        robot.motion.move(0.1, 0.0, 0.0)
        try:
            for k in range(150):
                robot.motion.getRobotVelocity()  # one 20 ms cycle
                room = kin.transform_from_6d(sim.true_camera_pose(0))
                local = kin.position6d(np.linalg.inv(kin.world_to_robot(sim.true_pose())) @ room)
                if k >= 50:
                    lateral.append(local[1])
                    roll.append(local[3])
        finally:
            robot.motion.stopMove()
        assert max(lateral) - min(lateral) >= 0.01 or math.degrees(max(roll) - min(roll)) >= 1.0
        for _ in range(50):
            robot.motion.getRobotVelocity()
        room = kin.transform_from_6d(sim.true_camera_pose(0))
        still = kin.position6d(np.linalg.inv(kin.world_to_robot(sim.true_pose())) @ room)
        assert abs(still[1]) < 1e-3 and abs(still[3]) < 1e-3  # settled
    quiet = {**cfg, "world": {**cfg["world"], "sim": {"camera_sway": False}}}
    with naoloc.connect(quiet) as robot:
        assert robot.sim is not None
        robot.motion.move(0.1, 0.0, 0.0)
        try:
            for _ in range(30):
                robot.motion.getRobotVelocity()
            assert abs(robot.sim.true_camera_pose(0)[3]) < 1e-6
        finally:
            robot.motion.stopMove()


def test_keyframes_keep_the_camera_pose_the_robot_reported(tmp_path: Path) -> None:
    from naoloc.data.dataset import DatasetWriter, read_dataset
    from naoloc.geometry import Pose2D
    from naoloc.robot.keyframe import CameraInfo, Keyframe, camera_in_robot

    reported = kin.transform("CameraTop", FRAME_ROBOT, {**standinit_angles(0.4, -0.1)})
    reported[2, 3] += 0.01  # a robot whose camera sits 1 cm higher than the nominal model
    image = np.kron(np.arange(12 * 16, dtype=np.uint8).reshape(12, 16, 1), np.ones((20, 20, 3)))
    kw = {"image": image.astype(np.uint8), "pose": Pose2D(), "head_yaw": 0.4, "head_pitch": -0.1,
          "camera": CameraInfo(320, 240, 1.06, 0.83, 0)}  # fmt: skip
    with_pose = Keyframe(**kw, camera_pose=tuple(reported.reshape(-1)))  # type: ignore[arg-type]
    without = Keyframe(**kw)  # type: ignore[arg-type]
    np.testing.assert_allclose(with_pose.camera_matrix(), kin.optical_from_camera(reported))
    np.testing.assert_allclose(without.camera_matrix(), camera_in_robot(0.4, -0.1, 0))
    path = tmp_path / "s.mcap"
    with DatasetWriter(path, config={}, meta={}) as writer:
        writer.write(with_pose)
        writer.write(without)
    back = read_dataset(path).keyframes
    assert back[0].camera_pose == pytest.approx(with_pose.camera_pose)
    assert back[1].camera_pose is None


class _Counting:
    """ALMotion with a count of the remote calls made through it."""

    def __init__(self, inner: object) -> None:
        self.inner, self.calls = inner, 0

    def __getattr__(self, name: str) -> object:
        attr = getattr(self.inner, name)
        if not callable(attr):
            return attr

        def call(*args: object, **kwargs: object) -> object:
            self.calls += 1
            return attr(*args, **kwargs)

        return call


@pytest.mark.parametrize("backend", _backends())
def test_a_still_picture_reads_the_state_once_and_keeps_its_pose(backend: str) -> None:
    from naoloc.behaviours.wall_follow import FloorEye
    from naoloc.config import CameraConfig
    from naoloc.robot.camera import Camera

    cfg = {"robot": {"backend": backend}, "world": {"start_pose": [1.5, 2.0, 0.7]}}
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        robot.posture.goToPosture("StandInit", 1.0)
        robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [0.9, -0.3], 0.6)
        counting = _Counting(robot.motion)
        robot.motion = counting  # type: ignore[assignment]
        with Camera(robot, CameraConfig()) as camera:
            counting.calls = 0
            moving, _ = camera.keyframe()
            bracketed = counting.calls
            counting.calls = 0
            still, _ = camera.keyframe(still=True)
            assert (bracketed, counting.calls) == (7, 3)  # + the image: 8 and 4 remote calls
        assert still.command_pose is None and moving.command_pose is not None
        assert still.pose == pytest.approx(moving.pose, abs=1e-3)
        assert still.head_yaw == pytest.approx(moving.head_yaw, abs=1e-3)
        assert np.allclose(still.camera_pose, moving.camera_pose, atol=1e-3)
        true_room = kin.transform_from_6d(robot.sim.true_camera_pose(0))
        true = np.linalg.inv(kin.world_to_robot(robot.sim.true_pose())) @ true_room
        got = np.asarray(still.camera_pose).reshape(4, 4)
        assert np.abs(got[:3, 3] - true[:3, 3]).max() < 0.005
        eye = FloorEye(robot, CameraConfig())
        try:
            counting.calls = 0
            view = eye.view(still=True)
            assert view is not None and counting.calls == 1
            counting.calls = 0
            moving_view = eye.view()
            assert moving_view is not None and counting.calls == 2
            assert np.allclose(view[3], moving_view[3], atol=1e-3)
        finally:
            eye.close()
