"""Which way is open: a step away from the walls a look saw (FRAME_ROBOT, m, rad).

Pure functions over recorded floor-wall lines, no map: a robot that cannot find itself
(a look found no pose) may stand where its cameras see too little of the room, pressed into
a corner or facing a wall from a few decimetres. A step into the open before the next look
shows more of what the map knows.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from naoloc.geometry import Pose2D, relative_pose
from naoloc.localization.observations import LineScan

__all__ = ["away_from_walls"]


def away_from_walls(
    scans: Sequence[LineScan], now: Pose2D, near_m: float
) -> tuple[float, float] | None:
    """The unit direction (FRAME_ROBOT now) that leads away from the walls seen near.

    Each line of each scan is moved into the robot's frame now by the odometry (the scans'
    and ``now``'s, both FRAME_WORLD); a line nearer than ``near_m`` pushes with weight
    ``(near_m - distance) / near_m`` along its normal, away from it. A corner pushes out of
    it diagonally.

    Args:
        scans: Floor-wall line scans (a look's), each with its odometry at capture.
        now: The robot's odometry now (FRAME_WORLD).
        near_m: Lines farther than this do not push, m.

    Returns:
        ``(dx, dy)``, unit length; None when no line is near, or the pushes mostly cancel
        (their sum is less than half their weights': walls on opposite sides, where no
        way is more open than another).
    """
    px = py = total = 0.0
    for scan in scans:
        rel = relative_pose(now, scan.odometry)  # the capture pose in the robot frame now
        for line in scan.lines:
            normal = rel.theta + line.normal
            nx, ny = math.cos(normal), math.sin(normal)
            # The line's foot is rel + line.distance * n: its distance from the origin now,
            # along the normal.
            distance = rel.x * nx + rel.y * ny + line.distance
            if distance < 0.0:  # the robot has passed to the line's other side
                nx, ny, distance = -nx, -ny, -distance
            if distance >= near_m:
                continue
            weight = (near_m - distance) / near_m
            px, py, total = px - weight * nx, py - weight * ny, total + weight
    norm = math.hypot(px, py)
    if total <= 0.0 or norm < 0.5 * total:  # nothing near, or pushes that mostly cancel
        return None
    return px / norm, py / norm
