"""Facts about the NAO model that the backend needs besides the MJCF: postures, head limits.

Joint limits and speeds live in ``model/nao.xml`` (joint ranges and ``speed/<joint>``
custom numerics) and are read from the compiled model; see ``model/README.md`` for sources.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import MappingProxyType
from typing import Final

import numpy as np

from naoloc.robot import kinematics

MODEL_DIR: Final = Path(__file__).resolve().parent / "model"
NAO_XML: Final = MODEL_DIR / "nao.xml"

# Link lengths (NAO H25 "Links" documentation page) live in naoloc/robot/kinematics.py.
ROBOT_RADIUS: Final = 0.15  # m, radius of the collision capsule around the body

# NAOqi's head anti-collision limits: HeadPitch range (deg) as a function of HeadYaw (deg),
# linearly interpolated ("Joints" documentation page, head section); at yaw 0 the range is
# the joint's own (-38.5..29.5 deg).
_HEAD_YAW_DEG = (-119.52, -87.49, -62.45, -51.74, -43.32, -27.85, 0.0,
                 27.85, 43.32, 51.74, 62.45, 87.49, 119.52)  # fmt: skip
_HEAD_PITCH_MIN_DEG = (-25.73, -18.91, -24.64, -27.50, -31.40, -38.50, -38.50,
                       -38.50, -31.40, -27.50, -24.64, -18.91, -25.73)  # fmt: skip
_HEAD_PITCH_MAX_DEG = (18.91, 11.46, 17.19, 18.91, 21.20, 24.18, 29.51,
                       24.18, 21.20, 18.91, 17.19, 11.46, 18.91)  # fmt: skip


def head_pitch_limits(head_yaw: float) -> tuple[float, float]:
    """HeadPitch range (rad) allowed at a HeadYaw (rad): the head shell hits the shoulders.

    Args:
        head_yaw: HeadYaw in radians.

    Returns:
        ``(min, max)`` HeadPitch in radians.
    """
    yaw = math.degrees(head_yaw)
    lo = float(np.interp(yaw, _HEAD_YAW_DEG, _HEAD_PITCH_MIN_DEG))
    hi = float(np.interp(yaw, _HEAD_YAW_DEG, _HEAD_PITCH_MAX_DEG))
    return math.radians(lo), math.radians(hi)


def _legs(hip: float, knee: float, ankle: float | None = None) -> dict[str, float]:
    if ankle is None:
        ankle = -(hip + knee)  # keeps the feet flat with an upright torso
    out: dict[str, float] = {}
    for side in "LR":
        out.update(
            {
                f"{side}HipYawPitch": 0.0,
                f"{side}HipRoll": 0.0,
                f"{side}HipPitch": hip,
                f"{side}KneePitch": knee,
                f"{side}AnklePitch": max(-1.18, ankle),
                f"{side}AnkleRoll": 0.0,
            }
        )
    return out


def _arms(
    pitch: float, roll: float, elbow_yaw: float, elbow_roll: float, hand: float
) -> dict[str, float]:
    return {
        "LShoulderPitch": pitch,
        "LShoulderRoll": roll,
        "LElbowYaw": elbow_yaw,
        "LElbowRoll": -elbow_roll,
        "LWristYaw": 0.0,
        "LHand": hand,
        "RShoulderPitch": pitch,
        "RShoulderRoll": -roll,
        "RElbowYaw": -elbow_yaw,
        "RElbowRoll": elbow_roll,
        "RWristYaw": 0.0,
        "RHand": hand,
    }


_HEAD0 = {"HeadYaw": 0.0, "HeadPitch": 0.0}

# Joint angles (rad) of NAOqi's predefined postures, approximated from the figures of the
# ALRobotPosture documentation. StandInit's legs are NAO's (hip -0.45, knee 0.70, ankle
# -0.35): with the feet flat the torso leans 0.1 rad forward (naoloc/robot/kinematics.py places it);
# the other postures keep the torso upright (the model does not lie down: Sit and Lying
# postures only set the joints).
POSTURES: Final = MappingProxyType(
    {
        "StandInit": {
            **_HEAD0,
            **_arms(1.40, 0.30, -1.39, 1.00, 0.25),
            **_legs(-0.45, 0.70, -0.35),
        },
        "Stand": {**_HEAD0, **_arms(1.40, 0.20, -1.39, 0.50, 0.25), **_legs(-0.20, 0.40)},
        "StandZero": {**_HEAD0, **_arms(0.0, 0.0, 0.0, 0.0349, 0.0), **_legs(0.0, 0.0)},
        "Crouch": {**_HEAD0, **_arms(1.50, 0.15, -1.20, 0.90, 0.0), **_legs(-0.70, 1.85)},
        "Sit": {**_HEAD0, **_arms(0.90, 0.20, -1.20, 0.60, 0.0), **_legs(-1.40, 1.30)},
        "SitRelax": {**_HEAD0, **_arms(1.20, 0.30, -0.80, 0.40, 0.0), **_legs(-1.20, 1.50)},
        "LyingBack": {**_HEAD0, **_arms(1.60, 0.10, 0.0, 0.0349, 0.0), **_legs(0.0, 0.0)},
        "LyingBelly": {**_HEAD0, **_arms(-1.20, 0.10, 0.0, 0.0349, 0.0), **_legs(0.0, 0.0)},
    }
)
STANDING_POSTURES: Final = ("StandInit", "Stand", "StandZero")


def posture_torso_height(name: str) -> float:
    """Torso height (m) above the floor of a predefined posture, feet flat (kinematics)."""
    return float(kinematics.robot_to_torso(POSTURES[name])[2, 3])
