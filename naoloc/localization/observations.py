"""What the localizer is given: typed observations, each stamped with the robot's odometry.

Every observation carries the raw odometry pose (NAOqi FRAME_WORLD, as
``getRobotPosition(True)`` gives it) at the moment it was taken; the localizer moves its
belief by the odometry between consecutive observations. Nothing here touches a robot: a
behaviour takes pictures and measures lines, then hands them over, and an evaluation can
hand the same observations to another map (replay).

Frames: odometry poses in FRAME_WORLD (x forward, y left at the odometry's origin, theta
counter-clockwise; metres, radians); floor-wall lines in FRAME_ROBOT at capture.
"""

from __future__ import annotations

from dataclasses import dataclass

from naoloc.geometry import Pose2D
from naoloc.perception.features import Features
from naoloc.perception.floorline import WallLine
from naoloc.robot.keyframe import Keyframe

__all__ = ["LineScan", "Observation", "Odometry", "Picture"]


@dataclass(frozen=True, eq=False)
class Picture:
    """A camera picture.

    Attributes:
        keyframe: The picture with the robot's odometry pose (``pose``, FRAME_WORLD) and the
            camera's pose in FRAME_ROBOT at capture (``camera_pose``).
        features: Its features with the map's extractor, in the map's pinhole model; None:
            the localizer extracts them.
    """

    keyframe: Keyframe
    features: Features | None = None

    @property
    def odometry(self) -> Pose2D:
        """The robot's odometry pose at capture (FRAME_WORLD)."""
        return self.keyframe.pose

    @property
    def stamp(self) -> float:
        """Capture time, s (the robot's clock)."""
        return float(self.keyframe.stamp)


@dataclass(frozen=True, eq=False)
class LineScan:
    """The floor-wall lines of one bottom-camera picture.

    Attributes:
        lines: Lines in FRAME_ROBOT at capture (none: the picture showed no wall's foot).
        odometry: The robot's odometry pose at capture (FRAME_WORLD).
        stamp: Capture time, s.
    """

    lines: tuple[WallLine, ...]
    odometry: Pose2D
    stamp: float


@dataclass(frozen=True, eq=False)
class Odometry:
    """The robot's odometry alone (the belief only moves).

    Attributes:
        odometry: The odometry pose (FRAME_WORLD).
        stamp: Time, s.
    """

    odometry: Pose2D
    stamp: float


@dataclass(frozen=True, eq=False)
class Relocalize:
    """The behaviour's word that the belief is worth nothing now (the robot was lost and
    stops to look): the filter forgets it and localizes globally from here. Recorded like
    any observation, so a replay forgets at the same place.

    Attributes:
        stamp: Time, s.
    """

    stamp: float


Observation = Picture | LineScan | Odometry | Relocalize
