"""Facts about the NAO model that the backend needs besides the MJCF: postures, radius.

Joint limits and speeds live in ``model/nao.xml`` (joint ranges and ``speed/<joint>``
custom numerics) and are read from the compiled model; see ``model/README.md`` for sources.
"""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType
from typing import Final

from naoloc.robot import kinematics

MODEL_DIR: Final = Path(__file__).resolve().parent / "model"
NAO_XML: Final = MODEL_DIR / "nao.xml"

# Link lengths (NAO H25 "Links" documentation page) live in naoloc/robot/kinematics.py.
ROBOT_RADIUS: Final = 0.15  # m, radius of the collision capsule around the body


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
