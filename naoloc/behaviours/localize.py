"""Localize the robot from where it stands: look until the belief is concentrated.

The behaviour only moves the head (and, if the belief stays unsure, turns in place) and
feeds what it sees to the one localization filter (:class:`naoloc.localization.Localizer`):

- ``scan`` (default): at each head yaw of :data:`SCAN_YAWS` (nearest the front first), a
  top-camera picture (the art and furniture the map's landmarks are on) and a
  bottom-camera picture of the floor (the floor-wall lines, against the map's walls). It
  stops as soon as the filter tracks a pose (a short look); after a whole sweep without
  one it turns a quarter turn in place and sweeps again, at most ``extra_turns`` times.
- ``paper`` (the seed's Algorithm 5): find the nearest wall, turn the head to it and take
  one or two pictures of it the way the survey took its pictures
  (:func:`paper_queries`); the paper's estimator (:func:`naoloc.localization.paper.
  localize_paper`) answers.

The estimate is the robot's pose (FRAME_ROBOT origin) in the map frame where it stands at
the end. The observations stay in the result (``observations``), so an evaluation can give
them to another map (:func:`naoloc.localization.replay`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.behaviours.nearest_wall import detect_nearest_wall, detect_wall_by_floorline
from naoloc.behaviours.wall_follow import FloorEye
from naoloc.config import Config
from naoloc.errors import MotionError
from naoloc.geometry import Pose2D, midpose, modulo2PI, relative_pose
from naoloc.localization.localizer import Localizer, PoseEstimate, Status
from naoloc.localization.observations import LineScan, Observation, Picture
from naoloc.localization.paper import localize_paper
from naoloc.mapping.map import VisualMap
from naoloc.robot import Robot, pose_of
from naoloc.robot.camera import DEFAULT_HEAD_PITCH, Camera, lens_of, look, stand
from naoloc.robot.keyframe import Keyframe

__all__ = [
    "PAPER_SECOND_OFFSET",
    "SCAN_YAWS",
    "Eyes",
    "Localization",
    "estimate_fields",
    "localize",
    "paper_queries",
    "survey_look_ahead",
    "truth_in_map",
]

# Head yaws of a scan, rad: the head turns +-2.09 rad and the camera sees +-0.53 rad more,
# so seven yaws 0.67 rad apart overlap around ~290 deg. From the front to one side, then
# the other (the head travels 6 rad in all; nearest-first zigzags travel 14).
SCAN_YAWS: tuple[float, ...] = (0.0, 0.7, 1.35, 2.0, -0.7, -1.35, -2.0)
# Head speed of a scan (fraction of the maximum): the pictures are taken at rest.
SCAN_HEAD_SPEED = 0.6
# Head pitch of the bottom camera's floor pictures, rad: it then sees the floor from 0.5 m
# out to the horizon, where the walls' feet are.
LINE_PITCH = -0.35
# Offset of the paper's second picture from the first, rad (toward the wall's normal).
PAPER_SECOND_OFFSET = 0.1


def estimate_fields(est: PoseEstimate) -> dict[str, Any]:
    """The pose, confidence and method as the CLI's JSON lines give them (map frame).

    Without a pose the pose fields are None (JSON null), the confidence 0, the method
    ``none`` and ``reason`` says why: never a made-up pose.
    """
    if not est.found:
        return {
            "x": None, "y": None, "theta": None, "confidence": 0.0, "method": "none",
            "status": str(est.status), "reason": est.reason,
        }  # fmt: skip
    out: dict[str, Any] = {
        "x": round(est.x, 4),
        "y": round(est.y, 4),
        "theta": round(est.theta, 4),
        "confidence": round(float(est.confidence), 4),
        "method": est.method,
        "status": str(est.status),
    }
    if est.covariance is not None:
        out["covariance"] = [[round(float(v), 8) for v in row] for row in est.covariance]
    return out


@dataclass
class Localization:
    """One localization and what it was made from.

    Attributes:
        estimate: The filter's answer for the pose the robot stands at (map frame).
        observations: Everything the filter was given, in order (replayable).
        strategy: "scan" or "paper".
        pictures: Top-camera pictures taken.
        line_scans: Bottom-camera floor pictures taken.
        extra_turns: Quarter turns in place made because the belief stayed unsure.
        truth: The true pose in the map frame on a simulator (else None).
        error_m: Distance from estimate to truth, m (None without either).
        heading_error_deg: Wrapped heading difference, degrees (None without either).
        wall_s: Wall-clock seconds spent.
        robot_s: The robot's own seconds spent (simulated time on a simulator; wall-clock
            otherwise).
        compute_s: CPU seconds of the estimation alone (features, matching, the filter,
            floor-line detection); taking pictures and moving are not counted.
    """

    estimate: PoseEstimate
    observations: list[Observation]
    strategy: str
    pictures: int
    line_scans: int
    truth: Pose2D | None
    error_m: float | None
    heading_error_deg: float | None
    wall_s: float
    robot_s: float
    extra_turns: int = 0
    compute_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def queries(self) -> list[Keyframe]:
        """The top-camera pictures taken (odometry poses: raw FRAME_WORLD)."""
        return [o.keyframe for o in self.observations if isinstance(o, Picture)]

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``localize`` line."""
        est = self.estimate
        out: dict[str, Any] = {
            **estimate_fields(est),
            "strategy": self.strategy,
            "images": self.pictures,
            "line_scans": self.line_scans,
            "extra_turns": self.extra_turns,
            "robot_s": round(self.robot_s, 3),
            "compute_s": round(self.compute_s, 4),
        }
        if self.truth is not None:
            out["truth"] = [round(v, 4) for v in self.truth]
            if self.error_m is not None:
                out["error_m"] = round(self.error_m, 4)
                out["heading_error_deg"] = round(float(self.heading_error_deg or 0.0), 3)
        return out


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


