"""Walk back to the map origin (where the survey started) on the live pose.

A short look from standstill starts the filter (:func:`naoloc.behaviours.localize.localize`);
then the robot walks continuously toward home along a path planned over the floor grid the
map implies (:mod:`naoloc.navigation.grid`), steered by pure pursuit
(:mod:`naoloc.navigation.route`) from the belief's pose, which every camera frame updates
while it walks (:class:`naoloc.behaviours.track.Tracker`). It re-plans from the belief every
``go_home.replan_s`` seconds. It stops to look only when the belief is lost, at most
``go_home.max_tries`` looks in all; after a look that found no pose it first steps
``go_home.step_away_m`` away from the walls that look saw near (a robot pressed into a
corner sees too little of the room). Within ``go_home.align_m`` of home it turns to home's
heading as it walks (omnidirectionally). Within ``go_home.approach_m`` of home it stops
walking and steps onto home with short ``moveTo`` steps, refining the belief standing
between them with the floor lines of a standstill look's head sweep (its far yaws see the
walls beside and behind, which the walking head's swing does not: home's position along
the way it faces), until the belief is within ``go_home.tolerance_m`` of home facing map +x as the
survey started.

A robot that touches something while walking (the simulator's contacts; a real NAO's
bumpers are not reachable through the mirrored services) stops; up to
``go_home.contacts`` times it then marks the floor ahead blocked, steps
``go_home.back_off_m`` back and plans around it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from naoloc.behaviours.localize import (
    SCAN_YAWS,
    Localization,
    estimate_fields,
    localize,
    look_lines,
    robot_clock,
    truth_in_map,
)
from naoloc.behaviours.track import Tracker, TrackPoint
from naoloc.behaviours.walk_watch import TOUCHING, touching
from naoloc.config import Config, GoHomeConfig
from naoloc.constants import WALK_SPEED
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.localization.localizer import Localizer, PoseEstimate
from naoloc.localization.observations import LineScan, Relocalize
from naoloc.mapping.map import VisualMap
from naoloc.navigation.clearance import away_from_walls
from naoloc.navigation.grid import BLOCKED, FloorGrid, NoPath, grid_of_map
from naoloc.navigation.route import path_length, pursuit, remaining
from naoloc.robot import Robot, pose_of

__all__ = ["GoHomeResult", "go_home", "next_sweep"]


@dataclass
class GoHomeResult:
    """How going home went.

    Attributes:
        final: The belief's answer at the end (map frame).
        looks: Localizations from standstill (the first one included).
        reached: Whether the belief put the robot within the tolerance of home.
        first: The first look.
        truth: The true final pose in the map frame (simulator), else None.
        error_m: True distance from the map origin at the end, m (simulator), else None.
        path_m: Length of the first planned path, m.
        walked_m: Odometry distance walked, m.
        robot_s: Robot time spent, s.
        trail: The track while walking.
        reason: Why it stopped short (empty when it arrived).
        stops: The estimate of every look from standstill, in order (the first one's too).
    """

    final: PoseEstimate
    looks: int
    reached: bool
    first: Localization
    truth: Pose2D | None = None
    error_m: float | None = None
    path_m: float = 0.0
    walked_m: float = 0.0
    robot_s: float = 0.0
    trail: list[TrackPoint] = field(default_factory=list)
    reason: str = ""
    stops: list[PoseEstimate] = field(default_factory=list)

    @property
    def walk_s(self) -> float:
        """The time to walk the first planned path at a NAO's speed, s."""
        return self.path_m / WALK_SPEED

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``go-home`` line (map frame)."""
        out: dict[str, Any] = {
            **estimate_fields(self.final),
            "tries": self.looks,
            "reached": self.reached,
            "path_m": round(self.path_m, 3),
            "walked_m": round(self.walked_m, 3),
            "robot_s": round(self.robot_s, 2),
            "walk_s": round(self.walk_s, 2),
        }
        if self.first.estimate.found:
            e = self.first.estimate
            out["start"] = [round(e.x, 4), round(e.y, 4), round(e.theta, 4)]
        if self.reason:
            out["reason"] = self.reason
        if self.truth is not None and self.error_m is not None:
            out["error_m"] = round(self.error_m, 4)
            out["truth"] = [round(v, 4) for v in self.truth]
        return out


def go_home(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    on_point: Callable[[TrackPoint], None] | None = None,
    on_step: Callable[[str], None] | None = None,
    localizer: Localizer | None = None,
) -> GoHomeResult:
    """Walk to the map origin on the live pose (see the module doc).

    Args:
        robot: The robot, anywhere in the mapped room.
        vmap: The map.
        cfg: Config (``go_home``, ``localize``, cameras).
        on_point: Called with every pose while walking (live view).
        on_step: Called with a short note as the work advances.
        localizer: The filter to use (e.g. one tracking already); a new one otherwise.

    Returns:
        How it went; the robot is stopped.
    """
    r0 = robot_clock(robot)
    home = Pose2D(0.0, 0.0, 0.0)
    gh = cfg.go_home
    tol = gh.tolerance_m
    loc = localizer if localizer is not None else Localizer(vmap, cfg.localize.filter)
    first = localize(robot, vmap, cfg, localizer=loc)
    last = first
    looks = 1
    result = GoHomeResult(first.estimate, looks, False, first)
    result.stops.append(first.estimate)
    grid = grid_of_map(vmap)
    odo0 = robot.motion.getRobotPosition(True)
    tracker = Tracker(robot, loc, cfg)
    route: list[Pose2D] = []
    planned_at = -math.inf
    lost = bumps = 0
    budget = gh.min_time_s
    try:
        while True:
            est = loc.pose()
            if not est.found:
                lost += 1
                if lost < gh.lost_frames and route:
                    result.trail.append(_point(tracker, on_point))
                    continue
                robot.motion.stopMove()
                if looks >= gh.max_tries:
                    result.reason = f"lost, and {looks} looks found no pose"
                    break
                if on_step is not None:
                    on_step("lost: stopping to look")
                if not last.estimate.found and not _step_away(robot, last, cfg):
                    result.reason = f"blocked: {TOUCHING}, stepping away from a wall"
                    break
                # Lost: the belief is worth nothing; look from standstill, globally.
                loc.update(Relocalize(robot_clock(robot)))
                last = localize(robot, vmap, cfg, localizer=loc)
                result.stops.append(last.estimate)
                looks += 1
                route, lost = [], 0
                continue
            lost = 0
            here = est.pose()
            now = robot_clock(robot)
            if now - r0 > budget:
                result.reason = f"gave up after {now - r0:.0f} s"
                break
            if math.hypot(here.x - home.x, here.y - home.y) <= max(tol, gh.approach_m):
                robot.motion.stopMove()
                result.reached = _final_approach(robot, tracker, loc, home, gh, result, on_point)
                if result.reached:
                    break
                continue  # still short, or the belief lost there: walk on, or look again
            if not route or now - planned_at > gh.replan_s:
                try:
                    route = grid.plan(here, home)
                except NoPath as err:
                    result.reason = f"no path home: {err}"
                    break
                if planned_at == -math.inf:
                    result.path_m = path_length(here, route)
                    budget = max(gh.min_time_s, gh.time_per_m_s * result.path_m)
                planned_at = now
            route = remaining(route, here, gh.reached_m)
            cmd = pursuit(here, route, goal_theta=home.theta, align_m=gh.align_m)
            robot.motion.move(cmd.x, cmd.y, cmd.theta)
            result.trail.append(_point(tracker, on_point))
            if touching(robot):  # a robot that is blocked stops
                robot.motion.stopMove()
                if bumps >= gh.contacts:
                    result.reason = f"blocked: {TOUCHING}"
                    break
                bumps += 1
                if on_step is not None:
                    on_step("touched something: backing off to go around it")
                if not _back_off(robot, grid, loc.pose(), gh):
                    result.reason = f"blocked: {TOUCHING}, and backing off did not free it"
                    break
                route = []  # re-plan around it
    finally:
        robot.motion.stopMove()
        tracker.close()
    odo1 = robot.motion.getRobotPosition(True)
    result.walked_m = math.hypot(odo1[0] - odo0[0], odo1[1] - odo0[1])
    result.final = loc.pose()
    result.looks = looks
    result.robot_s = robot_clock(robot) - r0
    truth = truth_in_map(robot, vmap.meta)
    if truth is not None:
        result.truth = truth
        result.error_m = math.hypot(truth.x - home.x, truth.y - home.y)
    return result


def _step_away(robot: Robot, look: Localization, cfg: Config) -> bool:
    """After a look that found no pose: step ``go_home.step_away_m`` away from the walls
    that look's floor lines saw within ``go_home.near_wall_m`` (pressed into a corner or
    facing a wall from a few decimetres the cameras see too little of the room), blocking.
    No step when no wall was near or the walls around cancel out.

    Returns:
        Whether the robot stands free afterwards (the simulator's contacts).
    """
    step = cfg.go_home.step_away_m
    if step <= 0.0:
        return True
    scans = [o for o in look.observations if isinstance(o, LineScan)]
    way = away_from_walls(scans, pose_of(robot.motion, True), cfg.go_home.near_wall_m)
    if way is None:
        return True
    try:
        robot.motion.moveTo(step * way[0], step * way[1], 0.0)
    finally:
        robot.motion.stopMove()
    return not touching(robot)


def _back_off(robot: Robot, grid: FloorGrid, est: PoseEstimate, gh: GoHomeConfig) -> bool:
    """After a contact ahead (the robot is stopped): mark the floor just ahead of the belief's
    pose blocked in ``grid`` (furniture the map's landmarks did not show: a disc of
    ``gh.contact_radius_m`` ``gh.contact_ahead_m`` ahead) and step ``gh.back_off_m`` straight
    back, blocking.

    Returns:
        Whether the robot stands free of the contact afterwards.
    """
    if est.found:
        here = est.pose()
        grid.mark(
            here.x + gh.contact_ahead_m * math.cos(here.theta),
            here.y + gh.contact_ahead_m * math.sin(here.theta),
            gh.contact_radius_m,
            BLOCKED,
            force=True,
        )
    try:
        robot.motion.moveTo(-gh.back_off_m, 0.0, 0.0)
    finally:
        robot.motion.stopMove()
    return not touching(robot)


def _point(
    tracker: Tracker, on_point: Callable[[TrackPoint], None] | None, frame: bool = True
) -> TrackPoint:
    """The tracker's next pose (``frame``: a camera frame, else the odometry alone), shown."""
    point = tracker.step() if frame else tracker.tick()
    if on_point is not None:
        on_point(point)
    return point


def next_sweep(yaws: tuple[float, ...], head_yaw: float) -> tuple[float, ...]:
    """The head yaws of a sweep (rad) in the order that moves the head least from
    ``head_yaw``: from the nearer end of the range to the other.

    A floor-line sweep's order does not matter to the filter, the head's travel does: after
    a sweep that ended at -2 rad, the next goes up from there (4 rad) rather than back
    through the middle (8 rad).
    """
    ascending = tuple(sorted(yaws))
    if abs(head_yaw - ascending[-1]) < abs(head_yaw - ascending[0]):
        return ascending[::-1]
    return ascending


def _final_approach(
    robot: Robot,
    tracker: Tracker,
    loc: Localizer,
    home: Pose2D,
    gh: GoHomeConfig,
    result: GoHomeResult,
    on_point: Callable[[TrackPoint], None] | None,
) -> bool:
    """Short steps onto home, facing map +x (the survey's start heading).

    Standing, the head sweeps as a standstill look's does (:data:`SCAN_YAWS`; each later
    sweep from where the last one ended, :func:`next_sweep`) and the
    bottom camera's floor lines at each yaw go to the filter: the far yaws see the walls
    beside and behind, so the belief knows home's position along the way the robot faces,
    where the walking head's swing sees only landmarks. Then one blocking ``moveTo`` to
    where the belief puts home; at most ``gh.final_steps`` steps. The filter takes every
    step's odometry.

    Returns:
        Whether the belief ends within ``gh.tolerance_m`` of home, facing +x within 0.1 rad.
    """
    tol = gh.tolerance_m
    yaws: tuple[float, ...] = SCAN_YAWS
    for step in range(gh.final_steps + 1):
        for yaw in yaws:
            look_lines(tracker.eyes, loc, yaw)
            result.trail.append(_point(tracker, on_point, frame=False))
        yaws = next_sweep(SCAN_YAWS, yaws[-1])
        est = loc.pose()
        if not est.found:
            return False
        here = est.pose()
        rel = relative_pose(here, home)  # home in FRAME_ROBOT now
        dist = math.hypot(rel.x, rel.y)
        near = dist <= tol
        if near and abs(modulo2PI(home.theta - here.theta)) <= 0.1:
            return True
        if step == gh.final_steps or dist > 2 * gh.approach_m:
            return near
        try:
            if near:  # only the heading is left
                robot.motion.moveTo(0.0, 0.0, modulo2PI(home.theta - here.theta))
            else:
                robot.motion.moveTo(rel.x, rel.y, rel.theta)
        finally:
            robot.motion.stopMove()
    return False
