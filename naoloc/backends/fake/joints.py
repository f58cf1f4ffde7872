"""Joint facts of the fake NAO: predefined postures, torso heights, limits and speeds.

Posture angles are close to the ones NAOqi's ALRobotPosture uses (radians); the cameras
are placed by the joints' forward kinematics (naoloc/robot/kinematics.py).
"""

from __future__ import annotations

from naoloc.constants import JOINT_LIMITS, JOINT_NAMES

# Max speed (rad/s) of joints NAOqi limits we do not mirror (arms, legs, hands).
DEFAULT_JOINT_SPEED = 5.0

# Posture -> (hip pitch, knee pitch, ankle pitch, shoulder pitch, shoulder roll,
#             elbow yaw, elbow roll)
_POSTURE_PARAMS: dict[str, tuple[float, float, float, float, float, float, float]] = {
    "StandInit": (-0.45, 0.70, -0.35, 1.40, 0.30, -1.39, -1.00),
    "Stand": (-0.17, 0.09, 0.09, 1.40, 0.30, -1.39, -1.00),
    "StandZero": (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    "Crouch": (-0.87, 2.11, -1.18, 1.40, 0.30, -1.39, -1.00),
    "Sit": (-1.53, 1.58, 0.09, 0.90, 0.10, -0.80, -0.50),
    "SitRelax": (-1.53, 1.58, 0.09, 1.20, 0.20, -0.60, -0.30),
    "LyingBack": (0.0, 0.0, 0.0, 1.80, 0.20, 0.0, -0.10),
    "LyingBelly": (0.0, 0.0, 0.0, -1.50, 0.20, 0.0, -0.10),
}
STANDING = ("StandInit", "Stand", "StandZero")


def posture_angles(name: str) -> dict[str, float]:
    """All 26 joint angles (rad) of a predefined posture; the head looks straight ahead."""
    hip, knee, ankle, sp, sr, ey, er = _POSTURE_PARAMS[name]
    angles = dict.fromkeys(JOINT_NAMES, 0.0)
    for side, sign in (("L", 1.0), ("R", -1.0)):
        angles[f"{side}HipPitch"] = hip
        angles[f"{side}KneePitch"] = knee
        angles[f"{side}AnklePitch"] = ankle
        angles[f"{side}ShoulderPitch"] = sp
        angles[f"{side}ShoulderRoll"] = sign * sr
        angles[f"{side}ElbowYaw"] = sign * ey
        angles[f"{side}ElbowRoll"] = sign * er
        angles[f"{side}Hand"] = 0.25
    return angles


def posture_names() -> list[str]:
    """Names of the predefined postures."""
    return list(_POSTURE_PARAMS)


def joint_limits(name: str) -> tuple[float, float, float]:
    """``(min rad, max rad, max speed rad/s)`` of a joint; unlimited range for non-head joints."""
    return JOINT_LIMITS.get(name, (-4.0, 4.0, DEFAULT_JOINT_SPEED))
