"""Walk back to the map origin (where the survey started) using the map.

Each round localizes (:func:`naoloc.behaviours.localize.localize`, which turns in place
until it is confident), then walks with ``moveTo`` one leg (at most :data:`LEG_M`) toward
the origin as seen from the estimate, and localizes again, until a confident estimate is
within ``go_home.tolerance_m`` of the origin or ``go_home.max_tries`` walks were made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from naoloc.behaviours.camera import Camera
from naoloc.behaviours.localize import Localization, estimate_fields, localize, truth_in_map
from naoloc.config import Config
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot import Robot, pose_of

if TYPE_CHECKING:
    from naoloc.mapping import VisualMap


@dataclass
class GoHomeResult:
    """How going home went.

    Attributes:
        final: The last localization (estimate in the map frame).
        tries: Walks made toward the origin.
        reached: True when the last estimate was within the tolerance.
        rounds: Every localization, in order.
        truth: The true final pose in the map frame (simulator), else None.
        error_m: True distance from the map origin at the end, m (simulator), else None.
    """

    final: Localization
    tries: int
    reached: bool
    rounds: list[Localization] = field(default_factory=list)
    truth: Pose2D | None = None
    error_m: float | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``go-home`` line."""
        out: dict[str, Any] = {
            **estimate_fields(self.final.estimate),
            "tries": self.tries,
            "reached": self.reached,
            "estimates": [
                [round(r.estimate.x, 3), round(r.estimate.y, 3)]
                for r in self.rounds
                if r.estimate.found
            ],
        }
        if self.truth is not None and self.error_m is not None:
            out["error_m"] = round(self.error_m, 4)
            out["truth"] = [round(v, 4) for v in self.truth]
        return out


# Longest walk between two localizations, m: odometry stays good over a leg, and a fresh
# estimate re-plans the rest. Without a confident estimate the leg is shorter.
LEG_M = 2.0
UNSURE_LEG_M = 0.5
# With nothing recognised even after a full turn: step this far forward (m), then look again.
LOST_STEP_M = 1.0
MAX_LOST_STEPS = 4  # exploring steps when nothing is recognised; they are not walks home


def go_home(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    on_round: Callable[[int, Localization], None] | None = None,
    turns: int = 1,
    leg_m: float = LEG_M,
) -> GoHomeResult:
    """Localize, walk a leg toward the map origin, and repeat until there or out of tries.

    Args:
        robot: The robot, anywhere in the mapped room.
        vmap: The map.
        cfg: Config; uses ``go_home.tolerance_m``, ``go_home.max_tries``, ``localize`` and
            ``camera``.
        on_round: Called after each localization with the walk count so far and its result.
        turns: Body headings of the first sweep of each localization (1 = no turning in
            place; the localize behaviour adds quarter turns while it is not confident).
        leg_m: Longest walk between two localizations, m.

    Returns:
        The final estimate, walks made, and the true error on a simulator.

    Each round localizes (the robot turns in place until the map gives a confident, verified
    estimate or it has looked all around). A confident estimate within the tolerance ends
    the walk home. Otherwise the robot walks at most ``leg_m`` (``UNSURE_LEG_M`` when the
    estimate is not confident) toward the origin and localizes again. When a localization is
    not confident but an earlier one was, that earlier estimate carried forward by odometry
    is used instead. A localization with confidence 0 (nothing recognised all around) and
    no earlier confident one is followed by a short step forward; up to ``MAX_LOST_STEPS`` of
    those do not count as walks. After a walk that fails
    (``moveTo`` returns False: an obstacle) the robot localizes again and keeps to the survey
    circuit, which it is known to have walked, in legs of ``2 * leg_m``.

    Raises:
        MotionError: A turn in place while localizing failed (the robot is stopped).
    """
    from naoloc.mapping.localizer import CONFIDENT

    tolerance = cfg.go_home.tolerance_m
    rounds: list[Localization] = []
    tries = 0
    lost_steps = 0
    reached = False
    blocked = False
    anchor: tuple[Pose2D, Pose2D] | None = None  # last confident estimate, odometry then
    with Camera(robot, cfg.camera, "naoloc_go_home") as camera:
        try:
            while True:
                loc = localize(robot, vmap, cfg, camera=camera, turns=turns)
                rounds.append(loc)
                if on_round is not None:
                    on_round(tries, loc)
                est = loc.estimate
                odometry = pose_of(robot.motion, True)
                confident = est.found and est.confidence >= CONFIDENT
                if confident:
                    anchor = (Pose2D(est.x, est.y, est.theta), odometry)
                if confident and math.hypot(est.x, est.y) <= tolerance:
                    reached = True
                    break
                if tries >= cfg.go_home.max_tries:
                    break
                if anchor is None and not est.found and lost_steps < MAX_LOST_STEPS:
                    # Nothing recognised all around and no earlier fix: explore a little
                    # (mid-room, far from every survey view) without using up a walk home.
                    lost_steps += 1
                    robot.motion.moveTo(LOST_STEP_M, 0.0, 0.0)  # False at an obstacle: fine
                    robot.motion.stopMove()
                    continue
                tries += 1
                if anchor is not None and not confident:
                    # Not recognised here (e.g. mid-room, far from every survey view): the
                    # last confident estimate carried by odometry is the better guess.
                    here = anchor[0] * relative_pose(anchor[1], odometry)
                    confident = True
                elif not est.found:  # nothing recognised all around: step elsewhere
                    robot.motion.moveTo(LOST_STEP_M, 0.0, 0.0)  # False at an obstacle: fine
                    robot.motion.stopMove()
                    continue
                else:
                    here = Pose2D(est.x, est.y, est.theta)
                if blocked:  # along the circuit, which is free, as far as odometry holds
                    route = route_home(vmap, here)
                    length = 2.0 * leg_m if confident else UNSURE_LEG_M
                else:
                    route = straight_home(here)
                    length = leg_m if confident else UNSURE_LEG_M
                leg = truncate_route(here, route, length)
                # Once the straight line was blocked, keep to the circuit from then on.
                blocked = not _follow(robot, here, leg, ends_home=leg[-1] == route[-1]) or blocked
        finally:
            robot.motion.stopMove()
    truth = truth_in_map(robot, vmap.meta)
    error = None if truth is None else math.hypot(truth.x, truth.y)
    return GoHomeResult(rounds[-1], tries, reached, rounds, truth, error)


