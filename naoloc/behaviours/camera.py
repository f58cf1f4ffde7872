"""Taking pictures with what is known about where they were taken.

:class:`Camera` subscribes once to ALVideoDevice and turns each NAOqi image into a
:class:`~naoloc.keyframe.Keyframe` carrying the odometry pose (sensors and commands),
the head angles, the camera pose from ALMotion's kinematics and, on a simulator, the true
pose. :func:`look` points the head.
"""

from __future__ import annotations

import contextlib
import math
from types import TracebackType

from naoloc.config import CameraConfig
from naoloc.constants import FRAME_ROBOT, JOINT_LIMITS
from naoloc.errors import RobotError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.image import Frame, frame_from_naoqi
from naoloc.keyframe import CameraInfo, Keyframe
from naoloc.robot import Robot, pose_of

# Head pitch while taking pictures, rad (negative looks up): walls carry their texture above
# the camera's height, and the shell limits pitch to about -0.33 rad at +-90 degrees of yaw.
DEFAULT_HEAD_PITCH = -0.2
HEAD_SPEED = 0.3  # fraction of the maximum head joint speed

_YAW_MIN, _YAW_MAX, _ = JOINT_LIMITS["HeadYaw"]
_PITCH_MIN, _PITCH_MAX, _ = JOINT_LIMITS["HeadPitch"]


def clamp_head(yaw: float, pitch: float) -> tuple[float, float]:
    """Clamp head angles (rad) to the joint limits, including the shell's at large yaw."""
    yaw = min(max(yaw, _YAW_MIN + 1e-3), _YAW_MAX - 1e-3)
    lo, hi = _PITCH_MIN, _PITCH_MAX
    if abs(yaw) > 1.2:  # the shell: about -18.9 to +11.5 degrees at +-87.5 degrees of yaw
        lo, hi = -0.33, 0.2
    return yaw, min(max(pitch, lo), hi)


def look(robot: Robot, yaw: float, pitch: float = DEFAULT_HEAD_PITCH) -> tuple[float, float]:
    """Turn the head to ``(yaw, pitch)`` (rad, clamped to the limits); blocking.

    Returns:
        The angles commanded after clamping.
    """
    yaw, pitch = clamp_head(yaw, pitch)
    robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [yaw, pitch], HEAD_SPEED)
    return yaw, pitch


class Camera:
    """One ALVideoDevice subscription that yields keyframes.

    Args:
        robot: The robot.
        cfg: Which camera, resolution and colorspace.
        name: Subscriber name.

    Raises:
        RobotError: The subscription or an image fails.
    """

    def __init__(self, robot: Robot, cfg: CameraConfig, name: str = "naoloc") -> None:
        self.robot = robot
        self.index = cfg.index
        self.handle = robot.video.subscribeCamera(
            name, cfg.index, cfg.resolution, cfg.colorspace, cfg.fps
        )
        self._fov = (
            float(robot.video.getHorizontalFOV(cfg.index)),
            float(robot.video.getVerticalFOV(cfg.index)),
        )
        self._closed = False

    def frame(self) -> Frame:
        """The latest image as a :class:`~naoloc.image.Frame`.

        No ``releaseImage`` follows: NAOqi's releaseImage frees buffers locked by
        getImageLocal, and getImageRemote locks none (one remote call saved per picture).
        """
        return frame_from_naoqi(self.robot.video.getImageRemote(self.handle))

    def info(self, frame: Frame) -> CameraInfo:
        """The camera model of ``frame`` (size from the frame, FOV from ALVideoDevice)."""
        return CameraInfo(frame.width, frame.height, self._fov[0], self._fov[1], self.index)

    def keyframe(
        self, origin: Pose2D | None = None, command_origin: Pose2D | None = None
    ) -> tuple[Keyframe, Pose2D]:
        """Take a picture with the robot's pose and head angles.

        Args:
            origin: FRAME_WORLD odometry pose (sensors) of the map origin; None keeps the
                raw FRAME_WORLD pose.
            command_origin: The same from commands (getRobotPosition(False)).

        Returns:
            The keyframe (pose relative to ``origin``) and the raw FRAME_WORLD odometry.
        """
        motion = self.robot.motion
        frame = self.frame()
        odometry = pose_of(motion, True)
        command = pose_of(motion, False)
        yaw, pitch = (float(a) for a in motion.getAngles(["HeadYaw", "HeadPitch"], True))
        # The robot's own kinematics (a real NAO's included), never an assumed geometry.
        name = "CameraTop" if self.index == 0 else "CameraBottom"
        camera_pose = tuple(float(v) for v in motion.getTransform(name, FRAME_ROBOT, True))
        truth = None
        if self.robot.sim is not None:
            truth = Pose2D.from_list(self.robot.sim.true_pose())
        pose = odometry if origin is None else relative_pose(origin, odometry)
        if command_origin is not None:
            command = relative_pose(command_origin, command)
        if len(camera_pose) != 16 or not all(
            math.isfinite(v) for v in (*pose, yaw, pitch, *camera_pose)
        ):
            raise RobotError("the robot reported a non-finite pose, head angle or camera pose")
        keyframe = Keyframe(
            image=frame.bgr(),
            pose=pose,
            head_yaw=yaw,
            head_pitch=pitch,
            camera=self.info(frame),
            stamp=frame.stamp,
            command_pose=command,
            true_pose=truth,
            camera_pose=camera_pose,
        )
        return keyframe, odometry

    def close(self) -> None:
        """Unsubscribe (best effort). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(Exception):  # closing must not mask the real error
            self.robot.video.unsubscribe(self.handle)

    def __enter__(self) -> Camera:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def stand(robot: Robot) -> None:
    """Wake up and take StandInit (the walk-ready posture); blocking."""
    if not robot.motion.robotIsWakeUp():
        robot.motion.wakeUp()
    robot.posture.goToPosture("StandInit", 0.5)