def robot_clock(robot: Robot) -> float:
    """The robot's time, s: simulated time on a simulator, the wall clock otherwise."""
    return robot.sim.sim_time() if robot.sim is not None else time.monotonic()


class Eyes:
    """The two cameras a localization looks with, as observations for the filter.

    Args:
        robot: The robot.
        cfg: Config (``localize`` camera settings and the lens).
        lines: Whether to open the bottom camera for floor-wall lines.
    """

    def __init__(self, robot: Robot, cfg: Config, lines: bool = True) -> None:
        self.robot = robot
        self.top = Camera(robot, cfg.localize.camera(cfg.camera), "naoloc_localize")
        self.floor: FloorEye | None = None
        self.detect_s = 0.0
        try:
            if lines:
                self.floor = FloorEye(robot, cfg.camera, "naoloc_localize_floor", lens_of(cfg))
        except BaseException:
            self.top.close()
            raise

    def picture(self, still: bool = False) -> Picture:
        """A top-camera picture with the robot's odometry (raw FRAME_WORLD) at capture.

        Args:
            still: The robot stands and the head rests: its state is read once
                (:meth:`Camera.keyframe`).
        """
        return Picture(self.top.keyframe(still=still)[0])

    def line_scan(self, still: bool = False) -> LineScan | None:
        """The floor-wall lines the bottom camera sees now (None: no usable picture).

        Args:
            still: The robot stands and the head rests: the odometry and the camera's
                pose are read once, before the image, instead of around it.
        """
        if self.floor is None:
            return None
        before = pose_of(self.robot.motion, True)  # bracketing the view's own readings
        view = self.floor.view(still)
        odometry = before if still else midpose(before, pose_of(self.robot.motion, True))
        if view is None:
            return None
        t0 = time.process_time()
        lines = self.floor.detect(view)
        self.detect_s += time.process_time() - t0
        return LineScan(tuple(lines), odometry, robot_clock(self.robot))

    def close(self) -> None:
        """Unsubscribe both cameras (best effort)."""
        if self.floor is not None:
            self.floor.close()
        self.top.close()


