"""Walk back to the map origin (where the survey started) using the map.

Each round localizes (:func:`naoloc.behaviours.localize.localize`, which turns in place
until it is confident) and fuses the fix with the odometry walked since the last one in a
particle filter (:mod:`naoloc.localization.fusion`). From the filter's pose it plans a path home
over the
floor grid the map implies (:mod:`naoloc.navigation.grid`: the floor the survey walked is free,
walls and furniture seen as landmarks near the floor are blocked), walks the first leg of it
(at most ``leg_m``; a leg that would arrive from farther than ``FINAL_LEG_M`` stops short)
open-loop on odometry with ``moveTo``, and localizes again. A leg that ends within
``FINAL_LEG_M`` of home ends facing map +x, as the survey started: there the pictures see
what the survey's first pictures saw, not whatever stands beside home (room 1789164527:
facing a bench beside home, fixes erred 0.36-0.55 m and go-home gave up 0.49 m off). A
blocked walk (``moveTo`` returns False, or the fixes before and after a leg show the robot
went nowhere while its odometry counted steps) marks the place ahead of the robot blocked
and the next plan goes around it. When a fresh fix puts the robot within
``go_home.tolerance_m`` of the origin it side-steps the residual, turns to face map +x and
localizes again (up to ``SETTLES`` times); it stops there, or after ``go_home.max_tries``
walks.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from naoloc.behaviours.localize import Localization, estimate_fields, localize, truth_in_map
from naoloc.config import Config
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.localization.fusion import Belief, Fix, ParticleFilter, fix_from_estimate
from naoloc.navigation.grid import BLOCKED, FloorGrid, NoPath, grid_from_map
from naoloc.robot import Robot, pose_of
from naoloc.robot.camera import Camera

if TYPE_CHECKING:
    from naoloc.mapping import VisualMap


@dataclass
class GoHomeResult:
    """How going home went.

    Attributes:
        final: The last localization (estimate in the map frame).
        tries: Walks made toward the origin.
        reached: True when the last fix put the robot within the tolerance.
        rounds: Every localization, in order.
        truth: The true final pose in the map frame (simulator), else None.
        error_m: True distance from the map origin at the end, m (simulator), else None.
        path_m: Distance walked by odometry, m (turns in place excluded).
        trail: Map-frame poses the robot believed it was at, from the start to the end: the
            filter's belief at each localization and the odometry-carried pose after each leg.
        beliefs: The filter's belief after each localization (None before the first fix).
        blocked_at: Map-frame places where a walk was blocked.
        reason: Why it stopped short (empty when it arrived).
    """

    final: Localization
    tries: int
    reached: bool
    rounds: list[Localization] = field(default_factory=list)
    truth: Pose2D | None = None
    error_m: float | None = None
    path_m: float = 0.0
    trail: list[Pose2D] = field(default_factory=list)
    beliefs: list[Belief | None] = field(default_factory=list)
    blocked_at: list[Pose2D] = field(default_factory=list)
    reason: str = ""

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``go-home`` line (map frame)."""
        last = next((b for b in reversed(self.beliefs) if b is not None), None)
        if last is not None:
            pose: dict[str, Any] = {
                "x": round(last.pose.x, 4),
                "y": round(last.pose.y, 4),
                "theta": round(last.pose.theta, 4),
                "confidence": estimate_fields(self.final.estimate)["confidence"],
                "method": "filter",
                **last.to_json(),
            }
        else:
            pose = dict(estimate_fields(self.final.estimate))
        out: dict[str, Any] = {
            **pose,
            "tries": self.tries,
            "reached": self.reached,
            "path_m": round(self.path_m, 3),
            "estimates": [
                [round(r.estimate.x, 3), round(r.estimate.y, 3)]
                for r in self.rounds
                if r.estimate.found
            ],
            "blocked": len(self.blocked_at),
        }
        if self.reason:
            out["reason"] = self.reason
        if self.truth is not None and self.error_m is not None:
            out["error_m"] = round(self.error_m, 4)
            out["truth"] = [round(v, 4) for v in self.truth]
        return out


