"""Tracking while the robot walks: every camera frame goes to the filter.

A :class:`Tracker` takes one observation per step, alternating a top-camera picture (the
map's landmarks) and a bottom-camera floor picture (the walls' feet), while the head
swings between :data:`WALK_YAWS` without stopping (non-blocking ``setAngles``: the pictures
record the head angles they were taken at). It moves nothing else; a behaviour walks the
robot (:func:`walk_route`, ``go_home``) and calls :meth:`Tracker.step` in its control loop.

:func:`track` is ``naoloc track``: a short look from standstill, then a walk along a route
(or standing still) with the pose at every frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from naoloc.behaviours.localize import Eyes, Localization, localize, robot_clock, truth_in_map
from naoloc.behaviours.walk_watch import touching
from naoloc.config import Config
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.localization.localizer import Localizer, PoseEstimate
from naoloc.localization.observations import Odometry
from naoloc.mapping.map import VisualMap
from naoloc.navigation.route import pursuit, remaining
from naoloc.robot import Robot, pose_of

__all__ = ["WALK_YAWS", "TrackPoint", "TrackResult", "Tracker", "track", "walk_route"]

# Head yaws the head swings between while walking (rad), and its pitch (rad; the top camera
# sees the art, the bottom one the floor 1-3 m out) and speed (fraction of the maximum).
WALK_YAWS: tuple[float, ...] = (0.9, 0.0, -0.9, 0.0)
WALK_PITCH = -0.45
WALK_HEAD_SPEED = 0.2


@dataclass(frozen=True)
class TrackPoint:
    """One pose of a track.

    Attributes:
        t: Robot time, s.
        estimate: The filter's answer then.
        truth: The true pose in the map frame (simulator), else None.
        cpu_s: CPU seconds the observation cost (detection, features, filter).
        frame: Whether a camera frame updated it (else the odometry alone moved it).
    """

    t: float
    estimate: PoseEstimate
    truth: Pose2D | None
    cpu_s: float
    frame: bool = True

    @property
    def error_m(self) -> float | None:
        """Distance from the estimate to the truth (m), None without either."""
        if self.truth is None or not self.estimate.found:
            return None
        return math.hypot(self.estimate.x - self.truth.x, self.estimate.y - self.truth.y)

    def to_json(self) -> dict[str, object]:
        """One JSON line of ``naoloc track`` (map frame)."""
        e = self.estimate
        out: dict[str, object] = {"t": round(self.t, 3), "status": str(e.status)}
        if e.found:
            out.update(x=round(e.x, 4), y=round(e.y, 4), theta=round(e.theta, 4),
                       confidence=round(e.confidence, 4))  # fmt: skip
            if e.covariance is not None:
                out["covariance"] = [[round(float(v), 8) for v in r] for r in e.covariance]
        else:
            out.update(x=None, y=None, theta=None, confidence=0.0, reason=e.reason)
        if self.truth is not None:
            out["truth"] = [round(v, 4) for v in self.truth]
            err = self.error_m
            if err is not None:
                out["error_m"] = round(err, 4)
        return out


class Tracker:
    """Feeds the filter one camera frame per step while something else moves the robot.

    Args:
        robot: The robot.
        loc: The filter to feed.
        cfg: Config (cameras, lens; ``go_home.reached_m`` for :func:`walk_route`).
        eyes: Open cameras to use (closed by the caller); opened here otherwise.
    """

    def __init__(self, robot: Robot, loc: Localizer, cfg: Config, eyes: Eyes | None = None) -> None:
        self.robot = robot
        self.loc = loc
        self.reached_m = cfg.go_home.reached_m
        self.meta = loc.vmap.meta
        self._own = eyes is None
        self.eyes = (
            eyes if eyes is not None else Eyes(robot, cfg, lines=loc.filter.walls is not None)
        )
        self.k = 0

    def step(self) -> TrackPoint:
        """Aim the head (without waiting), take the next frame, update the filter."""
        yaw = WALK_YAWS[(self.k // 2) % len(WALK_YAWS)]
        if self.k % 2 == 0:
            self.robot.motion.setAngles(
                ["HeadYaw", "HeadPitch"], [yaw, WALK_PITCH], WALK_HEAD_SPEED
            )
        cpu0 = self.loc.cpu_s + self.eyes.detect_s
        if self.k % 2 == 0 or self.eyes.floor is None:
            self.loc.update(self.eyes.picture())
        else:
            scan = self.eyes.line_scan()
            if scan is not None:
                self.loc.update(scan)
        self.k += 1
        cpu = self.loc.cpu_s + self.eyes.detect_s - cpu0
        return TrackPoint(
            robot_clock(self.robot), self.loc.pose(), truth_in_map(self.robot, self.meta), cpu
        )

    def tick(self) -> TrackPoint:
        """The pose now from the odometry alone (between frames: the belief moved by the
        walk since the last frame, as a robot's tf publishes map -> base_link)."""
        motion = self.robot.motion
        self.loc.update(Odometry(pose_of(motion, True), robot_clock(self.robot)))
        return TrackPoint(
            robot_clock(self.robot), self.loc.pose(), truth_in_map(self.robot, self.meta), 0.0,
            frame=False,
        )  # fmt: skip

    def close(self) -> None:
        """Close the cameras this tracker opened."""
        if self._own:
            self.eyes.close()


@dataclass
class TrackResult:
    """A track: the first look and every pose while walking.

    Attributes:
        first: The standstill localization that started it.
        points: The poses, one per frame.
        walked_m: Odometry distance walked, m.
        reason: Why it stopped early ("" when the route or time ended).
    """

    first: Localization
    points: list[TrackPoint] = field(default_factory=list)
    walked_m: float = 0.0
    reason: str = ""


def walk_route(
    robot: Robot,
    tracker: Tracker,
    route: Sequence[Pose2D],
    *,
    max_s: float,
    on_point: Callable[[TrackPoint], None] | None = None,
    lost_steps: int = 20,
    ticks: int = 2,
) -> tuple[list[TrackPoint], str]:
    """Walk along ``route`` (map frame) steering by the belief, tracking at every frame.

    A waypoint within ``go_home.reached_m`` of the belief's pose counts as passed
    (:attr:`Tracker.reached_m`). The robot stops when the belief's pose reaches the last
    waypoint, when ``max_s`` of robot time have passed, or when the belief has been lost
    for ``lost_steps`` frames (it is then stopped for the caller to look), or when the body
    touches a wall or furniture (:func:`naoloc.behaviours.walk_watch.touching`). It is
    stopped on every exit. Between frames, ``ticks`` odometry-only poses keep the pose live
    at the odometry's rate.

    Returns:
        The track's points and why it stopped (``arrived``, ``time``, ``lost``,
        ``blocked``).
    """
    points: list[TrackPoint] = []
    left = list(route)
    start = robot_clock(robot)
    unsure = 0
    why = "time"
    steer = None
    reach = tracker.reached_m
    try:
        while robot_clock(robot) - start < max_s:
            point = tracker.step()
            points.append(point)
            if on_point is not None:
                on_point(point)
            if touching(robot):  # a robot that is blocked stops
                why = "blocked"
                break
            if steer is not None:  # the command stands until the next frame's: odometry poses
                for _ in range(ticks):
                    tick = tracker.tick()
                    points.append(tick)
                    if on_point is not None:
                        on_point(tick)
            est = point.estimate
            if not est.found:
                unsure += 1
                if unsure >= lost_steps:
                    why = "lost"
                    break
                continue  # keep the last command: the odometry carries the belief
            unsure = 0
            here = est.pose()
            left = remaining(left, here, reach)
            if len(left) == 1 and math.hypot(left[0].x - here.x, left[0].y - here.y) < reach:
                why = "arrived"
                break
            steer = pursuit(here, left)
            robot.motion.move(steer.x, steer.y, steer.theta)
    finally:
        robot.motion.stopMove()
    return points, why


def track(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    route: Sequence[Pose2D] = (),
    duration_s: float = 20.0,
    on_point: Callable[[TrackPoint], None] | None = None,
    localizer: Localizer | None = None,
) -> TrackResult:
    """Localize from standstill, then track the pose while walking ``route`` (map frame).

    Without a route the robot stands and the head keeps swinging: the pose streams at the
    camera's rate for ``duration_s`` of robot time. ``localizer``: the filter to feed (e.g.
    one that records); a new one otherwise.
    """
    loc = localizer if localizer is not None else Localizer(vmap, cfg.localize.filter)
    first = localize(robot, vmap, cfg, localizer=loc)
    result = TrackResult(first)
    if not first.estimate.found:
        result.reason = first.estimate.reason or "no pose to start from"
        return result
    tracker = Tracker(robot, loc, cfg)
    try:
        start = robot.motion.getRobotPosition(True)
        if route:
            points, why = walk_route(robot, tracker, route, max_s=duration_s, on_point=on_point)
        else:
            points, why = [], "time"
            t0 = robot_clock(robot)
            while robot_clock(robot) - t0 < duration_s:
                p = tracker.step()
                points.append(p)
                if on_point is not None:
                    on_point(p)
        end = robot.motion.getRobotPosition(True)
        result.walked_m = math.hypot(end[0] - start[0], end[1] - start[1])
        result.points = points
        result.reason = "" if why in ("arrived", "time") else why
    finally:
        robot.motion.stopMove()
        tracker.close()
    return result


def heading_error_deg(est: PoseEstimate, truth: Pose2D) -> float:
    """Wrapped heading error, degrees."""
    return math.degrees(abs(modulo2PI(est.theta - truth.theta)))
