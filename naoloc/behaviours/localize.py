"""Localize the robot in a map: look around (head, maybe a turn in place), ask the map.

Two ways to take the query pictures:

- ``paper`` (the seed's Algorithm 5): find the nearest wall, turn the head to it and take
  one or two pictures of that wall the way the survey took its pictures (see
  :func:`paper_queries`).
- ``scan`` (default for mode ``verified``): pictures at several head yaws across the
  head's range, optionally repeated after turning in place, so the map sees most of
  the room around the robot. When the map's answer is not confident (no PnP-verified pose
  with enough inliers), the robot turns a quarter turn in place and sweeps again, up to
  ``extra_turns`` times, and the map combines every picture so far by their odometry. The
  robot never translates. A first sweep that is not confident goes to the floor step
  first: when it decides (it confirms the PnP pose, keeps it by a clear margin, or a floor
  candidate clearly wins the vote), the scan stops there without turning (97 % of the scans
  in twelve rooms; docs/RESULTS.md, "Issue 12, twelfth step"). Then (if not
  done already) the bottom camera measures the floor-wall lines around the
  robot (``localize.floor_lines``, by default ``always``): with the walls the map records
  they allow a few poses (:mod:`naoloc.localization.floorfix`). A PnP pose one of them confirms
  takes
  that pose (the lines place the walls to a few centimetres, the map's landmarks less
  well); otherwise the one the pictures' landmark matches support best, clearly, becomes
  the estimate (method ``floorlines``). A keyframe-bearing guess the floor step neither
  confirms nor replaces is no estimate (method ``none``): it is unverified.

Every query keeps its odometry pose, so :meth:`VisualMap.localize` can combine them; the
estimate is the robot pose (FRAME_ROBOT origin) in the map frame when the last picture was
taken, which is where the robot still stands.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from naoloc.behaviours.nearest_wall import detect_nearest_wall, detect_wall_by_floorline
from naoloc.behaviours.wall_follow import FloorEye
from naoloc.config import Config
from naoloc.errors import MotionError
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.perception.floorline import WallLine
from naoloc.robot import Robot, pose_of
from naoloc.robot.camera import DEFAULT_HEAD_PITCH, Camera, lens_of, look, stand
from naoloc.robot.keyframe import Keyframe

if TYPE_CHECKING:
    from naoloc.localization.floorfix import Walls
    from naoloc.mapping import Estimate, VisualMap
    from naoloc.mapping.localizer import MatchMemo
    from naoloc.perception.features import Features

# Head yaws of a scan, rad: the head turns +-2.09 rad, the camera sees +-0.53 rad more. Seven
# (0.67 rad apart, the camera's 1.06 rad FOV overlapping): with the head tilted up toward the
# art, five yaws 1 rad apart missed 5 of 16 poses in the home room, seven missed 1
# (docs/RESULTS.md, "Looking at the art").
SCAN_YAWS: tuple[float, ...] = (-2.0, -1.35, -0.7, 0.0, 0.7, 1.35, 2.0)
# Offset of the paper's second picture from the first, rad (toward the wall's normal): a
# second look at the same wall. Measured at the Table 3 positions (docs/RESULTS.md, "The
# paper's mode"): 0.5 rad away the second picture sees what the survey never framed so.
PAPER_SECOND_OFFSET = 0.1
# The floor-line fix (localize.floor_lines): the bottom camera's head yaws and pitches (rad)
# around the robot; a PnP pose within FLOOR_CONFIRM_* of one of the lines' poses is confirmed
# and takes the best-supported such pose; otherwise a candidate needs FLOOR_MIN_SUPPORT query
# features it explains and FLOOR_MARGIN times more than any candidate farther than
# FLOOR_DISTINCT_M (m); its confidence (below CONFIDENT).
FLOOR_YAWS: tuple[float, ...] = (-2.0, -1.0, 0.0, 1.0, 2.0)
FLOOR_PITCHES: tuple[float, ...] = (-0.35, 0.0)
FLOOR_CONFIRM_M = 0.3
FLOOR_CONFIRM_RAD = 0.15
FLOOR_MIN_SUPPORT = 20
FLOOR_MARGIN = 1.15
# A candidate from the landmarks' bearings (an axis no wall line gave) stands in the vote
# only with this much support. They fit the map's landmarks, so they out-vote true line
# poses that fit the walls: six fresh rooms, the true ones got 83-159, wrong ones 24-63
# (against true line poses of 29-40).
FLOOR_SWEPT_MIN_SUPPORT = 70
# A PnP pose the lines do not contradict but no candidate confirms stays (refined) only
# with this many times the support of every distinct candidate.
FLOOR_KEEP_MARGIN = 1.5
FLOOR_DISTINCT_M = 0.3
FLOOR_CONFIDENCE = 0.3
# Turns in place (and sweeps) added while the estimate is not confident, and their angle, rad.
EXTRA_TURNS = 3
EXTRA_TURN_RAD = math.pi / 2


def estimate_fields(est: Estimate) -> dict[str, float | str | None]:
    """The pose, confidence and method of an estimate as the CLI's JSON lines give them.

    Map frame. With nothing recognised the pose fields are None (JSON null), the confidence
    0 and the method ``none``: never a made-up pose.
    """
    if not est.found:
        return {"x": None, "y": None, "theta": None, "confidence": 0.0, "method": "none"}
    return {
        "x": round(est.x, 4),
        "y": round(est.y, 4),
        "theta": round(est.theta, 4),
        "confidence": round(float(est.confidence), 4),
        "method": est.method,
    }


def estimate_covariance(est: Estimate) -> dict[str, Any]:
    """The estimate's uncertainty as the JSON ``covariance`` (3 x 3 of x, y, theta).

    The standard deviations are those the particle filter gives a fix
    (:func:`naoloc.localization.fusion.fix_from_estimate`: from the PnP inliers, or the confidence);
    nothing when there is no estimate.
    """
    if not est.found:
        return {}
    from naoloc.localization.fusion import fix_from_estimate

    fix = fix_from_estimate(est)
    sxy, sth = fix.sigma_xy_m**2, fix.sigma_theta_rad**2
    cov = [[sxy, 0.0, 0.0], [0.0, sxy, 0.0], [0.0, 0.0, sth]]
    return {"covariance": [[round(v, 6) for v in row] for row in cov]}


@dataclass(frozen=True)
class Localization:
    """One localization and what it was made from.

    Attributes:
        estimate: The map's estimate (map frame) for the pose the robot stands at.
        queries: The pictures used (poses: raw FRAME_WORLD odometry).
        strategy: "scan" or "paper".
        extra_turns: Quarter turns in place made because an estimate was not confident.
        truth: The true pose in the map frame, when a simulator and the map's
            origin_room_pose know it; else None.
        error_m: Distance from estimate to truth, m (None without truth or without an
            estimate).
        heading_error_deg: Wrapped heading difference, degrees (None without truth).
        wall_s: Wall-clock seconds spent (pictures and the map's work).
        compute_s: CPU seconds of the map's work alone (feature extraction, the localizer,
            floor-line detection and the floor step's votes), every thread of the process;
            taking pictures and moving the head or body are not counted.
        floor_log: The floor lines the floor step measured (None when it did not run):
            they do not depend on the map, so other maps can be scored with them
            (:func:`floor_step_again`).
    """

    estimate: Estimate
    queries: list[Keyframe]
    strategy: str
    truth: Pose2D | None
    error_m: float | None
    heading_error_deg: float | None
    wall_s: float
    extra_turns: int = 0
    compute_s: float = 0.0
    floor_log: FloorLog | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``localize`` line."""
        est = self.estimate
        out: dict[str, Any] = {
            **estimate_fields(est),
            **estimate_covariance(est),
            "mode": est.mode,
            "strategy": self.strategy,
            "images": len(self.queries),
            "extra_turns": self.extra_turns,
            "compute_s": round(self.compute_s, 4),
        }
        if self.truth is not None:
            out["truth"] = [round(v, 4) for v in self.truth]
            if self.error_m is not None:
                out["error_m"] = round(self.error_m, 4)
                out["heading_error_deg"] = round(float(self.heading_error_deg or 0.0), 3)
        return out


class CpuMeter:
    """CPU seconds spent inside :meth:`timed` blocks (``time.process_time``: every thread of
    the process, so OpenCV's worker threads count too).

    Attributes:
        seconds: The total so far.
    """

    def __init__(self) -> None:
        self.seconds = 0.0

    @contextmanager
    def timed(self) -> Iterator[None]:
        """Add the CPU time of the ``with`` block to :attr:`seconds`."""
        t0 = time.process_time()
        try:
            yield
        finally:
            self.seconds += time.process_time() - t0


def truth_in_map(robot: Robot, meta: dict[str, Any]) -> Pose2D | None:
    """The robot's true pose in the map frame, or None when unknown.

    Args:
        robot: The robot; needs ``robot.sim``.
        meta: The map's meta; needs ``origin_room_pose`` (room frame pose at the map origin).
    """
    origin = meta.get("origin_room_pose")
    if robot.sim is None or origin is None:
        return None
    return relative_pose(Pose2D.from_list(origin), Pose2D.from_list(robot.sim.true_pose()))


def scan_queries(
    camera: Camera,
    yaws: Sequence[float] = SCAN_YAWS,
    *,
    turns: int = 1,
    pitch: float = DEFAULT_HEAD_PITCH,
) -> list[Keyframe]:
    """Pictures at several head yaws; with ``turns`` > 1, repeated after turns in place.

    Args:
        camera: The camera subscription (its robot is moved: head, and body rotation only).
        yaws: Head yaws of one sweep, rad.
        turns: Body headings to sweep from, evenly spread over a full turn.
        pitch: Head pitch, rad.

    Returns:
        The keyframes, poses in raw FRAME_WORLD odometry.

    Raises:
        MotionError: A turn in place failed (the robot is stopped).
    """
    robot = camera.robot
    out: list[Keyframe] = []
    order = list(yaws)
    try:
        for k in range(max(1, turns)):
            if k > 0:
                if not robot.motion.moveTo(0.0, 0.0, 2.0 * math.pi / turns):
                    raise MotionError("turning in place failed during the localization scan")
                order.reverse()  # sweep back from where the head is
            out += sweep(camera, order, pitch)
    finally:
        robot.motion.stopMove()
    return out


def sweep(
    camera: Camera, yaws: Sequence[float], pitch: float = DEFAULT_HEAD_PITCH
) -> list[Keyframe]:
    """One picture at each head yaw (rad), in the given order; only the head moves."""
    out: list[Keyframe] = []
    for yaw in yaws:
        look(camera.robot, yaw, pitch)
        out.append(camera.keyframe()[0])
    return out


def paper_queries(
    camera: Camera,
    images: int = 2,
    *,
    pitch: float = DEFAULT_HEAD_PITCH,
    look_ahead: float = 0.0,
    eye: FloorEye | None = None,
) -> list[Keyframe]:
    """The paper's way: find the nearest wall, then take 1-2 pictures of it as the survey did.

    The nearest wall comes from the floor-wall lines left and right (``eye``, the bottom
    camera), which need no texture; when neither is seen (or without ``eye``), from the
    paper's forward picture (more keypoints in one half). The pictures are taken at the
    head yaw the survey photographed that side with: turned ``look_ahead`` from the wall
    toward the robot's front (0 = straight at it, as in the paper's survey). The paper's
    query repeats its survey's view; measured at the Table 3 positions, a query straight at
    the wall after a look-ahead survey erred 1.7-3.0 m, the survey's view 0.2-1.0 m, and the
    keypoint halves picked the far wall in 10 of 20 evaluations (the floor lines in none).

    Args:
        camera: The camera subscription (only the head moves).
        images: 1 or 2 pictures (more are capped at 2); the second is turned
            :data:`PAPER_SECOND_OFFSET` toward the wall.
        pitch: Head pitch, rad.
        look_ahead: The survey's turn from the wall toward the walking direction, rad
            (the map's ``picture_yaw - head_yaw``).
        eye: The bottom camera, for the floor-wall lines; None: the paper's detector only.
    """
    robot = camera.robot
    wall_yaw: float | None = None
    if eye is not None:
        lines = detect_wall_by_floorline(robot, eye, pitch)
        wall_yaw = lines.head_yaw if lines.side is not None else None
    if wall_yaw is None:
        wall_yaw = detect_nearest_wall(robot, camera, pitch).head_yaw
    side = math.copysign(1.0, wall_yaw)
    first = wall_yaw - side * look_ahead
    yaws = [first, first + side * PAPER_SECOND_OFFSET]
    out: list[Keyframe] = []
    for yaw in yaws[: max(1, min(2, images))]:
        look(robot, yaw, pitch)
        out.append(camera.keyframe()[0])
    return out


def survey_look_ahead(meta: dict[str, Any]) -> float:
    """The survey's turn of the head from the wall toward the walking direction, rad.

    From a map's meta (``picture_yaw`` and ``head_yaw``); 0 when it has neither (maps from
    before the look-ahead, or a survey that faced the wall).
    """
    picture, head = meta.get("picture_yaw"), meta.get("head_yaw")
    if not isinstance(picture, (int, float)) or not isinstance(head, (int, float)):
        return 0.0
    return abs(float(picture) - float(head))


def _heading_from_last_sweep(
    vmap: VisualMap,
    last: Sequence[Keyframe],
    feats: Sequence[Features],
    combined: Estimate,
    mode: str,
    memo: MatchMemo | None = None,
) -> Estimate:
    """The combined estimate's position with the heading the last sweep alone verifies.

    Turning in place moves the robot little but its heading by the turn's odometry, which
    errs about 6 % of the angle on a NAO: combining sweeps across turns carries that error
    into the heading (measured: 14-25 deg after three quarter turns). The head's own angles
    are exact, so the last sweep's own heading is kept: its PnP heading always, its
    keyframe-bearing heading when the combined estimate has only that too.
    """
    tail = vmap.localize_features(feats, last, mode=mode, memo=memo)  # type: ignore[arg-type]
    if not tail.found:
        return combined
    # A PnP heading beats any; the keyframes' bearings (one sweep: exact head angles) beat
    # the same bearings combined across turns.
    if not (tail.method == "pnp" or (tail.method == combined.method == "keyframes")):
        return combined
    details = {**combined.details, "heading_from": "last sweep"}
    return dataclasses.replace(combined, theta=tail.theta, details=details)


def measure_floor_lines(robot: Robot, cfg: Config, meter: CpuMeter | None = None) -> list[WallLine]:
    """The floor-wall lines around the robot: bottom camera at :data:`FLOOR_YAWS` x pitches.

    Args:
        robot: The robot.
        cfg: Config (camera and lens).
        meter: Counts the detection's CPU time (not the pictures'), when given.

    Returns:
        The lines, FRAME_ROBOT of the robot now (it does not move; the head does).
    """
    meter = meter if meter is not None else CpuMeter()
    eye = FloorEye(robot, cfg.camera, "naoloc_localize_floor", lens=lens_of(cfg))
    lines: list[WallLine] = []
    try:
        for pitch in FLOOR_PITCHES:
            for yaw in FLOOR_YAWS:
                look(robot, yaw, pitch)
                view = eye.view()
                if view is not None:
                    with meter.timed():
                        lines += eye.detect(view)
    finally:
        eye.close()
    return lines


@dataclass
class FloorLog:
    """The floor lines one localization measured so far, each set with the robot's
    odometry pose (map-independent, the odometry frame) when it was measured."""

    taken: list[tuple[Pose2D, list[WallLine]]] = dataclasses.field(default_factory=list)


def _floor_fix(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    queries: Sequence[Keyframe],
    feats: Sequence[Features],
    estimate: Estimate,
    meter: CpuMeter,
    log: FloorLog | None = None,
) -> Estimate:
    """The estimate, or a better one from the floor lines (:mod:`naoloc.localization.floorfix`).

    A PnP pose that floor-line poses confirm (within :data:`FLOOR_CONFIRM_M` and
    :data:`FLOOR_CONFIRM_RAD`) takes the one of them the pictures' landmark matches support
    best (:func:`naoloc.mapping.support.pose_support`): it keeps method ``pnp`` and its
    confidence, and ``details["floor_refined"]`` keeps the PnP pose. The lines place the
    walls to 1-4 cm, while PnP carries the map's landmark errors (anywhere protocol, six
    rooms: median 0.07 m for PnP poses, 0.02 m for floor-line poses). A PnP pose no
    candidate confirms but no line contradicts (a wall hidden behind furniture gives no
    candidate on its axis) keeps its place on the axes the lines do not pin and takes the
    lines' heading and coordinates on the others (:func:`naoloc.localization.floorfix.check_pose`;
    ``details["floor_consistent"]``), if one axis is pinned and its support is
    :data:`FLOOR_KEEP_MARGIN` times that of every distinct candidate. Otherwise the
    candidate supported best replaces the estimate (a PnP pose the floor contradicts, a
    keyframe fallback, or none) when its support is at least :data:`FLOOR_MIN_SUPPORT` and
    :data:`FLOOR_MARGIN` times that of every other candidate farther than
    :data:`FLOOR_DISTINCT_M` from it.

    Where no wall line gives one axis (its walls 4 m away or behind furniture), the
    candidates take that coordinate from where the landmarks' bearings agree
    (:func:`naoloc.mapping.support.axis_peaks`); those stand in the votes only with
    :data:`FLOOR_SWEPT_MIN_SUPPORT` (``details["floor_axis_from"]`` says when one won).

    With ``log``, the lines measured before a turn in place join those measured now,
    carried by the odometry and turned to agree with them
    (:func:`naoloc.localization.floorfix.carry_lines`; ``details["floor_carried"]`` counts them):
    the
    head sees about 290 deg around the robot, so after a turn a wall seen before may be in
    the blind spot behind it, or hidden behind furniture from the new heading.
    """
    from naoloc.localization.floorfix import map_walls

    walls = map_walls(vmap)
    if walls is None:
        return estimate
    here = pose_of(robot.motion) if log is not None else Pose2D()
    lines = measure_floor_lines(robot, cfg, meter)
    earlier = list(log.taken) if log is not None else []
    if log is not None:
        log.taken.append((here, lines))
    with meter.timed():
        return _vote_carried(vmap, walls, earlier, here, lines, queries, feats, estimate)


def _vote_carried(
    vmap: VisualMap,
    walls: Walls,
    earlier: Sequence[tuple[Pose2D, list[WallLine]]],
    here: Pose2D,
    lines: list[WallLine],
    queries: Sequence[Keyframe],
    feats: Sequence[Features],
    estimate: Estimate,
) -> Estimate:
    """:func:`_floor_vote` on the lines measured at ``here`` (odometry) and the ``earlier``
    ones carried there (:func:`naoloc.localization.floorfix.carry_lines`;
    ``details["floor_carried"]``
    counts them)."""
    from naoloc.localization.floorfix import carry_lines

    carried: list[WallLine] = []
    for at, seen in earlier:
        carried += carry_lines(seen, relative_pose(at, here), lines)
    result = _floor_vote(vmap, walls, [*lines, *carried], queries, feats, estimate)
    if carried:
        result.details["floor_carried"] = len(carried)
    return result


def floor_step_again(
    vmap: VisualMap,
    cfg: Config,
    queries: Sequence[Keyframe],
    feats: Sequence[Features],
    estimate: Estimate,
    log: FloorLog | None,
) -> Estimate:
    """The floor step for another map's (or mode's) estimate from the same pictures, with
    the floor lines a localization already measured there (:attr:`Localization.floor_log`).

    The lines do not depend on the map: the last floor step's lines, with the earlier ones
    carried to where the robot stood then (:func:`naoloc.localization.floorfix.carry_lines`), are
    voted
    on with this map's walls and landmarks as the localization's last floor step would
    have, under ``cfg.localize.floor_lines``; a keyframe guess neither confirmed nor
    replaced becomes no estimate. An evaluation re-scores its pictures so, and other maps
    get the floor step their own localization would have had.

    Args:
        vmap: The map to score with.
        cfg: Config (``localize.floor_lines``).
        queries: The pictures, as taken.
        feats: Their features, extracted with ``vmap``'s extractor (``vmap.extract``).
        estimate: ``vmap``'s estimate from ``feats`` (map frame).
        log: The lines measured and the odometry poses they were measured at, or None.
    """
    from naoloc.localization.floorfix import map_walls
    from naoloc.mapping.localizer import CONFIDENT

    when = cfg.localize.floor_lines
    walls = map_walls(vmap)
    if log is None or not log.taken or walls is None or when == "off":
        return estimate
    if estimate.mode != "verified" or (when == "unsure" and estimate.confidence >= CONFIDENT):
        return estimate
    here, lines = log.taken[-1]
    result = _vote_carried(vmap, walls, log.taken[:-1], here, lines, queries, feats, estimate)
    return _unverified_as_none(result)


def _floor_vote(
    vmap: VisualMap,
    walls: Walls,
    lines: Sequence[WallLine],
    queries: Sequence[Keyframe],
    feats: Sequence[Features],
    estimate: Estimate,
) -> Estimate:
    """:func:`_floor_fix`'s work once the lines are measured (no robot calls)."""
    from naoloc.localization.floorfix import candidates, check_pose, landmark_candidates
    from naoloc.mapping import support as sup
    from naoloc.mapping.localizer import Estimate as _Estimate

    held: list[sup.SupportMatches] = []  # the features matched once, when a vote needs them

    def matches() -> sup.SupportMatches:
        if not held:
            held.append(sup.support_matches(vmap, feats, queries))
        return held[0]

    def pose_support(poses: Sequence[Pose2D]) -> list[int]:
        return sup.pose_support(vmap, feats, queries, poses, matches=matches())

    def solve(
        theta: float, axis: int, fixed: float, span: tuple[float, float]
    ) -> list[tuple[float, int]]:
        return sup.axis_peaks(matches(), walls.frame, theta, axis, fixed, span)

    cands = candidates(lines, walls)
    from_lines = len(cands)  # the landmarks' places come after these
    info: dict[str, Any] = {"floor_lines": len(lines), "floor_candidates": from_lines}
    found = estimate.found
    pnp = found and estimate.method == "pnp"
    support: list[int] | None = None  # the candidates' votes, once counted
    if pnp:
        # Only the lines' candidates confirm: a place from the landmarks' bearings agrees
        # with a PnP pose on a look-alike print as well (room 551152189: 5.7 m off).
        near = [c for c in cands
                if _close(c, estimate.pose(), FLOOR_CONFIRM_M, FLOOR_CONFIRM_RAD)]  # fmt: skip
        if near:
            details = dict(estimate.details)
            details.update(info, floor_confirmed=True)
            alternatives = details.get("alternatives") or []
            if alternatives:
                # A look-alike place the lines allow no pose near is ruled out: a filter
                # fed this fix no longer weighs it (fusion.Fix.verified).
                allowed = [a for a in alternatives if any(
                    _close(c, Pose2D(a[0], a[1], a[2]), FLOOR_CONFIRM_M, FLOOR_CONFIRM_RAD)
                    for c in cands
                )]  # fmt: skip
                details["alternatives"] = allowed
                details["floor_ruled_out"] = len(alternatives) - len(allowed)
            pick = 0
            if len(near) > 1:  # a vote only when there is a choice (matching: 0.1-0.2 s)
                votes = pose_support(near)
                pick = max(range(len(near)), key=lambda i: votes[i])
                details["floor_support"] = votes[pick]
            details["floor_refined"] = {"pnp": estimate.pose().to_list()}
            p = near[pick]
            return _Estimate(p.x, p.y, p.theta, estimate.confidence, estimate.mode, details)
    cands += landmark_candidates(lines, walls, solve)
    info["floor_swept"] = len(cands) - from_lines
    if pnp:
        # No candidate near it, but maybe no line against it either: a wall hidden behind
        # furniture bounds that axis without giving it (fresh rooms: three correct PnP
        # poses replaced by candidates 0.43-0.49 m off, made from the furniture's line).
        # It must have one axis from a wall's line and clearly out-vote every distinct
        # candidate: a PnP pose on a look-alike print can be consistent too (room
        # 938307118: 1.9 m and a quarter turn off, support 128 against the truth's 112).
        checked = check_pose(lines, walls, estimate.pose(), FLOOR_CONFIRM_M, FLOOR_CONFIRM_RAD)
        if checked is not None and checked[1] >= 1:
            kept = checked[0]
            votes = pose_support([kept, *cands])
            support = votes[1:]  # each pose's vote is its own: the vote below reuses them
            rivals = [support[i] for i in _standing(support, from_lines)
                      if not _close(cands[i], kept, FLOOR_DISTINCT_M, math.pi)]  # fmt: skip
            beaten = max(rivals, default=0)
            if beaten < FLOOR_MIN_SUPPORT or votes[0] >= FLOOR_KEEP_MARGIN * beaten:
                details = dict(estimate.details)
                details.update(
                    info, floor_consistent=True, floor_support=votes[0], floor_rival=beaten
                )
                details["floor_refined"] = {"pnp": estimate.pose().to_list()}
                return _Estimate(
                    kept.x, kept.y, kept.theta, estimate.confidence, estimate.mode, details
                )
    if not cands:
        estimate.details.update(info)
        return estimate
    # The estimate does not stand in the vote: a wrong PnP pose on a look-alike place
    # explains nearly as many features as the true one (room 1595909956: two of its poses
    # 2.7 and 4.4 m off kept that way, with support 47 and 58).
    if support is None:
        support = pose_support(cands)
    standing = _standing(support, from_lines)
    if not standing:
        estimate.details.update(info, floor_support=max(support))
        return estimate
    best = max(standing, key=lambda i: support[i])
    rivals = [support[i] for i in standing
              if not _close(cands[i], cands[best], FLOOR_DISTINCT_M, math.pi)]  # fmt: skip
    if support[best] < FLOOR_MIN_SUPPORT or (
        rivals and FLOOR_MARGIN * max(rivals) >= support[best]
    ):
        estimate.details.update(info, floor_support=support[best])
        return estimate
    pose = cands[best]
    details = dict(estimate.details)
    details.update(
        info, method="floorlines", floor_support=support[best], floor_rival=max(rivals, default=0)
    )
    if best >= from_lines:
        details["floor_axis_from"] = "landmarks"  # one coordinate from their bearings
    if found:
        details["replaced"] = {"method": estimate.method, "pose": estimate.pose().to_list()}
    return _Estimate(pose.x, pose.y, pose.theta, FLOOR_CONFIDENCE, "verified", details)


def _unverified_as_none(estimate: Estimate) -> Estimate:
    """No estimate in place of a keyframe-bearing guess the floor step, run with the map's
    walls (``details["floor_lines"]`` says so), neither confirmed nor replaced: in twelve
    fresh rooms 13 of 13 such guesses were 1-6 m off. The guess is kept in
    ``details["unverified"]``. Where the floor step did not run, the guess stays."""
    from naoloc.mapping.localizer import no_estimate

    if not (estimate.found and estimate.method == "keyframes"):
        return estimate
    if "floor_lines" not in estimate.details:
        return estimate
    details = {k: v for k, v in estimate.details.items() if k != "method"}
    details["unverified"] = {"method": "keyframes", "pose": estimate.pose().to_list()}
    return no_estimate(
        estimate.mode, "no verified pose: the floor lines neither confirm nor replace the "
        "keyframes' guess", details,
    )  # fmt: skip


def _worth_early_floor(estimate: Estimate) -> bool:
    """Whether the floor step may settle a first sweep before the scan turns in place: its
    estimate is not confident (a PnP pose below CONFIDENT, a keyframe guess, or none)."""
    from naoloc.mapping.localizer import CONFIDENT

    return estimate.confidence < CONFIDENT


def _floor_decided(estimate: Estimate) -> bool:
    """Whether the floor step decided an estimate: it confirmed the PnP pose, kept it by a
    clear margin (``floor_consistent``, here also with :data:`FLOOR_MIN_SUPPORT`: one
    sweep's pictures are few, and a pose kept with 6 against 4 was 0.57 m off), or a
    candidate clearly won the vote (method ``floorlines``). Otherwise it left the estimate
    as it was.

    A first sweep settled so (twelve rooms, 240 poses, `tools/bench_scan_cpu.py`) was as
    right as one that turned on (97.1 % within 0.3 m both, p90 0.055 against 0.073 m),
    and the CPU p90 fell from 0.98 to 0.53 s; only confirmed PnP poses settled it before
    (68 % of the scans, now 97 %).
    """
    d = estimate.details
    if d.get("floor_consistent"):  # one sweep's features: the margin alone is not enough
        return int(d.get("floor_support", 0)) >= FLOOR_MIN_SUPPORT
    return bool(d.get("floor_confirmed")) or estimate.method == "floorlines"


def _standing(support: Sequence[int], from_lines: int) -> list[int]:
    """The candidates that stand in the vote: every one the lines give, and those only the
    landmarks' bearings give (index ``from_lines`` on) with :data:`FLOOR_SWEPT_MIN_SUPPORT`."""
    return [i for i, s in enumerate(support) if i < from_lines or s >= FLOOR_SWEPT_MIN_SUPPORT]


def _close(a: Pose2D, b: Pose2D, metres: float, radians: float) -> bool:
    return a.distance(b) <= metres and abs(modulo2PI(a.theta - b.theta)) <= radians


def localize(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    mode: str | None = None,
    strategy: str | None = None,
    yaws: Sequence[float] = SCAN_YAWS,
    turns: int = 1,
    extra_turns: int = EXTRA_TURNS,
    camera: Camera | None = None,
    floor_lines: str | None = None,
    early_floor: bool = True,
    on_step: Callable[[str], None] | None = None,
) -> Localization:
    """Take query pictures without translating and localize them in ``vmap``.

    Args:
        robot: The robot, standing where it should be localized.
        vmap: The map.
        cfg: Config; uses ``localize.mode``, ``localize.images`` (paper strategy),
            ``localize.head_pitch_rad`` and ``camera``.
        mode: "verified" or "paper"; default ``cfg.localize.mode``.
        strategy: "scan" or "paper"; default "paper" for mode paper, else "scan".
        yaws: Head yaws of a scan, rad.
        turns: Body headings of the first scan (1 = no turning in place).
        extra_turns: Scan strategy only: while the estimate's confidence is below
            :data:`naoloc.mapping.localizer.CONFIDENT`, turn a quarter turn in place and sweep
            again, at most this many times (0 = never).
        camera: An open camera subscription to reuse; one is opened otherwise.
        floor_lines: When to try the floor-line fix (scan strategy, verified mode):
            ``off``, ``unsure`` (the pictures verified no confident pose) or ``always``
            (also checks and refines confident poses); default ``cfg.localize.floor_lines``.
        early_floor: Scan strategy with the floor step on: before turning in place, run
            the floor step on a first sweep that is not confident, and stop when it
            decides (:func:`_floor_decided`). Off, the lines are measured once, after the
            last sweep.
        on_step: Called with a short note as the work advances (progress display).

    Returns:
        The estimate (for the pose at the last picture, where the robot stands), the queries,
        and the error against the truth on a simulator.

    Raises:
        MotionError: A turn in place failed (the robot is stopped).
    """
    from naoloc.mapping.localizer import CONFIDENT, MatchMemo

    t0 = time.monotonic()
    mode = mode or cfg.localize.mode
    strategy = strategy or ("paper" if mode == "paper" else "scan")
    own = camera is None
    cam = (
        camera
        if camera is not None
        else Camera(robot, cfg.localize.camera(cfg.camera), "naoloc_localize")
    )
    added = 0
    meter = CpuMeter()
    memo = MatchMemo()  # each picture's matches once, however often the map is asked
    floor_log = FloorLog()  # lines measured before a turn join those after it
    pitch = cfg.localize.head_pitch_rad  # up toward the art; clamped per yaw by look()
    try:
        stand(robot)
        if strategy == "paper":
            eye = FloorEye(robot, cfg.camera, "naoloc_localize_floor", lens=lens_of(cfg))
            try:
                queries = paper_queries(
                    cam, cfg.localize.images, pitch=pitch,
                    look_ahead=survey_look_ahead(vmap.meta), eye=eye,
                )  # fmt: skip
            finally:
                eye.close()
        else:
            queries = scan_queries(cam, yaws, turns=turns, pitch=pitch)
        if on_step is not None:
            on_step(f"{len(queries)} pictures")
        with meter.timed():
            feats = vmap.extract(queries)  # each picture's features once, kept across sweeps
            estimate = vmap.localize_features(feats, queries, mode=mode, memo=memo)  # type: ignore[arg-type]
        order = list(yaws) if turns % 2 == 0 else list(reversed(yaws))
        last_sweep = len(queries)
        when = cfg.localize.floor_lines if floor_lines is None else floor_lines
        floor = strategy == "scan" and mode == "verified" and when in ("always", "unsure")
        floored = False  # the floor step has given the estimate
        if floor and early_floor and extra_turns > 0 and _worth_early_floor(estimate):
            checked = _floor_fix(robot, vmap, cfg, queries, feats, estimate, meter, floor_log)
            if _floor_decided(checked):
                estimate, floored = checked, True
                if on_step is not None:
                    on_step(f"floor lines settle the first sweep: {checked.method}")
        while (
            strategy == "scan"
            and not floored
            and estimate.confidence < CONFIDENT
            and added < extra_turns
        ):
            try:
                if not robot.motion.moveTo(0.0, 0.0, EXTRA_TURN_RAD):
                    raise MotionError("turning in place failed during the localization scan")
                more = sweep(cam, order, pitch)
                queries += more
                with meter.timed():
                    feats += vmap.extract(more)
            finally:
                robot.motion.stopMove()
            order.reverse()  # sweep back from where the head is
            added += 1
            if on_step is not None:
                on_step(f"turned in place, {len(queries)} pictures")
            with meter.timed():
                estimate = vmap.localize_features(feats, queries, mode=mode, memo=memo)  # type: ignore[arg-type]
            last_sweep = len(order)
        if added and estimate.found:
            with meter.timed():
                estimate = _heading_from_last_sweep(
                    vmap, queries[-last_sweep:], feats[-last_sweep:], estimate, mode, memo
                )
        if floor and not floored and (when == "always" or estimate.confidence < CONFIDENT):
            estimate = _floor_fix(robot, vmap, cfg, queries, feats, estimate, meter, floor_log)
            if on_step is not None:
                on_step(f"floor lines: {estimate.method}")
        estimate = _unverified_as_none(estimate)
    finally:
        if own:
            cam.close()
    truth = truth_in_map(robot, vmap.meta)
    error = heading = None
    if truth is not None and estimate.found:
        error = math.hypot(estimate.x - truth.x, estimate.y - truth.y)
        heading = math.degrees(abs(modulo2PI(estimate.theta - truth.theta)))
    return Localization(
        estimate, queries, strategy, truth, error, heading, time.monotonic() - t0, added,
        meter.seconds, floor_log if floor_log.taken else None,
    )  # fmt: skip
