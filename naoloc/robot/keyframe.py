"""Value types shared by behaviours, datasets and the map: cameras and keyframes.

Frames: a keyframe's ``pose`` is the robot's FRAME_ROBOT origin in the map frame (the
odometry frame at the start of the survey: x forward, y left, theta counter-clockwise,
metres and radians). The camera's pose in FRAME_ROBOT is what the robot's own kinematics
said when the picture was taken (``ALMotion.getTransform(camera, FRAME_ROBOT, True)``,
kept in :attr:`Keyframe.camera_pose`); keyframes without it (older datasets) fall back to
the nominal StandInit kinematics of :func:`camera_in_robot`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from naoloc.constants import FOV_V5, FRAME_ROBOT
from naoloc.geometry import Pose2D
from naoloc.robot import kinematics

# NAO's StandInit leg angles (rad): the torso leans 0.1 rad forward with the feet flat.
STANDINIT_LEGS = {"HipPitch": -0.45, "KneePitch": 0.70, "AnklePitch": -0.35}


@dataclass(frozen=True, slots=True)
class CameraInfo:
    """Pinhole model of one NAO camera image.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        hfov: Horizontal field of view in radians.
        vfov: Vertical field of view in radians.
        index: NAOqi camera index (0 top, 1 bottom).
    """

    width: int = 320
    height: int = 240
    hfov: float = FOV_V5[0]
    vfov: float = FOV_V5[1]
    index: int = 0

    @property
    def fx(self) -> float:
        """Focal length along x in pixels."""
        return (self.width / 2.0) / math.tan(self.hfov / 2.0)

    @property
    def fy(self) -> float:
        """Focal length along y in pixels."""
        return (self.height / 2.0) / math.tan(self.vfov / 2.0)

    def matrix(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K (principal point at the image centre)."""
        return np.array(
            [[self.fx, 0.0, self.width / 2.0], [0.0, self.fy, self.height / 2.0], [0, 0, 1.0]]
        )

    def scaled(self, width: int, height: int) -> CameraInfo:
        """The same camera at another resolution."""
        return CameraInfo(width, height, self.hfov, self.vfov, self.index)


# Largest image side a camera model may have, pixels (NAO's largest is 2560 x 1920).
MAX_IMAGE_SIDE = 8192


def check_camera(cam: CameraInfo) -> CameraInfo:
    """``cam`` when it is a usable pinhole model, else ValueError naming the bad field.

    Width and height must be 1 to :data:`MAX_IMAGE_SIDE` pixels, both fields of view
    finite and strictly between 0 and pi radians (a zero field of view has no focal length),
    and the index 0 (top) or 1 (bottom).

    Raises:
        ValueError: One phrase naming the field and its value.
    """
    for name, side in (("width", cam.width), ("height", cam.height)):
        if not 1 <= side <= MAX_IMAGE_SIDE:
            raise ValueError(f"camera {name} is {side} px, must be 1 to {MAX_IMAGE_SIDE}")
    for name, fov in (("hfov", cam.hfov), ("vfov", cam.vfov)):
        if not (math.isfinite(fov) and 0.0 < fov < math.pi):
            raise ValueError(f"camera {name} is {fov} rad, must be between 0 and pi")
    if cam.index not in (0, 1):
        raise ValueError(f"camera index is {cam.index}, must be 0 (top) or 1 (bottom)")
    return cam


def standinit_angles(head_yaw: float = 0.0, head_pitch: float = 0.0) -> dict[str, float]:
    """Joint angles (rad) of StandInit's legs with the given head angles (rad)."""
    angles = {"HeadYaw": float(head_yaw), "HeadPitch": float(head_pitch)}
    for side in "LR":
        angles.update({f"{side}{joint}": value for joint, value in STANDINIT_LEGS.items()})
    return angles


# Height of the torso frame above the floor in StandInit (knees bent), metres, from the
# kinematics (0.3204 m). With straight legs it is 0.333 m (HipOffsetZ + Thigh + Tibia + Foot).
TORSO_HEIGHT_STANDINIT = float(kinematics.robot_to_torso(standinit_angles())[2, 3])


def camera_in_robot(head_yaw: float, head_pitch: float, index: int = 0) -> np.ndarray:
    """Nominal pose of a camera's optical frame in FRAME_ROBOT (StandInit), as a 4x4 matrix.

    The robot's own reading (:attr:`Keyframe.camera_pose`) is preferred; this is the
    forward kinematics of StandInit (its forward lean included) for keyframes without it.
    The optical frame is OpenCV's: z along the view, x to the image right, y down.

    Args:
        head_yaw: HeadYaw in radians (positive turns left).
        head_pitch: HeadPitch in radians (positive looks down).
        index: 0 top camera, 1 bottom camera.

    Returns:
        ``T`` such that ``p_robot = T @ [p_cam, 1]``.
    """
    name = "CameraTop" if index == 0 else "CameraBottom"
    t = kinematics.transform(name, FRAME_ROBOT, standinit_angles(head_yaw, head_pitch))
    return kinematics.optical_from_camera(t)


@dataclass(frozen=True, slots=True)
class Keyframe:
    """One survey or query image with what is known about where it was taken.

    Attributes:
        image: ``(h, w)`` uint8 grey or ``(h, w, 3)`` uint8 BGR pixels.
        pose: Robot pose in the map frame from odometry (getRobotPosition(True)).
        head_yaw: HeadYaw in radians when the image was taken.
        head_pitch: HeadPitch in radians when the image was taken.
        camera: The camera model of the image.
        stamp: Capture time in seconds.
        command_pose: Robot pose in the map frame from commands (getRobotPosition(False)).
        true_pose: Ground-truth pose in the room frame, when a simulator knows it.
        camera_pose: The camera's 4x4 pose in FRAME_ROBOT (NAOqi camera frame: x along the
            view), 16 floats row-major, as ``ALMotion.getTransform(camera, FRAME_ROBOT,
            True)`` gave it at capture; None when unknown.
    """

    image: np.ndarray
    pose: Pose2D
    head_yaw: float = 0.0
    head_pitch: float = 0.0
    camera: CameraInfo = CameraInfo()
    stamp: float = 0.0
    command_pose: Pose2D | None = None
    true_pose: Pose2D | None = None
    camera_pose: tuple[float, ...] | None = None

    def camera_matrix(self) -> np.ndarray:
        """The camera's optical frame (OpenCV) in FRAME_ROBOT as a 4x4 matrix.

        From the robot's own kinematics at capture (:attr:`camera_pose`), else the nominal
        StandInit kinematics for the head angles.
        """
        if self.camera_pose is None:
            return camera_in_robot(self.head_yaw, self.head_pitch, self.camera.index)
        t = np.asarray(self.camera_pose, dtype=np.float64).reshape(4, 4)
        return kinematics.optical_from_camera(t)

    def gray(self) -> np.ndarray:
        """The image as ``(h, w)`` uint8 grey."""
        if self.image.ndim == 2:
            return self.image
        import cv2

        return cv2.cvtColor(self.image, cv2.COLOR_BGR2GRAY)

    def camera_heading(self) -> float:
        """Heading of the camera's view in the map frame, radians."""
        return self.pose.theta + self.head_yaw