# Longest walk between two localizations, m: odometry stays good over a leg, and a fresh
# estimate re-plans the rest. Without a confident belief the leg is shorter.
LEG_M = 2.0
UNSURE_LEG_M = 0.5
# The leg that ends at home is at most this long (m): a longer approach stops halfway
# through the last FINAL_LEG_M and localizes again, so the last leg's odometry error (a NAO
# drifts sideways ~0.1-0.3 m over 1.5 m) is that of a short walk.
FINAL_LEG_M = 0.8
# Once a fix puts it within the tolerance, a residual longer than this (m) is walked too
# (a side-step, then a turn to face map +x), and a fresh localization checks where it is:
# at most SETTLES times, then it stops on the tolerance alone.
RESIDUAL_M = 0.03
SETTLES = 2
# Waypoints at most this far apart (m): each moveTo is re-aimed from odometry.
WAYPOINT_M = 0.75
# A belief is confident when its particles lie within this radius (m).
CONFIDENT_SPREAD_M = 0.15
# With nothing recognised even after a full turn: step this far forward (m), then look again.
LOST_STEP_M = 1.0
MAX_LOST_STEPS = 4  # exploring steps when nothing is recognised; they are not walks home
# A blocked walk marks a disc of this radius (m) this far ahead (m) of where it stopped.
BUMP_RADIUS_M = 0.2
BUMP_AHEAD_M = 0.3
# A leg is taken as blocked also when the fixes before and after it (PnP both) moved less
# than this share of what odometry walked (at least STALL_MIN_M): the robot pushed against
# something (a chair) while its odometry counted the steps it never made.
STALL_SHARE = 0.4
STALL_MIN_M = 0.3
PARTICLES = 1500


def floor_grid(vmap: Any) -> FloorGrid:
    """The floor grid of a map: keyframe poses walked free, landmarks near the floor blocked."""
    refined = getattr(vmap, "refined_poses", None)
    poses = np.asarray(vmap.keyframe_poses if refined is None else refined)
    points = getattr(vmap, "kp_points", None)
    pts = np.empty((0, 3)) if points is None else np.asarray(points)
    return grid_from_map(poses, pts)


