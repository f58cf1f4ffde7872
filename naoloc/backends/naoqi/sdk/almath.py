"""``almath`` of the old NAOqi Python SDK, in part: angle constants and 2D poses."""

from __future__ import annotations

import math
from typing import Final

from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse

__all__ = ["PI", "PI_2", "TO_DEG", "TO_RAD", "Pose2D", "modulo2PI", "pose2DInverse"]

PI: Final = math.pi
PI_2: Final = math.pi / 2.0
TO_RAD: Final = math.pi / 180.0
TO_DEG: Final = 180.0 / math.pi
