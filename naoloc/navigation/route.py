"""Following a path: pure-pursuit walking commands and route arithmetic (map frame, m, rad).

Pure functions: a behaviour asks :func:`pursuit` for a walking velocity from the belief's
pose and the planned waypoints, and sends it to ALMotion's ``move``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from naoloc.constants import WALK_SPEED, WALK_SPEED_THETA, WALK_SPEED_Y
from naoloc.geometry import Pose2D, modulo2PI

__all__ = ["Command", "path_length", "pursuit", "remaining", "truncate_route"]


@dataclass(frozen=True)
class Command:
    """A walking velocity (FRAME_ROBOT): forward m/s, sideways m/s, turn rad/s."""

    x: float
    y: float
    theta: float


def remaining(route: Sequence[Pose2D], here: Pose2D, reached_m: float) -> list[Pose2D]:
    """The waypoints still ahead: those before the last one within ``reached_m`` are done."""
    out = list(route)
    while len(out) > 1 and math.hypot(out[0].x - here.x, out[0].y - here.y) < reached_m:
        out.pop(0)
    return out


def pursuit(
    here: Pose2D,
    route: Sequence[Pose2D],
    *,
    lookahead_m: float = 0.35,
    speed: float = WALK_SPEED,
    turn_speed: float = WALK_SPEED_THETA,
    turn_first_rad: float = 0.6,
    goal_theta: float | None = None,
    align_m: float = 0.0,
) -> Command:
    """A pure-pursuit velocity toward the point ``lookahead_m`` along the route.

    Walks forward and steers toward that point; a point more than ``turn_first_rad`` off
    the heading is turned to in place first (a NAO walks badly while turning hard). Slows
    down within the last lookahead of the goal.

    Within ``align_m`` of the goal (along the route) and with a ``goal_theta``, the walk
    is omnidirectional, as a NAO's is: it turns toward the goal's heading while it steps
    toward the pursued point forward, sideways or back, so that it arrives facing the way
    the goal does instead of turning in place there.

    Args:
        here: The robot's pose, map frame.
        route: Waypoints ahead (map frame); the last is the goal.
        lookahead_m: Distance of the pursued point along the route, m.
        speed: Forward speed, m/s.
        turn_speed: Largest turn rate, rad/s.
        turn_first_rad: Heading error beyond which the robot turns in place.
        goal_theta: The heading to arrive with, rad, map frame (None: any).
        align_m: Distance from the goal along the route within which the robot turns to
            ``goal_theta`` while it walks, m (0: never).
    """
    if not route:
        return Command(0.0, 0.0, 0.0)
    target = _along(here, route, lookahead_m)
    dx, dy = target.x - here.x, target.y - here.y
    dist = math.hypot(dx, dy)
    if goal_theta is not None and path_length(here, route) <= align_m:
        return _aligning(here, dx, dy, dist, goal_theta, lookahead_m, speed, turn_speed)
    if dist < 1e-6:
        return Command(0.0, 0.0, 0.0)
    bearing = modulo2PI(math.atan2(dy, dx) - here.theta)
    if abs(bearing) > turn_first_rad:
        return Command(0.0, 0.0, math.copysign(turn_speed, bearing))
    # Pure pursuit: curvature 2 sin(bearing) / distance, at the forward speed.
    v = speed * min(1.0, dist / lookahead_m)
    w = max(-turn_speed, min(turn_speed, 2.0 * v * math.sin(bearing) / dist))
    return Command(v, 0.0, w)


def _aligning(
    here: Pose2D,
    dx: float,
    dy: float,
    dist: float,
    goal_theta: float,
    lookahead_m: float,
    speed: float,
    turn_speed: float,
) -> Command:
    """The omnidirectional step of :func:`pursuit`: toward ``(dx, dy)`` (map frame, m)
    whatever the heading, turning toward ``goal_theta`` (rad); each component within the
    walk's speeds (forward and back ``speed``, sideways :data:`WALK_SPEED_Y`)."""
    w = max(-turn_speed, min(turn_speed, 2.0 * modulo2PI(goal_theta - here.theta)))
    if dist < 1e-6:
        return Command(0.0, 0.0, w)
    v = speed * min(1.0, dist / lookahead_m)
    c, s = math.cos(here.theta), math.sin(here.theta)
    vx, vy = v * (c * dx + s * dy) / dist, v * (-s * dx + c * dy) / dist
    scale = max(1.0, abs(vx) / speed, abs(vy) / min(speed, WALK_SPEED_Y))
    return Command(vx / scale, vy / scale, w)


def path_length(start: Pose2D, route: Sequence[Pose2D]) -> float:
    """Length of the polyline from ``start`` through ``route``, m."""
    total, prev = 0.0, start
    for p in route:
        total += math.hypot(p.x - prev.x, p.y - prev.y)
        prev = p
    return total


def _along(here: Pose2D, route: Sequence[Pose2D], distance: float) -> Pose2D:
    """The point ``distance`` m along the polyline from ``here`` through ``route``."""
    prev, left = here, distance
    for p in route:
        seg = math.hypot(p.x - prev.x, p.y - prev.y)
        if seg >= left and seg > 0:
            f = left / seg
            return Pose2D(prev.x + f * (p.x - prev.x), prev.y + f * (p.y - prev.y))
        left -= seg
        prev = p
    return route[-1]


def truncate_route(here: Pose2D, route: list[Pose2D], length_m: float) -> list[Pose2D]:
    """The first ``length_m`` metres of a route of map-frame waypoints starting at ``here``.

    The last kept waypoint is interpolated on its segment when the route is longer; the
    route itself (same objects) when it is not longer.
    """
    out: list[Pose2D] = []
    prev = here
    left = length_m
    for point in route:
        seg = math.hypot(point.x - prev.x, point.y - prev.y)
        if seg <= left:
            out.append(point)
            left -= seg
            prev = point
            continue
        f = left / seg if seg > 0 else 0.0
        out.append(Pose2D(prev.x + f * (point.x - prev.x), prev.y + f * (point.y - prev.y)))
        return out
    return out