def go_home(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    on_round: Callable[[int, Localization], None] | None = None,
    turns: int = 1,
    leg_m: float = LEG_M,
) -> GoHomeResult:
    """Localize, fuse, plan, walk a leg toward the map origin; repeat until there.

    Args:
        robot: The robot, anywhere in the mapped room.
        vmap: The map.
        cfg: Config; uses ``go_home.tolerance_m``, ``go_home.max_tries``, ``localize``,
            ``camera`` and ``map.seed`` (the filter's seed).
        on_round: Called after each localization with the walk count so far and its result.
        turns: Body headings of the first sweep of each localization (1 = no turning in
            place; the localize behaviour adds quarter turns while it is not confident).
        leg_m: Longest walk between two localizations, m.

    Returns:
        The final estimate, walks made, path walked, and the true error on a simulator.

    A localization that recognises nothing before any fix is followed by a short exploring
    step forward (up to ``MAX_LOST_STEPS``, not counted as walks). Between fixes the filter
    carries the pose by odometry, so a round that recognises nothing still has a pose to plan
    from; it is walked in short legs.

    Raises:
        MotionError: A turn in place while localizing failed (the robot is stopped).
    """
    from naoloc.mapping.localizer import turn_scale_of

    tolerance = cfg.go_home.tolerance_m
    grid = floor_grid(vmap)
    spin = turn_scale_of(vmap)
    home = Pose2D()
    rounds: list[Localization] = []
    beliefs: list[Belief | None] = []
    trail: list[Pose2D] = []
    bumps: list[Pose2D] = []
    tries = lost_steps = settles = 0
    reached = False
    reason = ""
    walked = 0.0
    pf: ParticleFilter | None = None
    last_leg: tuple[Pose2D, float, float] | None = None  # start fix, odometry m, aim rad
    # Odometry after each move since the last localization: the filter moves by each in
    # turn, so its noise grows with every turn made, not with the net change of heading.
    moves: list[Pose2D] = []
    with Camera(robot, cfg.localize.camera(cfg.camera), "naoloc_go_home") as camera:
        try:
            odo_prev = pose_of(robot.motion, True)
            while True:
                loc = localize(robot, vmap, cfg, camera=camera, turns=turns)
                rounds.append(loc)
                if on_round is not None:
                    on_round(tries, loc)
                est = loc.estimate
                odo = pose_of(robot.motion, True)
                if pf is not None:  # move by each walk and turn since the last fix, in order
                    chain = [odo_prev, *moves, *(q.pose for q in loc.queries), odo]
                    for a, b in itertools.pairwise(chain):
                        step = relative_pose(a, b)  # its turn as the survey calibrated it
                        pf.predict(Pose2D(step.x, step.y, step.theta / spin))
                odo_prev = odo
                moves.clear()
                if last_leg is not None and est.found and est.method == "pnp":
                    stalled = _stalled(last_leg, est.pose())
                    if stalled is not None:
                        bumps.append(stalled)
                        grid.mark(stalled.x, stalled.y, BUMP_RADIUS_M, BLOCKED)
                last_leg = None
                fix = fix_from_estimate(est) if est.found else None
                if fix is not None:
                    if pf is None:
                        pf = ParticleFilter(
                            PARTICLES, seed=cfg.map.seed, bounds=grid.bounds(),
                            free=grid.free_test(clearance=False),
                        )  # fmt: skip
                        pf.reset_to(fix)
                    pf.update(fix)
                belief = pf.belief() if pf is not None else None
                beliefs.append(belief)
                if belief is None:
                    if lost_steps >= MAX_LOST_STEPS:
                        reason = "nothing recognised anywhere it looked"
                        break
                    # Nothing recognised all around and no fix yet: explore a little.
                    lost_steps += 1
                    walked += _walk_straight(robot, LOST_STEP_M, moves)
                    continue
                here = belief.pose
                trail.append(here)
                confident = belief.spread_m <= CONFIDENT_SPREAD_M
                if (
                    fix is not None
                    and confident
                    and math.hypot(here.x, here.y) <= tolerance
                    and not _fix_says_away(fix, tolerance)
                ):
                    if math.hypot(here.x, here.y) <= RESIDUAL_M or settles >= SETTLES:
                        reached = True
                        break
                    dist, end = _settle(robot, here, moves)  # the last few centimetres
                    walked += dist
                    trail.append(end)
                    settles += 1
                    continue  # localize again where it stopped
                if tries >= cfg.go_home.max_tries:
                    reason = f"not home after {tries} walks"
                    break
                tries += 1
                try:
                    route = grid.plan(here, home)
                except NoPath as err:
                    reason = str(err)
                    break
                leg = _densify(here, truncate_route(here, route, _leg_length(
                    here, route, leg_m if confident else UNSURE_LEG_M
                )))  # fmt: skip
                near = math.hypot(leg[-1].x, leg[-1].y) <= FINAL_LEG_M
                ok, dist, end = _follow(
                    robot, here, leg, moves, ends_home=leg[-1] == route[-1] or near
                )
                walked += dist
                trail.append(end)
                if est.found and est.method == "pnp":
                    aim = math.atan2(leg[0].y - here.y, leg[0].x - here.x)
                    last_leg = (est.pose(), dist, aim)
                if not ok:  # an obstacle the map did not know: remember it, plan around it
                    bump = end * Pose2D(BUMP_AHEAD_M, 0.0)
                    bumps.append(bump)
                    grid.mark(bump.x, bump.y, BUMP_RADIUS_M, BLOCKED)
        finally:
            robot.motion.stopMove()
    truth = truth_in_map(robot, vmap.meta)
    error = None if truth is None else math.hypot(truth.x, truth.y)
    return GoHomeResult(
        rounds[-1], tries, reached, rounds, truth, error, walked, trail, beliefs, bumps, reason
    )


def _fix_says_away(fix: Fix, tolerance: float) -> bool:
    """Whether a fix the floor lines verified puts the robot farther than ``tolerance``
    (m) from home: then the robot is not home, whatever the belief says (it walks on, and
    the filter moves to such a fix, :class:`ParticleFilter`)."""
    return fix.verified and math.hypot(fix.pose.x, fix.pose.y) > tolerance


def _leg_length(here: Pose2D, route: list[Pose2D], longest_m: float) -> float:
    """How far to walk along ``route`` (m) before localizing again.

    At most ``longest_m``; a route home longer than :data:`FINAL_LEG_M` but within reach
    stops ``FINAL_LEG_M / 2`` short of home, so the leg that arrives is a short one.
    """
    remaining = sum(
        math.hypot(b.x - a.x, b.y - a.y) for a, b in zip([here, *route[:-1]], route, strict=True)
    )
    if remaining > FINAL_LEG_M:
        return min(longest_m, remaining - FINAL_LEG_M / 2)
    return longest_m


