"""One NAOqi-semantics layer: the in-process robot and the served one answer alike.

The simulated backends' ALMotion and ALVideoDevice are the shared
``naoloc.backends.simulated`` classes; ``naoloc serve``'s fronts run those same objects on
the robot thread. Calls that only the server had before (per-subscriber settings, camera
parameters, the walk's flags, ``Frequency``) now work in process too, with the same rules.
"""

from __future__ import annotations

from typing import Any

import pytest

import naoloc
from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.motion import MotionFront
from naoloc.backends.naoqi.emulation.video import VideoFront
from naoloc.constants import WALK_SPEED, kBottomCamera, kQQVGA, kQVGA, kRGBColorSpace
from naoloc.errors import HandleError, MotionError, RobotError
from naoloc.robot import Robot
from naoloc.robot.image import frame_from_naoqi

FAKE = {"robot": {"backend": "fake"}, "world": {"odometry": {"profile": "ideal"}}}


def _direct(function: Any, *args: Any, **kwargs: Any) -> Any:
    return function(*args, **kwargs)


def _served(robot: Robot) -> tuple[MotionFront, VideoFront]:
    ctx = FrontContext(run=_direct, log=lambda _: None)
    return MotionFront(robot.motion, ctx), VideoFront(robot.video, ctx)


def test_video_settings_and_parameters_in_process_and_served() -> None:
    with naoloc.connect(FAKE) as robot:
        _, served = _served(robot)
        for video in (robot.video, served):
            video.setActiveCamera(kBottomCamera)
            handle = video.subscribe("layer", kQVGA, kRGBColorSpace, 12)  # any rate in 1-30
            assert handle in video.getSubscribers()
            assert video.getCameraIndex(handle) == kBottomCamera
            assert video.getFrameRate(handle) == 12
            assert video.setResolution(handle, kQQVGA) is True
            frame = frame_from_naoqi(video.getImageRemote(handle))
            assert frame.pixels.shape[:2] == (120, 160)
            assert video.setParameter(kBottomCamera, 0, 100) is True
            assert video.getCameraParameter(handle, 0) == 100
            assert video.unsubscribe(handle) is True
            with pytest.raises(HandleError, match="no camera subscriber"):
                video.getImageRemote(handle)
            with pytest.raises(RobotError, match="non-empty string"):
                video.subscribeCamera("", 0, kQVGA, kRGBColorSpace, 30)
            video.setAllParametersToDefaultValue(kBottomCamera)
            video.setActiveCamera(0)


def test_motion_rules_in_process_and_served() -> None:
    with naoloc.connect(FAKE) as robot:
        served, _ = _served(robot)
        for motion in (robot.motion, served):
            assert [k for k, _ in motion.getMoveConfig("Max")][:2] == ["MaxStepX", "MaxStepY"]
            motion.setMoveArmsEnabled(False, True)
            assert motion.getMoveArmsEnabled("LArm") is False
            assert motion.getMoveArmsEnabled("Arms") is False
            assert motion.getBodyNames("Head") == ["HeadYaw", "HeadPitch"]
            with pytest.raises(RobotError, match="in \\[-1, 1\\]"):
                motion.moveToward(1.5, 0.0, 0.0)
            with pytest.raises(RobotError, match="Frequency"):
                motion.moveToward(1.0, 0.0, 0.0, [["Frequency", 2.0]])
            motion.setAngles(["HeadYaw", "HeadPitch"], [0.3, 0.1], [1.0, 0.5])  # per joint
            motion.killMove()


def test_move_toward_frequency_slows_the_walk_in_process() -> None:
    with naoloc.connect(FAKE) as robot:
        robot.motion.moveToward(1.0, 0.0, 0.0)
        robot.motion.getRobotVelocity()  # one cycle at the new speed
        full = robot.motion.getRobotVelocity()[0]
        robot.motion.moveToward(1.0, 0.0, 0.0, [["Frequency", 0.0]])
        robot.motion.getRobotVelocity()
        slow = robot.motion.getRobotVelocity()[0]
        robot.motion.stopMove()
    assert full == pytest.approx(WALK_SPEED)
    assert slow == pytest.approx(WALK_SPEED * 0.42 / 0.6)


def test_move_init_at_rest_raises_in_both_backends_alike() -> None:
    with naoloc.connect({**FAKE, "world": {"sim": {"start_awake": False}}}) as robot:
        with pytest.raises(MotionError, match="not awake"):
            robot.motion.moveInit()
        assert robot.motion.moveTo(0.2, 0.0, 0.0) is False  # at rest: no walk
