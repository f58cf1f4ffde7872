"""Algorithm 3 of the paper: closed laps of a rectangle, a picture of the wall after each step.

The start pose is the map origin (O_w = getRobotPosition(True) before the first step). The
head turns toward the nearest wall (or ``survey.head_yaw_rad``) and stays there; the body
turns by ``-head_yaw`` at each corner, so a wall on the right gives a counter-clockwise
circuit. Each step is a ``moveTo`` toward the next waypoint of the rectangle in the map
frame, computed from the odometry, so odometry errors do not accumulate into the path
the robot believes it walked. After each step the pose and a picture are recorded.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from naoloc.behaviours.camera import Camera, look, stand
from naoloc.behaviours.nearest_wall import (
    ParallaxWall,
    WallSide,
    detect_nearest_wall,
    detect_wall_by_parallax,
)
from naoloc.config import Config
from naoloc.errors import MotionError
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.keyframe import Keyframe
from naoloc.robot import Robot, pose_of

FrameSink = Callable[[Keyframe, int, Pose2D], None]
"""Called with (keyframe, lap, raw FRAME_WORLD odometry) right after each picture."""

StartHook = Callable[[dict[str, Any]], None]
"""Called once with the survey meta (JSON-able) before the first step."""


@dataclass(frozen=True, slots=True)
class Waypoint:
    """One target of the circuit in the map frame.

    Attributes:
        pose: Target pose in the map frame (m, rad).
        picture: True when a picture is taken on arrival (after a step, not after a turn).
        lap: Lap number (0-based).
        closes_lap: True for the corner turn that ends a lap.
    """

    pose: Pose2D
    picture: bool
    lap: int
    closes_lap: bool = False


@dataclass
class SurveyResult:
    """What a survey did.

    Attributes:
        frames: Pictures taken.
        laps: Laps completed.
        path_m: Distance walked according to odometry, m.
        wall_s: Wall-clock seconds of the survey.
        head_yaw: HeadYaw kept while walking, rad.
        wall: The paper's nearest-wall detection (always run and recorded; not steered by).
        parallax: The parallax detection that chose the side, when nothing overrode it.
        yaw_source: Where the head yaw came from: "parallax", "config" or "caller".
        meta: The meta handed to the start hook.
    """

    frames: int = 0
    laps: int = 0
    path_m: float = 0.0
    wall_s: float = 0.0
    head_yaw: float = 0.0
    wall: WallSide | None = None
    parallax: ParallaxWall | None = None
    yaw_source: str = "parallax"
    meta: dict[str, Any] = field(default_factory=dict)


def circuit(sides: tuple[float, float], step: float, laps: int, turn: float) -> list[Waypoint]:
    """The waypoints of ``laps`` closed laps of a rectangle starting at the map origin.

    Args:
        sides: ``(along x, along y)`` side lengths in metres; the first side is along the
            robot's initial heading (map x).
        step: Nominal step between pictures, m; each side is cut into equal steps.
        laps: Number of laps.
        turn: Body turn at each corner, rad (+pi/2 counter-clockwise, -pi/2 clockwise).

    Returns:
        Waypoints in walking order: the steps of a side (with pictures), then the corner turn.
    """
    points: list[Waypoint] = []
    x = y = heading = 0.0
    for lap in range(laps):
        for k in range(4):
            side = sides[k % 2]
            n = max(1, round(side / step))
            c, s = math.cos(heading), math.sin(heading)
            x0, y0 = x, y
            for i in range(1, n + 1):
                d = side * i / n
                points.append(Waypoint(Pose2D(x0 + c * d, y0 + s * d, heading), True, lap))
            x, y = x0 + c * side, y0 + s * side
            heading = modulo2PI(heading + turn)
            points.append(Waypoint(Pose2D(x, y, heading), False, lap, k == 3))
    return points


def frames_per_lap(sides: tuple[float, float], step: float) -> int:
    """Pictures per lap: about 4 d / p."""
    return 2 * (max(1, round(sides[0] / step)) + max(1, round(sides[1] / step)))


def walk_to(robot: Robot, target: Pose2D, here: Pose2D) -> None:
    """``moveTo`` the map-frame ``target`` from where odometry says the robot is.

    Args:
        robot: The robot.
        target: Target pose in the map frame.
        here: The robot's odometry pose in the map frame now (the caller read it after the
            previous step; the robot has stood still since).

    Raises:
        MotionError: ``moveTo`` reports failure.
    """
    move = relative_pose(here, target)
    if not robot.motion.moveTo(move.x, move.y, move.theta):
        raise MotionError(
            f"moveTo({move.x:.2f}, {move.y:.2f}, {move.theta:.2f}) failed on the way to "
            f"({target.x:.2f}, {target.y:.2f}) in the map frame"
        )


def survey(
    robot: Robot,
    cfg: Config,
    on_frame: FrameSink,
    *,
    on_start: StartHook | None = None,
    progress: Callable[[int], None] | None = None,
    head_pitch: float | None = None,
    head_yaw: float | None = None,
) -> SurveyResult:
    """Walk ``cfg.survey.laps`` closed laps and record a picture after each step.

    The robot stands up, runs the paper's nearest-wall detector (recorded) and turns its
    head to a wall: ``cfg.survey.head_yaw_rad`` if set, else ``head_yaw`` if given, else the
    side the parallax detector finds (the paper's image cue is weak, and a wrong side walks
    the robot into a wall; the probe steps forward and back, so the start pose is kept).
    Then it records the origin and walks. Motion is stopped on every
    exit path (an exception or Ctrl-C included); frames already handed to ``on_frame``
    stay with the caller.

    Args:
        robot: The robot, standing where the survey starts (that pose is the map origin).
        cfg: Config; uses ``survey`` (laps, step_m, head_yaw_rad), :meth:`Config.survey_sides`
            and ``camera``.
        on_frame: Receives each keyframe (pose in the map frame), its lap and the raw
            FRAME_WORLD odometry, as soon as it is taken.
        on_start: Receives the survey meta before the first step: camera, origin,
            origin_room_pose and room_size_m on a simulator, head angles, direction.
        progress: Called with the number of new frames after each picture.
        head_pitch: Head pitch while walking, rad; None = ``cfg.survey.head_pitch_rad``.
        head_yaw: Head yaw to use instead of the detector's (rad), e.g. known from the
            room's layout; ``cfg.survey.head_yaw_rad`` still wins.

    Returns:
        The survey's summary.

    Raises:
        MotionError: A step failed (the robot is stopped; frames so far were delivered).
        RobotError: A service refused a call.
    """
    t0 = time.monotonic()
    result = SurveyResult()
    head_pitch = cfg.survey.head_pitch_rad if head_pitch is None else head_pitch
    sides = cfg.survey_sides()
    try:
        stand(robot)
        with Camera(robot, cfg.camera, "naoloc_survey") as camera:
            result.wall = detect_nearest_wall(robot, camera, head_pitch)
            if cfg.survey.head_yaw_rad is not None:
                yaw = cfg.survey.head_yaw_rad
                result.yaw_source = "config"
            elif head_yaw is not None:
                yaw = head_yaw
                result.yaw_source = "caller"
            else:
                result.parallax = detect_wall_by_parallax(
                    robot, camera, cfg.survey.step_m, head_pitch
                )
                yaw = result.parallax.head_yaw
                result.yaw_source = "parallax"
            yaw, pitch = look(robot, yaw, head_pitch)
            result.head_yaw = yaw
            turn = -math.copysign(math.pi / 2, yaw) if yaw != 0 else math.pi / 2
            origin = pose_of(robot.motion, True)
            command_origin = pose_of(robot.motion, False)
            probe = camera.info(camera.frame())
            result.meta = _meta(
                robot, cfg, origin, probe, yaw, pitch, turn, result.wall, result.parallax
            )
            result.meta["head_yaw_source"] = result.yaw_source
            if on_start is not None:
                on_start(result.meta)
            here = Pose2D()
            for point in circuit(sides, cfg.survey.step_m, cfg.survey.laps, turn):
                before = here
                walk_to(robot, point.pose, here)
                if point.picture:  # the keyframe's odometry reading is where the robot is
                    keyframe, odometry = camera.keyframe(origin, command_origin)
                    here = keyframe.pose
                    on_frame(keyframe, point.lap, odometry)
                    result.frames += 1
                    if progress is not None:
                        progress(1)
                else:
                    here = relative_pose(origin, pose_of(robot.motion, True))
                    if point.closes_lap:
                        result.laps = point.lap + 1
                result.path_m += before.distance(here)
    finally:
        robot.motion.stopMove()
        result.wall_s = time.monotonic() - t0
    return result


def _meta(
    robot: Robot,
    cfg: Config,
    origin: Pose2D,
    camera: Any,
    yaw: float,
    pitch: float,
    turn: float,
    wall: WallSide | None,
    parallax: ParallaxWall | None = None,
) -> dict[str, Any]:
    sides = cfg.survey_sides()
    meta: dict[str, Any] = {
        "backend": robot.backend,
        "origin_odometry": origin.to_list(),
        "camera": {
            "width": camera.width,
            "height": camera.height,
            "hfov": camera.hfov,
            "vfov": camera.vfov,
            "index": camera.index,
        },
        "head_yaw": yaw,
        "head_pitch": pitch,
        "direction": "ccw" if turn > 0 else "cw",
        "sides_m": list(sides),
        "step_m": cfg.survey.step_m,
        "laps": cfg.survey.laps,
        "frames_per_lap": frames_per_lap(sides, cfg.survey.step_m),
        "nearest_wall": None
        if wall is None
        else {"side": wall.side, "left": wall.left, "right": wall.right},
    }
    if parallax is not None:
        meta["parallax"] = {
            "side": parallax.side,
            "left_shift_px": _finite_or_none(parallax.left_shift_px),
            "right_shift_px": _finite_or_none(parallax.right_shift_px),
            "left_matches": parallax.left_matches,
            "right_matches": parallax.right_matches,
        }
    if robot.sim is not None:
        meta["origin_room_pose"] = list(robot.sim.true_pose())
        meta["room_size_m"] = list(robot.sim.room_size())
    return meta


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None