def _stalled(leg: tuple[Pose2D, float, float], fix: Pose2D) -> Pose2D | None:
    """Where to mark an obstacle when a leg's fixes say it went nowhere, else None.

    Args:
        leg: The fix the leg started from (map frame), the odometry distance walked (m) and
            the direction it set off in (map frame, rad).
        fix: The PnP fix after the leg (map frame).
    """
    start, walked, aim = leg
    if walked < STALL_MIN_M or math.hypot(fix.x - start.x, fix.y - start.y) >= (
        STALL_SHARE * walked
    ):
        return None
    return Pose2D(fix.x, fix.y, aim) * Pose2D(BUMP_AHEAD_M, 0.0)


def _settle(robot: Robot, here: Pose2D, moves: list[Pose2D]) -> tuple[float, Pose2D]:
    """Side-step from ``here`` onto the origin without turning, then turn to face map +x.

    The odometry pose after each move is appended to ``moves``.

    Returns:
        The odometry distance walked (m) and where odometry says it ended (map frame).
    """
    odo0 = pose_of(robot.motion, True)
    step = relative_pose(here, Pose2D(0.0, 0.0, here.theta))
    if robot.motion.moveTo(step.x, step.y, 0.0):
        moves.append(pose_of(robot.motion, True))
        now = here * relative_pose(odo0, moves[-1])
        robot.motion.moveTo(0.0, 0.0, modulo2PI(-now.theta))
    robot.motion.stopMove()
    moves.append(odo := pose_of(robot.motion, True))
    return odo0.distance(odo), here * relative_pose(odo0, odo)


def _walk_straight(robot: Robot, distance_m: float, moves: list[Pose2D]) -> float:
    """Walk forward (False at an obstacle is fine); the odometry distance walked, m.

    The odometry pose after the walk is appended to ``moves``.
    """
    before = pose_of(robot.motion, True)
    robot.motion.moveTo(distance_m, 0.0, 0.0)
    robot.motion.stopMove()
    moves.append(pose_of(robot.motion, True))
    return before.distance(moves[-1])


def _densify(here: Pose2D, route: list[Pose2D], spacing: float = WAYPOINT_M) -> list[Pose2D]:
    """The route with extra waypoints so that none is more than ``spacing`` m from the last."""
    out: list[Pose2D] = []
    prev = here
    for p in route:
        n = max(1, math.ceil(math.hypot(p.x - prev.x, p.y - prev.y) / spacing))
        out += [
            Pose2D(prev.x + (p.x - prev.x) * k / n, prev.y + (p.y - prev.y) * k / n)
            for k in range(1, n)
        ]
        out.append(p)
        prev = p
    return out


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


def _follow(
    robot: Robot,
    start: Pose2D,
    route: list[Pose2D],
    moves: list[Pose2D],
    *,
    ends_home: bool = True,
) -> tuple[bool, float, Pose2D]:
    """Walk through map-frame waypoints by odometry from ``start``.

    Each waypoint is approached facing it; when ``ends_home`` (the leg ends at home, or
    within ``FINAL_LEG_M`` of it), the robot then turns in place to face map +x at the last
    one, as the survey started. Turning apart from walking keeps a NAO's
    turn error (~6 % of the angle) out of where it arrives. The odometry pose after each
    move is appended to ``moves``.

    Returns:
        Whether every move succeeded, the odometry distance walked (m), and where odometry
        says the robot ended (map frame, carried from ``start``).
    """
    odo0 = pose_of(robot.motion, True)
    walked = 0.0
    ok = True
    prev = odo0
    targets: list[Pose2D | None] = list(route)
    if ends_home and route:
        targets.append(None)  # the turn in place to face map +x
    for point in targets:
        here = start * relative_pose(odo0, pose_of(robot.motion, True))
        if point is None:
            move = Pose2D(0.0, 0.0, modulo2PI(-here.theta))
        elif math.hypot(point.x - here.x, point.y - here.y) < 1e-3:
            continue
        else:
            heading = math.atan2(point.y - here.y, point.x - here.x)
            move = relative_pose(here, Pose2D(point.x, point.y, heading))
        moved = robot.motion.moveTo(move.x, move.y, move.theta)
        now = pose_of(robot.motion, True)
        moves.append(now)
        walked += prev.distance(now)
        prev = now
        if not moved:
            robot.motion.stopMove()
            ok = False
            break
    end = start * relative_pose(odo0, pose_of(robot.motion, True))
    return ok, walked, end
