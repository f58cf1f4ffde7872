"""``motion`` of the old NAOqi Python SDK: ALMotion's frame and axis-mask constants."""

from __future__ import annotations

from typing import Final

from naoloc.constants import FRAME_ROBOT, FRAME_TORSO, FRAME_WORLD

__all__ = [
    "AXIS_MASK_ALL", "AXIS_MASK_ROT", "AXIS_MASK_VEL", "AXIS_MASK_WX", "AXIS_MASK_WY",
    "AXIS_MASK_WZ", "AXIS_MASK_X", "AXIS_MASK_XY", "AXIS_MASK_Y", "AXIS_MASK_Z",
    "FRAME_ROBOT", "FRAME_TORSO", "FRAME_WORLD", "SPACE_NAO", "SPACE_SUPPORT_LEG",
    "SPACE_TORSO",
]  # fmt: skip

SPACE_TORSO: Final = FRAME_TORSO
SPACE_NAO: Final = FRAME_ROBOT
SPACE_SUPPORT_LEG: Final = 3
AXIS_MASK_X: Final = 1
AXIS_MASK_Y: Final = 2
AXIS_MASK_XY: Final = 3
AXIS_MASK_Z: Final = 4
AXIS_MASK_WX: Final = 8
AXIS_MASK_WY: Final = 16
AXIS_MASK_WZ: Final = 32
AXIS_MASK_VEL: Final = 7
AXIS_MASK_ROT: Final = 56
AXIS_MASK_ALL: Final = 63