def own_sigma(est: PoseEstimate, floor_m: float) -> float:
    """The belief's position std along its wider axis less the map's own error (m): the
    floor the filter adds to every covariance (``localize.filter.map_floor_m``, or the
    map's ``keyframe_sigma_m``) and the map frame's heading error at the pose
    (``est.map_frame``), which no number of looks removes."""
    sigma = est.sigmas(frame=False)[0]
    return math.sqrt(max(0.0, sigma**2 - floor_m**2))


def look_once(
    eyes: Eyes, loc: Localizer, yaw: float, pitch: float, line_pitch: float, lines_first: bool
) -> tuple[int, int]:
    """Look at head yaw ``yaw``: a picture (head pitch ``pitch``) and, with a bottom camera
    and a map with walls, the floor lines (``line_pitch``), in either order (the one that
    moves the head least after the last look); each goes to the filter.

    Returns:
        The pictures and line scans taken.
    """
    wants_lines = eyes.floor is not None and loc.filter.walls is not None
    steps = ["picture", "lines"] if wants_lines else ["picture"]
    if lines_first:
        steps.reverse()
    pictures = scans = 0
    for what in steps:
        if what == "picture":
            look(eyes.robot, yaw, pitch, SCAN_HEAD_SPEED)
            loc.update(eyes.picture(still=True))
            pictures += 1
        else:
            scans += look_lines(eyes, loc, yaw, line_pitch)
    return pictures, scans


def look_lines(eyes: Eyes, loc: Localizer, yaw: float, pitch: float = LINE_PITCH) -> int:
    """Turn the head to ``(yaw, pitch)`` (rad) and give the bottom camera's floor lines to
    the filter. The robot stands (the readings are taken once: :meth:`Eyes.line_scan`).

    Returns:
        1 when a scan was taken, else 0 (no usable picture).
    """
    look(eyes.robot, yaw, pitch, SCAN_HEAD_SPEED)
    scan = eyes.line_scan(still=True)
    if scan is None:
        return 0
    loc.update(scan)
    return 1