def truncate_route(here: Pose2D, route: list[Pose2D], length_m: float) -> list[Pose2D]:
    """The first ``length_m`` metres of a route of map-frame waypoints starting at ``here``.

    Args:
        here: Where the robot stands (map frame).
        route: Waypoints (map frame).
        length_m: Path length to keep, m (> 0).

    Returns:
        The waypoints within that length; the last one is interpolated on its segment when the
        route is longer. The route itself (same objects) when it is not longer.
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


def straight_home(here: Pose2D, leg_m: float = 0.75) -> list[Pose2D]:
    """Waypoints (map frame) on the straight line from ``here`` to the origin, ``leg_m`` apart.

    Short legs re-planned from odometry keep the walk's own errors from adding up.
    """
    distance = math.hypot(here.x, here.y)
    legs = max(1, math.ceil(distance / leg_m))
    return [Pose2D(here.x * (1 - k / legs), here.y * (1 - k / legs)) for k in range(1, legs + 1)]


def route_home(vmap: VisualMap, here: Pose2D, spacing: int = 5) -> list[Pose2D]:
    """Waypoints (map frame) to the origin along the survey circuit's first lap.

    Args:
        vmap: The map; ``keyframe_poses`` and ``meta["frames_per_lap"]`` give the circuit.
        here: The robot's estimated pose, map frame.
        spacing: Keep every ``spacing``-th survey pose as a waypoint.

    Returns:
        From the circuit pose nearest ``here``, the shorter way round to the origin, which
        ends the list.
    """
    poses = np.asarray(vmap.keyframe_poses, dtype=float)[:, :2]
    per_lap = int(vmap.meta.get("frames_per_lap") or len(poses))
    ring = poses[: max(1, min(per_lap, len(poses)))]
    i = int(np.argmin(np.hypot(ring[:, 0] - here.x, ring[:, 1] - here.y)))
    forward = ring[i:]
    backward = ring[i::-1]

    def length(path: np.ndarray) -> float:
        return float(np.sum(np.hypot(*np.diff(np.vstack([path, [0.0, 0.0]]), axis=0).T)))

    path = forward if length(forward) <= length(backward) else backward
    kept = path[::spacing]
    return [Pose2D(float(x), float(y)) for x, y in kept] + [Pose2D()]


def _follow(robot: Robot, start: Pose2D, route: list[Pose2D], *, ends_home: bool = True) -> bool:
    """Walk through map-frame waypoints by odometry from ``start``; False if a move failed.

    Each waypoint is approached facing it; when ``ends_home``, the last one (the origin) ends
    facing map +x.
    """
    odo0 = pose_of(robot.motion, True)
    for k, point in enumerate(route):
        here = start * relative_pose(odo0, pose_of(robot.motion, True))
        last = ends_home and k == len(route) - 1
        heading = 0.0 if last else math.atan2(point.y - here.y, point.x - here.x)
        if not last and math.hypot(point.x - here.x, point.y - here.y) < 1e-3:
            continue
        move = relative_pose(here, Pose2D(point.x, point.y, heading))
        if not robot.motion.moveTo(move.x, move.y, move.theta):
            robot.motion.stopMove()
            return False
    return True
