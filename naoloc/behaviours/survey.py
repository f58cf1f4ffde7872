"""Algorithm 3 of the paper: closed laps of a rectangle, a picture of the wall after each step.

The start pose is the map origin (O_w = getRobotPosition(True) before the first step). The
head turns toward the nearest wall (or ``survey.head_yaw_rad``) and stays there; the body
turns by ``-head_yaw`` at each corner, so a wall on the right gives a counter-clockwise
circuit. A NAO's odometry drifts (10 % distance scale, several degrees per corner), so the
walk is steered by vision: after each step the bottom camera measures the side wall's
floor-wall line and the next step goes back to ``survey.wall_offset_m`` and parallel to
the wall (bounded corrections, :mod:`naoloc.behaviours.wall_follow`); near each corner
the head looks ahead and the front wall's line says where to turn. After each step the
odometry pose and a picture are recorded (the map's input), and the survey meta gets the
vision measurements per frame (``vision``) and the metric scale of the odometry
(``metric_scale``, metres per odometry metre, from the front wall's distances), which
build-map applies. :func:`circuit` gives the nominal waypoints of that rectangle.

Beyond the paper, each stop also photographs the room across its interior
(``survey.far_yaws_rad``, ``survey.far_per_stop``, at ``survey.far_pitch_rad``): the wall
ahead and the far walls, 1-7 m away. The wall pictures alone show every wall from the
circuit's 1 m, so a robot near a wall, looking across the room at walls 5 m off, matched
nothing; the far pictures go to a separate sink and build-map gives them to the verified
localizer only (docs/history/RESULTS.md, "Issue 12, eleventh step").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.behaviours.nearest_wall import (
    FloorLineWall,
    ParallaxWall,
    WallSide,
    decide_side,
    detect_nearest_wall,
    detect_wall_by_floorline,
)
from naoloc.behaviours.walk_watch import WalkWatch
from naoloc.behaviours.wall_follow import (
    BESIDE_VIEW,
    FLOOR_BEYOND_M,
    FRONT_PITCH,
    MIN_KEEP_M,
    MIN_OFFSET_M,
    FloorEye,
    FrontSample,
    SideMemory,
    corrected_step,
    heading_views,
    line_dict,
    look_for_line,
    measure_front,
    measure_side,
    measure_side_views,
    median_line,
    metric_scale,
    trusted,
)
from naoloc.config import Config
from naoloc.errors import ConfigError, MotionError, SurveyError
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.perception.floorline import WallLine
from naoloc.perception.wall_gate import crosses_path, in_far_front_range, in_front_range
from naoloc.robot import Robot, pose_of
from naoloc.robot.camera import Camera, clamp_head, lens_of, look, stand
from naoloc.robot.keyframe import Keyframe

FRONT_LOOKAHEAD_M = 1.0  # start looking at the front wall this far before the corner
MAX_EXTRA_STEPS = 8  # steps a side may take beyond its planned count (odometry too short)
PROBE_STEP_M = 0.4  # the nearest-wall detector's step out of a corner, m
PROBE_CLEAR_M = 0.45  # room the body needs beyond the step before the wall ahead, m

FrameSink = Callable[[Keyframe, int, Pose2D], None]
"""Called with (keyframe, lap, raw FRAME_WORLD odometry) right after each picture."""

FarSink = Callable[[Keyframe, int, int, Pose2D], None]
"""Called with (far keyframe, lap, its stop: the number of wall pictures before the stop's
own, raw FRAME_WORLD odometry) right after the stop's wall picture went to the frame sink."""

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
        far_frames: Far pictures taken (``survey.far_yaws_rad``), not counted in ``frames``.
        head_yaw: HeadYaw kept while walking, rad.
        wall: The paper's nearest-wall detection (always run and recorded; not steered by).
        parallax: The parallax detection that chose the side, when the floor lines did not.
        floorline: The floor-wall line detection (left and right distances), when run.
        yaw_source: Where the head yaw came from: "floorline", "parallax", "config" or
            "caller".
        meta: The meta handed to the start hook.
    """

    frames: int = 0
    far_frames: int = 0
    laps: int = 0
    path_m: float = 0.0
    wall_s: float = 0.0
    head_yaw: float = 0.0
    wall: WallSide | None = None
    parallax: ParallaxWall | None = None
    floorline: FloorLineWall | None = None
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
    on_far: FarSink | None = None,
    result: SurveyResult | None = None,
) -> SurveyResult:
    """Walk ``cfg.survey.laps`` closed laps and record a picture after each step.

    An offset below :data:`naoloc.behaviours.wall_follow.MIN_OFFSET_M` is refused before
    the robot moves. The robot stands up, runs the paper's nearest-wall detector (recorded)
    and turns its head to a wall: ``cfg.survey.head_yaw_rad`` if set, else ``head_yaw`` if
    given, else the side whose floor-wall line (bottom camera, looked for beside and behind
    the arm) is nearer ``survey.wall_offset_m`` (the distance the robot was set from its
    wall; furniture beside it reads nearer); a side that shows no line is unseen, not
    far, and when no side can be told the survey stops before walking. Then it records
    the origin and walks, steered by the floor-wall lines and watched by the robot's own
    evidence (:func:`_walk_laps`, :class:`naoloc.behaviours.walk_watch.WalkWatch`). Motion
    is stopped on every exit path (an exception or Ctrl-C included); frames already handed to
    ``on_frame`` stay with the caller.

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
        on_far: Receives each far picture (``survey.far_yaws_rad``: the room across its
            interior, taken at each stop after the wall picture) with its lap and stop;
            None takes no far pictures.
        result: Filled in as the survey goes and returned (a caller that passes one keeps
            what the survey measured, ``meta`` included, when it raises).

    Returns:
        The survey's summary.

    Raises:
        ConfigError: ``survey.wall_offset_m`` is below the smallest offset that works.
        SurveyError: Neither side shows a floor line to follow (nothing was walked).
        SurveyBlocked: The robot's evidence says a step did not happen (blocked, pressed
            or sliding), or ``moveTo`` failed (the robot is stopped; frames so far were
            delivered).
        RobotError: A service refused a call.
    """
    check_offset(cfg.survey.wall_offset_m)
    t0 = time.monotonic()
    result = SurveyResult() if result is None else result
    head_pitch = cfg.survey.head_pitch_rad if head_pitch is None else head_pitch
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
                yaw = _detect_side(robot, cfg, head_pitch, result)
            yaw, pitch = look(robot, yaw, head_pitch)
            result.head_yaw = yaw
            turn = -math.copysign(math.pi / 2, yaw) if yaw != 0 else math.pi / 2
            origin = pose_of(robot.motion, True)
            command_origin = pose_of(robot.motion, False)
            probe = camera.info(camera.frame())
            result.meta.update(
                _meta(robot, cfg, origin, probe, yaw, pitch, turn, result.wall, result.parallax)
            )
            result.meta["head_yaw_source"] = result.yaw_source
            result.meta["lens"] = lens_of(cfg).to_dict()  # undone by build-map and localize
            if result.floorline is not None:
                result.meta["floorline_wall"] = {
                    "side": result.floorline.side,
                    "left_m": result.floorline.left_m,
                    "right_m": result.floorline.right_m,
                }
            if on_start is not None:
                on_start(result.meta)
            eye = FloorEye(robot, cfg.camera, lens=lens_of(cfg))
            try:
                _walk_laps(robot, cfg, camera, eye, origin, command_origin, yaw, pitch, turn,
                           result, on_frame, progress, on_far, probe.fx)  # fmt: skip
            finally:
                eye.close()
    finally:
        robot.motion.stopMove()
        result.wall_s = time.monotonic() - t0
    return result


def check_offset(offset: float) -> None:
    """Refuse a wall offset the survey cannot keep, before the robot moves.

    Raises:
        ConfigError: ``offset`` is below :data:`naoloc.behaviours.wall_follow.MIN_OFFSET_M`.
    """
    if offset < MIN_OFFSET_M:
        raise ConfigError(
            f"survey.wall_offset_m {offset:g} m is too near the walls: the bottom camera does "
            f"not see a wall's foot that near beside the robot; the smallest offset that "
            f"works is {MIN_OFFSET_M:g} m"
        )


def _detect_side(robot: Robot, cfg: Config, head_pitch: float, result: SurveyResult) -> float:
    """Head yaw toward the nearer side wall from the floor lines seen (beside and behind
    the arm, :func:`detect_wall_by_floorline` with the survey's offset).

    Raises:
        SurveyError: No side can be told from the lines seen (before any step).
    """
    eye = FloorEye(robot, cfg.camera, "naoloc_side", lens=lens_of(cfg))
    offset = cfg.survey.wall_offset_m
    try:
        seen = detect_wall_by_floorline(robot, eye, head_pitch, offset=offset)
        if seen.side is None and None in (seen.left_m, seen.right_m):
            seen = _look_after_a_step(robot, eye, seen, offset, cfg.survey_sides()[0])
    finally:
        eye.close()
    result.floorline = seen
    if seen.side is None:

        def where(d: float | None) -> str:
            return "no floor line" if d is None else f"a floor line {d:.2f} m away"

        raise SurveyError(
            f"no wall to follow: the left shows {where(seen.left_m)} and the right "
            f"{where(seen.right_m)}; put the robot {offset:g} m (survey.wall_offset_m) "
            "from a wall and parallel to it, or set survey.head_yaw_rad"
        )
    result.yaw_source = "floorline"
    return seen.head_yaw


def _look_after_a_step(
    robot: Robot, eye: FloorEye, seen: FloorLineWall, offset: float, first_side: float
) -> FloorLineWall:
    """Look again for the unseen sides' lines :data:`PROBE_STEP_M` ahead, then step back.

    In a corner the views behind the arm see two walls meeting and no line; a small step
    along the wall clears the corner. No step when the circuit's first side
    (``first_side``, m) is shorter than the step, or a front wall's line seen leaves less
    room than the step and the body (none seen: the wall is beyond the bottom camera's
    2.6 m, and the first side says the way is free).

    Returns:
        The detection with the lines seen after the step for the sides unseen before.

    Raises:
        MotionError: The probe step failed.
    """
    ahead = measure_front(robot, eye, PROBE_STEP_M + offset)
    if first_side < PROBE_STEP_M or (
        ahead is not None and ahead.distance < PROBE_STEP_M + PROBE_CLEAR_M
    ):
        return seen
    if not robot.motion.moveTo(PROBE_STEP_M, 0.0, 0.0):
        raise MotionError(f"the nearest-wall probe could not step {PROBE_STEP_M:.2f} m forward")
    try:
        again = detect_wall_by_floorline(robot, eye, offset=offset)
    finally:
        if not robot.motion.moveTo(-PROBE_STEP_M, 0.0, 0.0):
            raise MotionError(f"the nearest-wall probe could not step {PROBE_STEP_M:.2f} m back")
    left = again.left_m if seen.left_m is None else seen.left_m
    right = again.right_m if seen.right_m is None else seen.right_m
    side = decide_side(left, right, offset)
    yaw = 0.0 if side is None else math.copysign(math.pi / 2, 1.0 if side == "left" else -1.0)
    return FloorLineWall(side, yaw, left, right)


def _walk_laps(
    robot: Robot,
    cfg: Config,
    camera: Camera,
    eye: FloorEye,
    origin: Pose2D,
    command_origin: Pose2D,
    yaw: float,
    pitch: float,
    turn: float,
    result: SurveyResult,
    on_frame: FrameSink,
    progress: Callable[[int], None] | None,
    on_far: FarSink | None = None,
    f_px: float = 272.0,
) -> None:
    """The laps, steered by the floor-wall lines of the side and front walls.

    Each side is walked in steps of about ``survey.step_m``: after each step a picture
    (the survey's camera, the head turned ``survey.look_ahead_rad`` from the wall toward
    the walking direction) and the side wall's line (the bottom camera, beside or behind
    the arm: :func:`naoloc.behaviours.wall_follow.measure_side`); the next step goes back
    to ``survey.wall_offset_m`` and parallel to the wall. Near the side's end (by
    odometry), the head turns forward and the front wall's line sets where the corner is.
    With no line in view the step goes straight and the side ends by odometry. A
    :class:`WalkWatch` compares each step with the pictures, the lines and (simulator
    only) the contacts. Vision and scale facts go to ``result.meta`` as they come (a
    survey that raises keeps them). With ``on_far``, each stop also takes
    ``survey.far_per_stop`` far pictures (:func:`far_yaws`) after its wall picture; one
    looking ahead also gives the watch the front wall's line.
    """
    sides = cfg.survey_sides()
    offset, step = cfg.survey.wall_offset_m, cfg.survey.step_m
    keep = max(offset, MIN_KEEP_M)  # the distance steered to: never where the wall is unseen
    ahead = cfg.survey.look_ahead_rad
    picture_yaw = yaw - math.copysign(ahead, yaw) if yaw != 0 and ahead > 0 else yaw
    result.meta["picture_yaw"] = picture_yaw
    side_normal = math.copysign(math.pi / 2, yaw) if yaw != 0 else -math.pi / 2
    fars = far_yaws(cfg, yaw) if on_far is not None else []
    if fars:
        result.meta["far_views"] = {"yaws": fars, "pitch": cfg.survey.far_pitch_rad}
    vision: list[dict[str, Any]] = []
    result.meta["vision"] = vision  # filled as the survey goes: a partial dataset keeps it
    fronts: list[FrontSample] = []
    deviations: list[float] = []
    watch = WalkWatch(
        robot, offset, "left" if side_normal > 0 else "right", abs(picture_yaw - yaw), f_px
    )
    memory = SideMemory()
    try:
        here = Pose2D()
        # The origin's own line gives the map frame's heading: every view's, the median
        # (in a corner one view's line can mix in the other wall, and a short or distant
        # line reads a degree off).
        start_lines = measure_side_views(robot, eye, side_normal, offset)
        # and three more views centred on the wall's foot: one line can read a degree off
        start_lines += measure_side_views(robot, eye, side_normal, offset, heading_views(offset))
        side_line = median_line(start_lines)
        if side_line is None:
            side_line = measure_side(robot, eye, side_normal, offset)
        memory.start(trusted(side_line, offset, side_normal), here, offset)
        result.meta["start_side"] = line_dict(side_line)  # where the map frame's origin stands
        result.meta["start_views"] = [line_dict(line) for line in start_lines]
        # The wall ahead at the start: its angle is the origin's heading when the side wall
        # is too near to be seen (a small offset's corner); the watch's first front line.
        start_front = measure_front(robot, eye, sides[0] + offset)
        if start_front is not None and in_front_range(start_front.distance):
            _watch_ahead(robot, eye, watch, start_front, here, sides[0], sides[0])
        gate = _front_gate(offset, sides[0], sides[0])
        result.meta["start_front"] = line_dict(
            start_front if start_front is not None and gate(start_front) else None
        )
        across, _ = look_for_line(robot, eye, -side_normal, [BESIDE_VIEW])  # a heading too
        result.meta["start_across"] = line_dict(across)
        turn_side: WallLine | None = None
        for lap in range(cfg.survey.laps):
            for k in range(4):
                watch.new_side(lap, k)
                length = sides[k % 2]
                n = max(1, round(length / step))
                nominal = length / n
                walked, steps, last = 0.0, 0, False
                while not last:
                    front = raw_front = None
                    lookahead = length - nominal * 1.5 - FRONT_LOOKAHEAD_M - 0.15 * length
                    if walked >= lookahead or watch.wants_front:
                        remaining = length - walked
                        seen: list[WallLine] = []
                        agrees = _front_gate(offset, remaining, length, seen)
                        front = measure_front(robot, eye, remaining + offset, agrees)
                        # the evidence: the nearest line any pitch showed (head up, a wall
                        # at the picture's bottom edge reads 0.1 m far)
                        raw_front = front if front is not None else _nearest(seen)
                        _watch_ahead(robot, eye, watch, raw_front, here, remaining, length)
                        if front is not None:
                            if eye.last_pitch == FRONT_PITCH:  # the scale's lines, head up
                                fronts.append(FrontSample(lap * 4 + k, here, front))
                            memory.seen_front(front, here)
                    if front is not None:
                        to_go = front.distance - keep
                        if to_go < 0.5 * nominal:
                            break  # at the corner already: no step, no picture
                        length_now = min(nominal, to_go)
                        last = to_go <= 1.5 * nominal
                        if last:
                            length_now = to_go
                    else:
                        length_now = nominal
                        last = steps + 1 >= n
                    if steps >= n + MAX_EXTRA_STEPS:
                        break
                    steer = memory.steer(here)
                    move, steered = corrected_step(steer, side_normal, keep, length_now)
                    if not robot.motion.moveTo(move.x, move.y, move.theta):
                        raise watch.blocked(f"moveTo failed; {_ahead(robot, eye)}")
                    watch.stepped(length_now)
                    look(robot, picture_yaw, pitch)
                    keyframe, odometry = camera.keyframe(origin, command_origin)
                    motion = watch.picture(_gray(keyframe.image), here.distance(keyframe.pose))
                    far: list[tuple[Keyframe, Pose2D]] = []
                    far_front: WallLine | None = None
                    for _ in range(cfg.survey.far_per_stop if fars else 0):
                        far_yaw = fars[result.far_frames % len(fars)]
                        look(robot, far_yaw, cfg.survey.far_pitch_rad)
                        far.append(camera.keyframe(origin, command_origin))
                        result.far_frames += 1
                        if far_yaw == 0.0:  # the wall ahead: its line is the watch's too,
                            # and the map's where it is farther than the survey steers by
                            seen_ahead = eye.measure(0.0, 0.4)
                            far_front = _far_front(seen_ahead)
                            _watch_ahead(
                                robot,
                                eye,
                                watch,
                                _in_range(seen_ahead),
                                keyframe.pose,
                                length - walked - length_now,
                                length,
                            )
                    result.path_m += here.distance(keyframe.pose)
                    here = keyframe.pose
                    walked += length_now
                    steps += 1
                    side_line = measure_side(robot, eye, side_normal, offset)
                    memory.seen_side(trusted(side_line, offset, side_normal), here)
                    watch.side_line(side_line, here, memory.level)
                    good = trusted(side_line, offset, side_normal)
                    if good is not None:
                        deviations.append(good.distance - offset)
                    vision.append(
                        {
                            "frame": result.frames,
                            "side_index": lap * 4 + k,
                            "side": line_dict(side_line),
                            "front": line_dict(front),
                            "front_seen": line_dict(raw_front),
                            **({"far_front": line_dict(far_front)} if far_front else {}),
                            "steered": steered,
                            "carried": steered and steer is not None and steer.inliers == 0,
                            "level_m": round(memory.level, 3),
                            "motion": motion,
                            **({"turn_side": line_dict(turn_side)} if steps == 1 else {}),
                        }
                    )
                    on_frame(keyframe, lap, odometry)
                    for far_keyframe, far_odometry in far:
                        assert on_far is not None  # far pictures are taken only for it
                        on_far(far_keyframe, lap, result.frames, far_odometry)
                    result.frames += 1
                    if progress is not None:
                        progress(1)
                if not robot.motion.moveTo(0.0, 0.0, turn):
                    raise watch.blocked(f"the corner turn failed; {_ahead(robot, eye)}")
                after = relative_pose(origin, pose_of(robot.motion, True))
                result.path_m += here.distance(after)
                here = after
                memory.turned()  # the front wall is the next side's
                side_line = turn_side = measure_side(robot, eye, side_normal, offset)
                memory.seen_side(trusted(side_line, offset, side_normal), here)
            result.laps = lap + 1
    finally:
        scale, ratios = metric_scale(fronts)
        result.meta["wall_follow"] = {
            "side_normal": side_normal,
            "side_seen": sum(1 for v in vision if v["side"] is not None),
            "steered_steps": sum(1 for v in vision if v["steered"]),
            "front_seen": len(fronts),
            "offset_dev_mean_m": None if not deviations else float(np.mean(np.abs(deviations))),
            "offset_dev_max_m": None if not deviations else float(np.max(np.abs(deviations))),
        }
        result.meta["metric_scale"] = scale
        result.meta["metric_scale_samples"] = ratios


def _front_gate(
    offset: float, remaining: float, length: float, seen: list[WallLine] | None = None
) -> Callable[[WallLine], bool]:
    """Whether a front line agrees with the odometry (:func:`trusted_front`); every line
    judged is appended to ``seen``."""

    def gate(line: WallLine) -> bool:
        if seen is not None:
            seen.append(line)
        return trusted_front(line, offset, remaining, length) is not None

    return gate


def _watch_ahead(
    robot: Robot,
    eye: FloorEye,
    watch: WalkWatch,
    line: WallLine | None,
    here: Pose2D,
    remaining: float,
    length: float,
) -> None:
    """Hand a line ahead to the watch; a wall ahead it now holds against the odometry is
    looked at again with the head up first (:func:`_floor_goes_on`): a plank's edge is
    cleared, a wall's second sighting at the next stop stops the survey.

    Raises:
        SurveyBlocked: The watch's evidence (:meth:`WalkWatch.front_line`).
    """
    watch.front_line(line, here, remaining, length)
    if watch.pending("ahead") and _floor_goes_on(robot, eye, watch.ahead_m):
        watch.clear("ahead")  # the floor goes on past it: a plank's edge, not a wall


def _floor_goes_on(robot: Robot, eye: FloorEye, distance: float) -> bool:
    """Whether the floor visibly goes on past a line ``distance`` m ahead: looking ahead
    with the head up (twice as far up the second time), a wall's line beyond it, or a side
    wall's line whose far end lies more than :data:`FLOOR_BEYOND_M` past it (a wall across
    the way would end it there). A plank's edge or a rug's reads as a wall ahead to the
    level view; a wall does not let the floor go on."""
    for pitch in (FRONT_PITCH, 2 * FRONT_PITCH):
        look(robot, 0.0, pitch)
        for line in eye.lines():
            c, s = math.cos(line.normal), math.sin(line.normal)
            if c > 0.9 and line.distance > distance + FLOOR_BEYOND_M:
                return True  # a wall ahead, beyond the line
            if abs(s) > 0.8 and line.ends_m is not None:
                reach = max(-s * e for e in line.ends_m)  # how far ahead the side line runs
                if reach > distance + FLOOR_BEYOND_M:
                    return True
    return False


def _nearest(lines: list[WallLine]) -> WallLine | None:
    """The nearest of some lines (None for none)."""
    return min(lines, key=lambda line: line.distance) if lines else None


def _gray(image: np.ndarray) -> np.ndarray:
    """A grey copy of a BGR picture (a grey one as it is)."""
    import cv2

    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _far_front(line: WallLine | None) -> WallLine | None:
    """A line ahead (the head looking ahead) the map may place its frame by: within
    :data:`naoloc.perception.wall_gate.FAR_FRONT_RANGE_M` and across the robot's way
    (:func:`naoloc.perception.wall_gate.crosses_path`)."""
    if line is None or not in_far_front_range(line.distance) or not crosses_path(line):
        return None
    return line


def _in_range(line: WallLine | None) -> WallLine | None:
    """``line`` when within :data:`naoloc.perception.wall_gate.FRONT_RANGE_M`, the range
    the survey steers by."""
    return line if line is not None and in_front_range(line.distance) else None


def _ahead(robot: Robot, eye: FloorEye) -> str:
    """What the bottom camera sees ahead, for a failed move's message."""
    line = measure_front(robot, eye, 0.0)
    if line is None:
        return "no wall line in view ahead"
    return f"the wall ahead is {line.distance:.2f} m away"