def localize(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    mode: str | None = None,
    strategy: str | None = None,
    yaws: Sequence[float] = SCAN_YAWS,
    extra_turns: int | None = None,
    localizer: Localizer | None = None,
    on_step: Callable[[str], None] | None = None,
) -> Localization:
    """Look around without translating until the filter tracks a pose (or give up).

    Args:
        robot: The robot, standing where it should be localized.
        vmap: The map.
        cfg: Config; uses ``localize`` (mode, images, head pitch, filter) and ``camera``.
        mode: "verified" (the filter) or "paper"; default ``cfg.localize.mode``.
        strategy: "scan" or "paper"; default "paper" for mode paper, else "scan".
        yaws: Head yaws of a sweep, rad, in the order they are looked at.
        extra_turns: Turns in place of ``localize.extra_turn_rad`` (each followed by a
            sweep) while the belief is not concentrated (0 = never); default
            ``localize.extra_turns``.
        localizer: A filter to feed (e.g. one that is tracking already); a new one
            otherwise.
        on_step: Called with a short note as the work advances (progress display).

    Returns:
        The estimate for where the robot stands, the observations and, on a simulator, the
        error against the truth.

    Raises:
        MotionError: A turn in place failed (the robot is stopped).
    """
    t0, r0 = time.monotonic(), robot_clock(robot)
    mode = mode or cfg.localize.mode
    turns = cfg.localize.extra_turns if extra_turns is None else extra_turns
    strategy = strategy or ("paper" if mode == "paper" else "scan")
    pitch = cfg.localize.head_pitch_rad
    loc = localizer if localizer is not None else Localizer(vmap, cfg.localize.filter)
    start = len(loc.log)
    pictures = scans = turned = 0
    eyes = Eyes(robot, cfg, lines=cfg.localize.floor_lines != "off")
    try:
        stand(robot)
        if strategy == "paper":
            queries = paper_queries(
                eyes.top, cfg.localize.images, pitch=pitch,
                look_ahead=survey_look_ahead(vmap.meta), eye=eyes.floor,
            )  # fmt: skip
            c0 = time.process_time()
            feats = vmap.extract(queries)
            estimate = localize_paper(vmap, feats, queries)
            compute = time.process_time() - c0
            observations: list[Observation] = [
                Picture(q, f) for q, f in zip(queries, feats, strict=True)
            ]
            pictures = len(queries)
        else:
            order = list(yaws)
            settle = cfg.localize.settle_sigma_m
            while True:
                for k, yaw in enumerate(order):
                    p, s = look_once(eyes, loc, yaw, pitch, LINE_PITCH, k % 2 == 1)
                    pictures, scans = pictures + p, scans + s
                    now = loc.pose()
                    if now.found and own_sigma(now, loc.filter.map_floor_m) <= settle:
                        break
                if loc.pose().found or turned >= turns:
                    break
                if loc.pose().status is Status.NOT_MAPPED and loc.filter.pictures >= 2 * len(yaws):
                    break  # two sweeps fit no place: looking more will not change that
                try:
                    if not robot.motion.moveTo(0.0, 0.0, cfg.localize.extra_turn_rad):
                        raise MotionError("turning in place failed during the localization scan")
                finally:
                    robot.motion.stopMove()
                turned += 1
                order.reverse()  # sweep back from where the head is
                if on_step is not None:
                    on_step(f"turned in place, {pictures} pictures")
            estimate = loc.pose()
            observations = loc.log[start:]
            compute = loc.cpu_s + eyes.detect_s
    finally:
        eyes.close()
    truth = truth_in_map(robot, vmap.meta)
    error = heading = None
    if truth is not None and estimate.found:
        error = math.hypot(estimate.x - truth.x, estimate.y - truth.y)
        heading = math.degrees(abs(modulo2PI(estimate.theta - truth.theta)))
    return Localization(
        estimate=estimate,
        observations=list(observations),
        strategy=strategy,
        pictures=pictures,
        line_scans=scans,
        truth=truth,
        error_m=error,
        heading_error_deg=heading,
        wall_s=time.monotonic() - t0,
        robot_s=robot_clock(robot) - r0,
        extra_turns=turned,
        compute_s=compute,
    )


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
    toward the robot's front (0 = straight at it, as in the paper's survey).

    Args:
        camera: The camera subscription (only the head moves).
        images: 1 or 2 pictures (more are capped at 2); the second is turned
            :data:`PAPER_SECOND_OFFSET` toward the wall.
        pitch: Head pitch, rad.
        look_ahead: The survey's turn from the wall toward the walking direction, rad.
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

    From a map's meta (``picture_yaw`` and ``head_yaw``); 0 when it has neither (a survey
    that faced the wall).
    """
    picture, head = meta.get("picture_yaw"), meta.get("head_yaw")
    if not isinstance(picture, (int, float)) or not isinstance(head, (int, float)):
        return 0.0
    return abs(float(picture) - float(head))


def covariance_ellipse(cov: np.ndarray, p: float = 0.99) -> tuple[float, float, float]:
    """Semi-axes (m) and angle (rad, map frame) of a position covariance's ``p`` ellipse."""
    vals, vecs = np.linalg.eigh(cov[:2, :2])
    k = math.sqrt(-2.0 * math.log(1.0 - p))
    a, b = (k * math.sqrt(max(float(v), 0.0)) for v in vals[::-1])
    return a, b, math.atan2(float(vecs[1, 1]), float(vecs[0, 1]))
