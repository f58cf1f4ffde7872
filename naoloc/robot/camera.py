"""Taking pictures with what is known about where they were taken.

:class:`Camera` subscribes once to ALVideoDevice and turns each NAOqi image into a
:class:`~naoloc.robot.keyframe.Keyframe` carrying the odometry pose (sensors and commands),
the head angles, the camera pose from ALMotion's kinematics and, on a simulator, the true
pose. :func:`look` points the head.
"""

from __future__ import annotations

import contextlib
import math

from naoloc.config import CameraConfig, Config
from naoloc.constants import FOV_V5, FOV_V6, FRAME_ROBOT, JOINT_LIMITS
from naoloc.errors import RobotError
from naoloc.geometry import Pose2D, mid_transform, midpose, relative_pose
from naoloc.robot import Robot, pose_of
from naoloc.robot.image import Frame, frame_from_naoqi
from naoloc.robot.keyframe import CameraInfo, Keyframe
from naoloc.robot.kinematics import head_pitch_limits
from naoloc.robot.lens import Lens, lens_for

# Head pitch while taking pictures, rad (negative looks up): as far up as the head goes.
# Real rooms hang their art at 1.2-1.8 m and the top camera sits at about 0.5 m, looking
# 6.9 deg down in StandInit; with the head level the band it sees from 1 m (0.07-0.95 m) is
# skirting and blank wall. Measured in the home room at 1 m from the walls (median A-KAZE
# keypoints per QVGA frame, tools/look_figures.py): pitch 0 -> 0, -0.4 -> 3, -0.67 -> 32.
# The config keys survey.head_pitch_rad and localize.head_pitch_rad default to this.
DEFAULT_HEAD_PITCH = -0.672
HEAD_SPEED = 0.3  # fraction of the maximum head joint speed

_YAW_MIN, _YAW_MAX, _ = JOINT_LIMITS["HeadYaw"]


def clamp_head(yaw: float, pitch: float) -> tuple[float, float]:
    """Clamp head angles (rad) to the joint limits, including the shell's at large yaw."""
    yaw = min(max(yaw, _YAW_MIN + 1e-3), _YAW_MAX - 1e-3)
    lo, hi = head_pitch_limits(yaw)
    return yaw, min(max(pitch, lo + 1e-3), hi - 1e-3)


def lens_of(cfg: Config) -> Lens:
    """The lens of the configured robot's cameras (``camera.lens``; ``auto``: NAO's unless
    ``world.camera_realism`` turns the simulated lens distortion off)."""
    fov = FOV_V6 if cfg.world.model == "v6" else FOV_V5
    choice = cfg.camera.lens
    distortion = cfg.world.camera_realism.lens_distortion if choice == "auto" else choice == "nao"
    return lens_for(distortion, *fov)


def look(
    robot: Robot, yaw: float, pitch: float = DEFAULT_HEAD_PITCH, speed: float = HEAD_SPEED
) -> tuple[float, float]:
    """Turn the head to ``(yaw, pitch)`` (rad, clamped to the limits); blocking.

    Args:
        robot: The robot.
        yaw: HeadYaw, rad.
        pitch: HeadPitch, rad (negative looks up).
        speed: Fraction of the head's maximum joint speed.

    Returns:
        The angles commanded after clamping.
    """
    yaw, pitch = clamp_head(yaw, pitch)
    robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [yaw, pitch], speed)
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
        """The latest image as a :class:`~naoloc.robot.image.Frame`.

        No ``releaseImage`` follows: NAOqi's releaseImage frees buffers locked by
        getImageLocal, and getImageRemote locks none (one remote call saved per picture).
        """
        return frame_from_naoqi(self.robot.video.getImageRemote(self.handle))

    def info(self, frame: Frame) -> CameraInfo:
        """The camera model of ``frame`` (size from the frame, FOV from ALVideoDevice)."""
        return CameraInfo(frame.width, frame.height, self._fov[0], self._fov[1], self.index)

    def keyframe(
        self,
        origin: Pose2D | None = None,
        command_origin: Pose2D | None = None,
        *,
        still: bool = False,
    ) -> tuple[Keyframe, Pose2D]:
        """Take a picture with the robot's pose and head angles.

        Args:
            origin: FRAME_WORLD odometry pose (sensors) of the map origin; None keeps the
                raw FRAME_WORLD pose.
            command_origin: The same from commands (getRobotPosition(False)).
            still: The robot stands and the head rests (after a blocking head move): the
                state is read once, before the image, and the command pose only with a
                ``command_origin`` (four remote calls instead of eight; each costs a
                NAO one ALMotion cycle or a network round trip).

        Returns:
            The keyframe (pose relative to ``origin``) and the raw FRAME_WORLD odometry.
        """
        motion = self.robot.motion
        name = "CameraTop" if self.index == 0 else "CameraBottom"
        # The robot moves while the picture is taken (a walk, a swinging head): the state is
        # read just before and just after the image, in mirrored order, and each value is
        # the midpoint of its two readings, which bracket the image symmetrically (one
        # ALMotion cycle each way in a simulator; on a NAO, the call's time).
        odometry0 = pose_of(motion, True)
        angles0 = motion.getAngles(["HeadYaw", "HeadPitch"], True)
        camera0 = motion.getTransform(name, FRAME_ROBOT, True)  # its own kinematics, a NAO's too
        frame = self.frame()
        truth = None
        if self.robot.sim is not None:  # the simulator's truth when the picture was taken
            truth = Pose2D.from_list(self.robot.sim.true_pose())
        if still:
            camera1, angles1, odometry1 = camera0, angles0, odometry0
        else:
            camera1 = motion.getTransform(name, FRAME_ROBOT, True)
            angles1 = motion.getAngles(["HeadYaw", "HeadPitch"], True)
            odometry1 = pose_of(motion, True)
        command = None if still and command_origin is None else pose_of(motion, False)
        odometry = midpose(odometry0, odometry1)
        yaw, pitch = (0.5 * (float(a) + float(b)) for a, b in zip(angles0, angles1, strict=True))
        if len(camera0) != 16 or len(camera1) != 16:
            raise RobotError("the robot reported a camera pose that is not 16 numbers")
        camera_pose = tuple(mid_transform(camera0, camera1))
        pose = odometry if origin is None else relative_pose(origin, odometry)
        if command_origin is not None and command is not None:
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

    def __exit__(self, *exc: object) -> None:
        self.close()


def stand(robot: Robot) -> None:
    """Wake up and take StandInit (the walk-ready posture); blocking."""
    if not robot.motion.robotIsWakeUp():
        robot.motion.wakeUp()
    robot.posture.goToPosture("StandInit", 0.5)
