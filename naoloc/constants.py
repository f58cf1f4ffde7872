"""NAOqi constants in one place: frames, cameras, resolutions, colorspaces, joints.

Values follow the NAOqi 2.x API reference of ALMotion, ALVideoDevice and ALRobotPosture.
"""

from __future__ import annotations

import math
from typing import Final

# ALMotion frames.
FRAME_TORSO: Final = 0
FRAME_WORLD: Final = 1
FRAME_ROBOT: Final = 2

# ALVideoDevice camera indices.
kTopCamera: Final = 0  # noqa: N816 - NAOqi name
kBottomCamera: Final = 1  # noqa: N816
kDepthCamera: Final = 2  # noqa: N816

# ALVideoDevice resolutions: id -> (width, height) in pixels.
kQQQQVGA: Final = 8  # noqa: N816
kQQQVGA: Final = 7  # noqa: N816
kQQVGA: Final = 0  # noqa: N816
kQVGA: Final = 1  # noqa: N816
kVGA: Final = 2  # noqa: N816
k4VGA: Final = 3  # noqa: N816
k16VGA: Final = 4  # noqa: N816
RESOLUTIONS: Final[dict[int, tuple[int, int]]] = {
    kQQQQVGA: (40, 30),
    kQQQVGA: (80, 60),
    kQQVGA: (160, 120),
    kQVGA: (320, 240),
    kVGA: (640, 480),
    k4VGA: (1280, 960),
    k16VGA: (2560, 1920),
}
RESOLUTION_NAMES: Final[dict[int, str]] = {
    kQQQQVGA: "kQQQQVGA",
    kQQQVGA: "kQQQVGA",
    kQQVGA: "kQQVGA",
    kQVGA: "kQVGA",
    kVGA: "kVGA",
    k4VGA: "k4VGA",
    k16VGA: "k16VGA",
}

# ALVideoDevice colorspaces: id -> layers (bytes per pixel).
kYuvColorSpace: Final = 0  # noqa: N816 - luma only
kYUV422ColorSpace: Final = 9  # noqa: N816
kYUVColorSpace: Final = 10  # noqa: N816
kRGBColorSpace: Final = 11  # noqa: N816
kHSVColorSpace: Final = 12  # noqa: N816
kBGRColorSpace: Final = 13  # noqa: N816
COLORSPACE_LAYERS: Final[dict[int, int]] = {
    kYuvColorSpace: 1,
    kYUV422ColorSpace: 2,
    kYUVColorSpace: 3,
    kRGBColorSpace: 3,
    kHSVColorSpace: 3,
    kBGRColorSpace: 3,
}
COLORSPACE_NAMES: Final[dict[int, str]] = {
    kYuvColorSpace: "kYuv",
    kYUV422ColorSpace: "kYUV422",
    kYUVColorSpace: "kYUV",
    kRGBColorSpace: "kRGB",
    kHSVColorSpace: "kHSV",
    kBGRColorSpace: "kBGR",
}
CAMERA_FPS: Final = (5, 10, 15, 30)

# Camera field of view in radians (horizontal, vertical).
FOV_V5: Final = (math.radians(60.9), math.radians(47.6))
FOV_V6: Final = (math.radians(56.3), math.radians(43.7))

# Camera poses in the head frame (HeadPitch joint), NAO V4/V5 head:
# (x, y, z) in m, pitch in rad (down is positive).
TOP_CAMERA_IN_HEAD: Final = ((0.05871, 0.0, 0.06364), math.radians(1.2))
BOTTOM_CAMERA_IN_HEAD: Final = ((0.05071, 0.0, 0.01774), math.radians(39.7))
NECK_OFFSET_Z: Final = 0.1265  # m, torso to HeadYaw

# Walk limits: default, min, max.
MAX_STEP_X: Final = (0.040, 0.001, 0.080)  # m
MAX_STEP_Y: Final = (0.140, 0.101, 0.160)  # m
MAX_STEP_THETA: Final = (0.349, 0.001, 0.524)  # rad
STEP_FREQUENCY_HZ: Final = 2.0  # steps per second, at most
WALK_SPEED: Final = 0.1  # m/s, typical forward speed of a NAO
WALK_SPEED_Y: Final = 0.07  # m/s, sideways
WALK_SPEED_THETA: Final = 0.5  # rad/s, turning in place
MOTION_CYCLE_S: Final = 0.02  # ALMotion runs at 50 Hz

# Joint limits (rad) and maximum speeds (rad/s) for the head, as NAOqi reports them.
JOINT_LIMITS: Final[dict[str, tuple[float, float, float]]] = {
    "HeadYaw": (-2.0857, 2.0857, 8.26797),
    "HeadPitch": (-0.6720, 0.5149, 7.19407),
}

# The 26 joint names NAOqi lists for a NAO V5/V6 body: 25 degrees of freedom, because
# LHipYawPitch and RHipYawPitch share one motor.
JOINT_NAMES: Final = (
    "HeadYaw", "HeadPitch",
    "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll", "LWristYaw", "LHand",
    "LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll",
    "RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll",
    "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw", "RHand",
)  # fmt: skip
CHAINS: Final[dict[str, tuple[str, ...]]] = {
    "Head": ("HeadYaw", "HeadPitch"),
    "LArm": ("LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll", "LWristYaw", "LHand"),
    "RArm": ("RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll", "RWristYaw", "RHand"),
    "LLeg": ("LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch", "LAnkleRoll"),
    "RLeg": ("RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch", "RAnkleRoll"),
    "Body": JOINT_NAMES,
}

POSTURES: Final = (
    "Crouch",
    "LyingBack",
    "LyingBelly",
    "Sit",
    "SitRelax",
    "Stand",
    "StandInit",
    "StandZero",
)