def far_yaws(cfg: Config, wall_yaw: float) -> list[float]:
    """The far pictures' head yaws (rad, FRAME_ROBOT) for a survey whose head faces the
    wall at ``wall_yaw``: ``survey.far_yaws_rad`` turned toward the room's interior (away
    from the wall's side), clamped to the head's range."""
    inward = -math.copysign(1.0, wall_yaw) if wall_yaw != 0 else 1.0
    return [clamp_head(inward * r, cfg.survey.far_pitch_rad)[0] for r in cfg.survey.far_yaws_rad]


def trusted_front(
    line: WallLine | None, offset: float, remaining: float, length: float
) -> WallLine | None:
    """The front wall's line, if it agrees with the odometry about where the corner is.

    Args:
        line: The measured line ahead (FRAME_ROBOT).
        offset: The survey's wall offset, m.
        remaining: What the odometry says is left of the side, m.
        length: The side's length, m.

    Returns:
        ``line`` when it is within the camera's range, not nearer than half the offset, and
        puts the corner within ``0.25 * length + 0.3`` m of the odometry's (a NAO's
        distance scale errs 10 %; a rug's edge or a low piece of furniture would not
        agree), and crosses the robot's way (:func:`crosses_path`: a table's face beside
        the way is not the corner), else None.
    """
    if line is None or not in_front_range(line.distance) or line.distance < 0.5 * offset:
        return None
    if not crosses_path(line):
        return None
    if abs(line.distance - offset - remaining) > 0.25 * length + 0.3:
        return None
    return line


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
