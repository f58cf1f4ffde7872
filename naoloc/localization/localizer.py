"""``Localizer``: observations in, the belief's pose out. Robot-free and replayable.

::

    loc = Localizer(vmap, cfg.localize.filter)
    loc.update(Picture(keyframe))              # a picture with its odometry
    loc.update(LineScan(lines, odometry, t))   # floor-wall lines
    est = loc.pose()                           # PoseEstimate: pose, covariance, status

The pose is the robot's (FRAME_ROBOT origin) in the map frame at the latest observation's
odometry. ``status`` is ``tracking`` (the belief is concentrated on one place),
``lost`` (it is not, yet) or ``not the mapped room`` (the observations fit no place of the
map better than they fit somewhere else). Only a tracking estimate has a pose; the others
say why not. Every observation is kept in :attr:`Localizer.log`, so
:func:`replay` gives another map the same observations (an evaluation's re-scoring).
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.config import FilterTuning
from naoloc.geometry import Pose2D
from naoloc.localization.filter import Belief, MultiHypothesisFilter
from naoloc.localization.observations import LineScan, Observation, Odometry, Picture, Relocalize
from naoloc.localization.pictures import LandmarkIndex, match_picture
from naoloc.localization.walls import wall_map
from naoloc.mapping.map import VisualMap

__all__ = ["Localizer", "PoseEstimate", "Status", "decide", "replay", "turn_scale_of"]


class Status(enum.StrEnum):
    """What the belief says."""

    TRACKING = "tracking"
    LOST = "lost"
    NOT_MAPPED = "not the mapped room"


@dataclass(frozen=True)
class PoseEstimate:
    """The belief's answer.

    Attributes:
        x: Forward coordinate, m (map frame); NaN unless tracking.
        y: Left coordinate, m (map frame); NaN unless tracking.
        theta: Heading, rad in (-pi, pi] (map frame); NaN unless tracking.
        covariance: 3 x 3 covariance of (x, y, theta) (m^2, rad^2); None unless tracking.
            It holds the belief's spread, the map's own error (``map_floor_m``) and the map
            frame's heading error at this pose (``map_frame``).
        confidence: Probability of the best place given the observations (0 unless
            tracking).
        status: Tracking, lost, or not the mapped room.
        reason: Why there is no pose ("" when tracking).
        method: ``filter`` (or ``gcs`` for the paper's Algorithm 5, ``none`` without a pose).
        evidence: JSON-able figures behind it (pictures, support, hypotheses, other_room).
        map_frame: The part of ``covariance`` that is the map frame's heading error
            (:func:`frame_covariance`; None unless tracking): no look removes it.
    """

    x: float
    y: float
    theta: float
    covariance: np.ndarray | None
    confidence: float
    status: Status
    reason: str = ""
    method: str = "filter"
    evidence: dict[str, Any] = field(default_factory=dict)
    map_frame: np.ndarray | None = None

    @property
    def found(self) -> bool:
        """Whether there is a pose."""
        return self.status is Status.TRACKING and math.isfinite(self.x)

    def pose(self) -> Pose2D:
        """The pose (map frame)."""
        return Pose2D(self.x, self.y, self.theta)

    def sigmas(self, frame: bool = True) -> tuple[float, float]:
        """Position std along the wider axis (m) and heading std (rad); inf without one.
        ``frame``: with the map frame's heading error at the pose (False: without)."""
        if self.covariance is None:
            return math.inf, math.inf
        cov = self.covariance
        if not frame and self.map_frame is not None:
            cov = cov - self.map_frame
        return MultiHypothesisFilter.sigma(cov)


def turn_scale_of(meta: dict[str, Any]) -> float:
    """The survey's odometry turn per true turn (``meta.wall_poses.turn_scale``), else 1."""
    walls = meta.get("wall_poses")
    scale = walls.get("turn_scale") if isinstance(walls, dict) else None
    return float(scale) if isinstance(scale, (int, float)) and scale > 0 else 1.0


def _sigma(value: Any) -> float | None:
    """``value`` as a sigma read from a map's meta: a finite number >= 0 (not a bool), else
    None."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return None
    return float(value) if math.isfinite(value) and value >= 0 else None


def keyframe_sigma_of(meta: dict[str, Any]) -> float | None:
    """The map's keyframes' own error (``meta.keyframe_sigma_m``, std per axis, m: how its
    survey's laps disagree, :mod:`naoloc.mapping.laps`), or None (one lap, older maps)."""
    return _sigma(meta.get("keyframe_sigma_m"))


def heading_std_of(meta: dict[str, Any], default: float) -> float:
    """The map frame's heading error (``meta.wall_poses.heading_std_rad``, one sigma, rad:
    how its survey found the start's heading to its wall), else ``default``."""
    walls = meta.get("wall_poses")
    value = _sigma(walls.get("heading_std_rad") if isinstance(walls, dict) else None)
    return default if value is None else value


def frame_covariance(pose: np.ndarray, sigma: float) -> np.ndarray:
    """The covariance a map frame turned by an error of ``sigma`` (rad, std) about its
    origin gives a pose (x, y m, theta rad; map frame): turned by ``d``, the map puts a
    place at (x, y) at (x - d y, y + d x) and every heading d more."""
    jac = np.array([-float(pose[1]), float(pose[0]), 1.0])
    return sigma**2 * np.outer(jac, jac)


def decide(belief: Belief, tun: FilterTuning) -> tuple[Status, str]:
    """The status of a belief (a pure function of it and the tuning).

    - no hypothesis, or the other-room alternative outweighs the best one, once
      ``verdict_pictures`` pictures with features were seen: not the mapped room, unless a
      probable place has shown the room before (``room_seen`` of ``null_nats`` or more: the
      robot was carried, or lost its place, in the mapped room): lost;
    - the best place is probable (``confident``), its spread narrow (``max_sigma_*``),
      its own pictures showed it (``null_nats`` of their evidence: floor lines alone fit
      every corner of a rectangle alike) and the latest picture does not contradict it:
      tracking;
    - otherwise lost (with why).
    """
    enough = belief.pictures >= tun.verdict_pictures
    known = belief.room_seen >= tun.null_nats
    if belief.pose is None or belief.cov is None:
        if enough and not known:
            return Status.NOT_MAPPED, "the pictures fit no place of the map"
        return Status.LOST, "nothing recognised yet" if not known else "the place is lost"
    if belief.other_room > belief.probability and enough:
        if known:
            return Status.LOST, "the room was recognised, the place is not yet"
        return Status.NOT_MAPPED, "the observations fit no place of the map"
    if belief.contradicted:
        return Status.LOST, "the latest picture puts the robot elsewhere"
    if belief.seen_score < tun.null_nats:
        return Status.LOST, "no picture has shown this place yet"
    if belief.probability < tun.confident:
        return Status.LOST, f"unsure between places (best {belief.probability:.2f})"
    pos, head = MultiHypothesisFilter.sigma(belief.cov)
    if pos > tun.max_sigma_m or head > tun.max_sigma_rad:
        return Status.LOST, f"the belief is too wide ({pos:.2f} m, {math.degrees(head):.0f} deg)"
    return Status.TRACKING, ""


class Localizer:
    """The one localization filter over a map.

    Args:
        vmap: The map.
        tuning: The filter's tuning (``localize.filter``); default values when None.
        seed: Seeds PnP's RANSAC (with each picture's index), so a replay is exact.
    """

    def __init__(self, vmap: VisualMap, tuning: FilterTuning | None = None, seed: int = 0) -> None:
        self.vmap = vmap
        self.tuning = tuning if tuning is not None else FilterTuning()
        self.seed = seed
        self.landmarks = LandmarkIndex(vmap)
        self.heading_std = heading_std_of(vmap.meta, self.tuning.map_frame_rad)
        self.filter = self._new_filter()
        self.log: list[Observation] = []
        self.cpu_s = 0.0
        self._pictures = 0

    def _new_filter(self) -> MultiHypothesisFilter:
        return MultiHypothesisFilter(
            wall_map(self.vmap.meta), self.tuning, turn_scale_of(self.vmap.meta),
            keyframe_sigma_of(self.vmap.meta), self.landmarks.points,
        )  # fmt: skip

    def update(self, obs: Observation) -> None:
        """Take one observation (in the order they were made)."""
        t0 = time.process_time()
        try:
            if isinstance(obs, Picture):
                feats = obs.features
                if feats is None:
                    feats = self.vmap.extract([obs.keyframe])[0]
                    obs = Picture(obs.keyframe, feats)
                seed = self.seed * 1000003 + self._pictures
                self._pictures += 1
                m = match_picture(self.vmap, self.landmarks, feats, obs.keyframe, self.tuning, seed)
                self.filter.observe(m, obs.odometry)
            elif isinstance(obs, LineScan):
                self.filter.observe(tuple(obs.lines), obs.odometry)
            elif isinstance(obs, Odometry):
                self.filter.observe(None, obs.odometry)
            elif isinstance(obs, Relocalize):
                self.filter = self._new_filter()
            else:
                raise TypeError(f"not an observation: {type(obs).__name__}")
            self.log.append(obs)
        finally:
            self.cpu_s += time.process_time() - t0

    def belief(self) -> Belief:
        """The filter's belief (its best hypothesis even when not tracking)."""
        return self.filter.belief()

    def pose(self) -> PoseEstimate:
        """The pose at the latest observation, or why there is none."""
        b = self.filter.belief()
        status, reason = decide(b, self.tuning)
        evidence = {
            "pictures": b.pictures,
            "support": b.support,
            "score": round(b.score, 2),
            "picture_score": round(b.seen_score, 2),
            "hypotheses": b.hypotheses,
            "probability": round(b.probability, 4),
            "other_room": round(b.other_room, 4),
            "room_seen": round(b.room_seen, 2),
            "observations": len(self.log),
        }
        if status is not Status.TRACKING or b.pose is None:
            nan = float("nan")
            return PoseEstimate(nan, nan, nan, None, 0.0, status, reason, "none", evidence)
        frame = frame_covariance(b.pose, self.heading_std)
        return PoseEstimate(
            float(b.pose[0]), float(b.pose[1]), float(b.pose[2]), b.cov + frame, b.probability,
            status, "", "filter", evidence, frame,
        )  # fmt: skip


def replay(
    vmap: VisualMap,
    observations: Iterable[Observation],
    tuning: FilterTuning | None = None,
    seed: int = 0,
    same_features: bool = True,
) -> Localizer:
    """A new localizer fed ``observations`` in order (re-scoring with another map).

    Args:
        vmap: The map.
        observations: What another localizer logged.
        tuning: The filter's tuning.
        seed: As :class:`Localizer`.
        same_features: Whether ``vmap`` extracts features as the map that logged them did
            (then the pictures' features are reused; else extracted again).
    """
    loc = Localizer(vmap, tuning, seed)
    for obs in observations:
        if isinstance(obs, Picture) and not same_features:
            obs = Picture(obs.keyframe)
        loc.update(obs)
    return loc
