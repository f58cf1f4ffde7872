"""Walk back to the map origin (where the survey started) using the map.

Each round localizes (:func:`naoloc.behaviours.localize.localize`), then walks with
``moveTo`` to the origin as seen from the estimate (the map origin in FRAME_ROBOT is the
inverse of the estimated pose), and localizes again, until the estimate is within
``go_home.tolerance_m`` of the origin or ``go_home.max_tries`` walks were made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from naoloc.behaviours.camera import Camera
from naoloc.behaviours.localize import Localization, localize, truth_in_map
from naoloc.config import Config
from naoloc.errors import MotionError
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
        est = self.final.estimate
        out: dict[str, Any] = {
            "x": round(est.x, 4),
            "y": round(est.y, 4),
            "theta": round(est.theta, 4),
            "confidence": round(float(est.confidence), 4),
            "tries": self.tries,
            "reached": self.reached,
            "estimates": [[round(r.estimate.x, 3), round(r.estimate.y, 3)] for r in self.rounds],
        }
        if self.truth is not None and self.error_m is not None:
            out["error_m"] = round(self.error_m, 4)
            out["truth"] = [round(v, 4) for v in self.truth]
        return out


def go_home(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    on_round: Callable[[int, Localization], None] | None = None,
    turns: int = 1,
) -> GoHomeResult:
    """Localize, walk to the map origin, and repeat until close enough or out of tries.

    Args:
        robot: The robot, anywhere in the mapped room.
        vmap: The map.
        cfg: Config; uses ``go_home.tolerance_m``, ``go_home.max_tries``, ``localize`` and
            ``camera``.
        on_round: Called after each localization with the walk count so far and its result.
        turns: Body headings of each localization scan (1 = no turning in place).

    Returns:
        The final estimate, walks made, and the true error on a simulator.

    A localization with confidence 0 (nothing recognised) is followed by a quarter turn in
    place instead of a walk. A walk that fails (an obstacle) is retried after localizing
    again along the survey circuit, which the robot is known to have walked.

    Raises:
        MotionError: Turning in place failed (the robot is stopped).
    """
    tolerance = cfg.go_home.tolerance_m
    rounds: list[Localization] = []
    tries = 0
    reached = False
    blocked = False
    with Camera(robot, cfg.camera, "naoloc_go_home") as camera:
        try:
            while True:
                loc = localize(robot, vmap, cfg, camera=camera, turns=turns)
                rounds.append(loc)
                if on_round is not None:
                    on_round(tries, loc)
                est = loc.estimate
                lost = est.confidence <= 0.0
                if not lost and math.hypot(est.x, est.y) <= tolerance:
                    reached = True
                    break
                if tries >= cfg.go_home.max_tries:
                    break
                tries += 1
                if lost:  # nothing recognised: look elsewhere by turning in place
                    if not robot.motion.moveTo(0.0, 0.0, math.pi / 2):
                        raise MotionError("turning in place failed while lost")
                    continue
                here = Pose2D(est.x, est.y, est.theta)
                route = route_home(vmap, here) if blocked else straight_home(here)
                blocked = not _follow(robot, here, route)
        finally:
            robot.motion.stopMove()
    truth = truth_in_map(robot, vmap.meta)
    error = None if truth is None else math.hypot(truth.x, truth.y)
    return GoHomeResult(rounds[-1], tries, reached, rounds, truth, error)


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


def _follow(robot: Robot, start: Pose2D, route: list[Pose2D]) -> bool:
    """Walk through map-frame waypoints by odometry from ``start``; False if a move failed.

    Each waypoint is approached facing it; the last one (the origin) ends facing map +x.
    """
    odo0 = pose_of(robot.motion, True)
    for k, point in enumerate(route):
        here = start * relative_pose(odo0, pose_of(robot.motion, True))
        last = k == len(route) - 1
        heading = 0.0 if last else math.atan2(point.y - here.y, point.x - here.x)
        move = relative_pose(here, Pose2D(point.x, point.y, heading))
        if not robot.motion.moveTo(move.x, move.y, move.theta):
            robot.motion.stopMove()
            return False
    return True
