"""When a floor-wall line is believed: one sensor range and one side-line gate.

The bottom camera's floor-wall lines (:mod:`naoloc.perception.floorline`) are read by the
survey while it walks (keeping its distance from the side wall, finding the corner from the
front wall), by the survey's metric scale (:func:`naoloc.behaviours.wall_follow.metric_scale`)
and by the map's wall-referenced poses (:mod:`naoloc.mapping.wall_poses`). They all trust a
line by the rules here, so the robot steers by the same lines the map is later built from.

Frames: a line's ``distance`` is metres from FRAME_ROBOT's origin, its ``normal`` the
direction (rad, FRAME_ROBOT) from the origin to the line's nearest point.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Final

from naoloc.geometry import modulo2PI

if TYPE_CHECKING:
    from naoloc.perception.floorline import WallLine

# The floor line of a wall ahead is trusted up to this distance, m. The detector is scored
# to it (tools/floorline_accuracy.py: fronts 0.9-2.2 m ahead); the survey's lines read
# 1-2 cm short at every distance to it (tools/wall_pose_accuracy.py).
FRONT_RANGE_M: Final = 2.2
# A front line farther than FRONT_RANGE_M, up to this, m, does not steer the survey, but it
# places the frame it was seen from along its side in the map when it agrees with the walk
# between the side's corners (:mod:`naoloc.mapping.wall_poses`). Where no furniture stands in
# front of the wall the detector reads fronts 2.2-3.6 m ahead within 1.5 cm (median) and
# 3.4 cm (p90), 48 of 48 found (tools/floorline_accuracy.py --front 2.2 3.6, six rooms).
FAR_FRONT_RANGE_M: Final = 3.6
# A side line farther than this from the wall offset the survey keeps, m, sees something
# else (a piece of furniture, a doorway's recess, a rug's edge): the robot does not steer by
# it and the map does not place frames by it.
SIDE_OFFSET_ERROR_M: Final = 0.5
# Nor does a side line at a larger angle to the wall the survey walks along, rad.
SIDE_ANGLE_ERROR_RAD: Final = 0.35
# Nor one nearer than this, m: no view of the bottom camera sees a wall's foot that near
# beside the robot; what it shows there is the robot's own arm (tools/floorline_views.py).
SIDE_MIN_M: Final = 0.35
# Half the robot's way ahead, m: its body (0.15 m) and a margin. A wall the robot walks
# toward crosses it; a cabinet's or a table's face beside the way does not.
PATH_HALF_M: Final = 0.2


def in_front_range(distance: float) -> bool:
    """Whether a front line ``distance`` m ahead is within the trusted range."""
    return distance <= FRONT_RANGE_M


def in_far_front_range(distance: float) -> bool:
    """Whether a front line ``distance`` m ahead may place a map frame (not steer)."""
    return distance <= FAR_FRONT_RANGE_M


def crosses_path(line: WallLine, half_width: float = PATH_HALF_M) -> bool:
    """Whether a line ahead crosses the robot's way (its centre line, x forward, within
    ``half_width`` m to either side) where its inliers lie.

    The line's ``ends_m`` run along it from its nearest point to FRAME_ROBOT's origin; the
    way's centre line meets it at ``-distance * tan(normal)`` in those coordinates, and the
    way's edges ``half_width / cos(normal)`` to either side. A line whose ends are not
    known, or that runs along the way (``|normal|`` of 60 deg or more), is taken to cross it.
    """
    if line.ends_m is None:
        return True
    c = math.cos(line.normal)
    if c < 0.5:
        return True
    centre = -line.distance * math.tan(line.normal)
    reach = half_width / c
    low, high = line.ends_m
    return low < centre + reach and high > centre - reach


def side_line_angle(
    distance: float, normal: float, offset: float, side_normal: float
) -> float | None:
    """The robot's heading to the side wall's direction, if the side line is trusted.

    Args:
        distance: The line's distance, m.
        normal: The line's normal, rad (FRAME_ROBOT).
        offset: The distance the survey keeps from the side wall, m.
        side_normal: Where the side wall should be, rad (``-pi/2`` right, ``+pi/2`` left).

    Returns:
        ``side_normal - normal`` wrapped to (-pi, pi] (rad) when the line is within
        :data:`SIDE_OFFSET_ERROR_M` of ``offset`` and :data:`SIDE_ANGLE_ERROR_RAD` of
        ``side_normal``, and not nearer than :data:`SIDE_MIN_M`, else None.
    """
    delta = modulo2PI(side_normal - normal)
    if abs(distance - offset) > SIDE_OFFSET_ERROR_M or abs(delta) > SIDE_ANGLE_ERROR_RAD:
        return None
    return None if distance < SIDE_MIN_M else delta
