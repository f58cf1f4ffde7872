"""Survey keyframe poses referenced to the walls, instead of the drifting odometry.

A NAO's odometry errs about 10 % in distance and 6 % in turns and its heading wanders, so
after two laps the keyframe poses it reports are metres off (measured: median 2.1 m, max
4.4 m in the paper room). The survey, though, walks a known rectangle (``survey.side_m``,
or the room size less twice ``survey.wall_offset_m``) whose corners the front wall's
floor line places, and after every step it measures the side wall's floor line (bottom
camera): how far the wall is and at what angle. That fixes, for every keyframe, its
heading (the side's direction plus the measured angle to the wall), its distance from the
side wall, and, with the odometry's distance walked scaled so that each side ends at its
corner, its place along the side. The metric scale comes from the known rectangle (the
room dimensions the user gives) and the camera height behind the floor-line distances.

Furniture stands in front of walls: a side's line reads nearer where a bookcase or a
sideboard is. So the side's wall is the *farthest* line that a quarter of the side's frames
(and at least three) agree with once the odometry's walk inward is taken off, and every
frame's distance from the wall is that line's carried by the odometry (the survey's own
start included, whose line may see only the furniture it was put beside). The next side's
wall is the front wall this side turned at: it says where the side ended, better than the
front lines near a corner (furniture stands there too), which only the last side needs.

Frames: the wall frame W has its origin at the circuit's first corner (where the survey
starts), x along the first side, y to the left; the result is in the map frame (the
robot's pose at the survey start), as the odometry poses were. Distances in metres, angles
in radians.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from naoloc.geometry import Pose2D, modulo2PI
from naoloc.keyframe import Keyframe

MAX_OFFSET_ERROR_M: Final = 0.5  # a side line farther than this from the offset is not used
MAX_ANGLE_ERROR_RAD: Final = 0.35  # nor one at a larger angle to the expected wall
MIN_CORNER_TURN_RAD: Final = math.pi / 4  # an odometry turn this large between frames: corner
SCALE_RANGE: Final = (0.7, 1.4)  # a side's metres per odometry metre outside this: not used
MIN_CORNER_FRACTION: Final = 0.5  # sides whose corner a front line must have placed
MAX_FRONT_M: Final = 2.2  # front lines are checked to 2.2 m (tools/floorline_accuracy.py)
LINE_STD_M: Final = 0.03  # a floor line's distance, one sigma (NAO's lens reads 2-4 cm long)
LINE_STD_RAD: Final = 0.01  # and its angle
MIN_ANGLE_GATE_RAD: Final = 0.12  # an angle this close to the prediction is always used
WALL_CLUSTER_M: Final = 0.05  # side lines this close (after the walk inward) see one thing
MIN_WALL_FRAMES: Final = 3  # frames that must see a side's wall
WALL_SUPPORT: Final = 0.25  # and the share of the side's lines that must


@dataclass(frozen=True)
class WallPoses:
    """The wall-referenced keyframe poses and how they were found.

    Attributes:
        keyframes: The keyframes with ``pose`` replaced (map frame).
        side_scales: Metres per odometry metre of each side walked (None: no corner seen).
        lines_used: Keyframes whose pose used their side wall's line.
    """

    keyframes: list[Keyframe]
    side_scales: list[float | None]
    lines_used: int

    def summary(self) -> dict[str, Any]:
        """JSON-able facts for the map's meta."""
        known = [s for s in self.side_scales if s is not None]
        return {
            "sides": len(self.side_scales),
            "sides_with_corner": len(known),
            "median_scale": None if not known else round(float(np.median(known)), 4),
            "lines_used": self.lines_used,
            "frames": len(self.keyframes),
        }


def _sides_of_frames(
    meta_vision: Sequence[dict[str, Any]], keyframes: Sequence[Keyframe]
) -> list[int]:
    """Side index (0, 1, 2, ... over all laps) of every keyframe.

    New surveys record it per frame; for older ones a turn of more than 45 degrees in the
    odometry between two frames starts a new side.
    """
    if all(isinstance(v.get("side_index"), int) for v in meta_vision):
        return [int(v["side_index"]) for v in meta_vision]
    sides, side = [], 0
    for i, kf in enumerate(keyframes):
        if i and abs(modulo2PI(kf.pose.theta - keyframes[i - 1].pose.theta)) > MIN_CORNER_TURN_RAD:
            side += 1
        sides.append(side)
    return sides


def _line(
    entry: dict[str, Any] | None, offset: float, side_normal: float
) -> tuple[float, float] | None:
    """(distance m, robot heading to the wall direction rad) from a trusted side line."""
    if not isinstance(entry, dict):
        return None
    distance, normal = entry.get("distance_m"), entry.get("normal_rad")
    if not isinstance(distance, (int, float)) or not isinstance(normal, (int, float)):
        return None
    if not (math.isfinite(distance) and math.isfinite(normal)):
        return None
    delta = modulo2PI(side_normal - normal)
    if abs(distance - offset) > MAX_OFFSET_ERROR_M or abs(delta) > MAX_ANGLE_ERROR_RAD:
        return None
    return float(distance), float(delta)


def wall_poses(
    keyframes: Sequence[Keyframe],
    meta: dict[str, Any],
    *,
    offset: float,
) -> WallPoses | None:
    """Keyframe poses from the survey's rectangle, its floor lines and the odometry.

    Args:
        keyframes: The survey's keyframes, in the order taken (odometry poses, map frame).
        meta: The survey meta: ``sides_m``, ``vision`` (per-frame side and front lines),
            ``wall_follow.side_normal`` and optionally ``start_side``.
        offset: ``survey.wall_offset_m``, m.

    Returns:
        The poses, or None when the meta lacks what this needs (no vision, a survey that
        did not follow walls) or when front lines placed fewer than half of the corners
        (the robot did not walk the known rectangle): the odometry poses are then kept.
    """
    vision = meta.get("vision")
    sides_m = meta.get("sides_m")
    follow = meta.get("wall_follow")
    if (
        not isinstance(vision, list)
        or len(vision) != len(keyframes)
        or not isinstance(sides_m, list)
        or len(sides_m) != 2
        or not isinstance(follow, dict)
        or not isinstance(follow.get("side_normal"), (int, float))
        or not keyframes
    ):
        return None
    side_normal = float(follow["side_normal"])
    turn = -math.copysign(1.0, side_normal)  # wall on the right: the corners turn left
    side_of = _sides_of_frames(vision, keyframes)
    n_sides = side_of[-1] + 1
    lengths = [float(sides_m[k % 2]) for k in range(n_sides)]

    # Distance walked (odometry) from each side's corner to each frame.
    along = np.zeros(len(keyframes))
    prev = Pose2D()
    for i, kf in enumerate(keyframes):
        step = math.hypot(kf.pose.x - prev.x, kf.pose.y - prev.y)
        first = i == 0 or side_of[i] != side_of[i - 1]
        along[i] = step if first else along[i - 1] + step
        prev = kf.pose
    corners = [np.zeros(2)]
    for k in range(n_sides):
        d = k * turn * math.pi / 2
        corners.append(corners[-1] + lengths[k] * np.array([math.cos(d), math.sin(d)]))

    # Pass 1, per frame: the heading to the side wall (the filtered line angles), the
    # distance walked inward since the side began (odometry, turned by that heading) and
    # the side line's distance.
    track = _SideTrack()
    deltas: list[float] = []
    inward_m: list[float] = []
    measured: list[float | None] = []
    fallback: list[float] = []
    start_line = _line(meta.get("start_side"), offset, side_normal)
    for i, kf in enumerate(keyframes):
        k = side_of[i]
        if i and k == side_of[i - 1]:
            inward_m.append(inward_m[-1] + track.predict(keyframes[i - 1].pose, kf.pose, turn))
        else:
            track.reset()
            inward_m.append(0.0)
        line = _line(vision[i].get("side"), offset, side_normal)
        track.update(line, offset)
        deltas.append(track.delta)
        measured.append(None if line is None else line[0])
        fallback.append(track.lateral)
    # The survey's origin stands before side 0's first frame: its line belongs to side 0.
    start_inward = -_inward(Pose2D(), keyframes[0].pose, 0.0 if start_line is None
                            else start_line[1], turn)  # fmt: skip

    # Pass 2, per side: the wall is the farthest line (furniture only stands in front of
    # it); every frame's distance from it is that line's, carried by the odometry's inward
    # motion. A side with no such wall keeps the filtered distances.
    wall_at: dict[int, float] = {}
    used = 0
    for k in range(n_sides):
        idx = [i for i in range(len(keyframes)) if side_of[i] == k]
        seen = [m - inward_m[i] for i in idx if (m := measured[i]) is not None]
        extra = [start_line[0] - start_inward] if k == 0 and start_line is not None else []
        wall = farthest_wall(seen + extra)
        if wall is not None:
            wall_at[k] = wall
            used += sum(1 for c in seen if abs(c - wall) < WALL_CLUSTER_M)

    # Where each side ended: the next side's wall (the farthest line along all of it) is
    # the front wall this side turned at, so the last frame's distance to it is known.
    # A side starts where the previous one ended: as far along it as that side's last
    # frame stood inward of its circuit.
    laterals = [
        wall_at[k] + inward_m[i] - offset if (k := side_of[i]) in wall_at else fallback[i]
        for i in range(len(keyframes))
    ]
    ends: dict[int, tuple[float, float]] = {}
    starts: dict[int, float] = {}
    for k in range(n_sides - 1):
        last = max(i for i in range(len(keyframes)) if side_of[i] == k)
        starts[k + 1] = laterals[last]
        if k + 1 not in wall_at:
            continue
        ahead = deltas[last] - turn * math.pi / 2  # heading off side k+1's direction
        behind = -_inward(keyframes[last].pose, keyframes[last + 1].pose, ahead, turn)
        to_go = wall_at[k + 1] + behind  # from the last frame to side k+1's wall, m
        ends[k] = (float(along[last]), lengths[k] - (to_go - offset))
    true_along, scales = _along_sides(along, side_of, vision, lengths, offset, ends, starts)
    if sum(1 for x in scales if x is not None) < MIN_CORNER_FRACTION * n_sides:
        # The front wall's line put too few corners: the robot did not walk the known
        # rectangle (sides ended by odometry), which these poses assume.
        return None

    poses: list[Pose2D] = []
    for i, lateral in enumerate(laterals):
        k = side_of[i]
        d = k * turn * math.pi / 2
        u = np.array([math.cos(d), math.sin(d)])
        inward = np.array([-math.sin(d), math.cos(d)]) * turn  # away from the wall
        position = corners[k] + true_along[i] * u + lateral * inward
        poses.append(Pose2D(float(position[0]), float(position[1]), modulo2PI(d + deltas[i])))

    start = _start_pose(meta.get("start_side"), offset, side_normal)
    if 0 in wall_at:  # the origin's distance from side 0's wall, not from what it saw
        start = Pose2D(0.0, (wall_at[0] + start_inward - offset) * turn, start.theta)
    out = [
        dataclasses.replace(kf, pose=start.inverse() * p, command_pose=None)
        for kf, p in zip(keyframes, poses, strict=True)
    ]
    return WallPoses(out, scales, used)


class _SideTrack:
    """Heading to the side wall and distance inward of the circuit, along one side.

    The odometry's relative motion between frames predicts both; a side line that
    disagrees with the prediction by more than its gate (a chair's foot, a rug's edge) is
    not used, unless the prediction has grown too uncertain to judge.
    """

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """A new side: the survey's steering put the robot back on the circuit."""
        self.lateral, self.delta = 0.0, 0.0
        self.var_lateral, self.var_delta = 0.15**2, 0.1**2

    def predict(self, before: Pose2D, after: Pose2D, turn: float) -> float:
        """Move by the odometry's step from ``before`` to ``after`` (map frame).

        Returns:
            The step's motion inward (away from the side wall), m.
        """
        step = before.inverse() * after
        moved = _inward(before, after, self.delta, turn)
        self.lateral += moved
        self.delta = modulo2PI(self.delta + step.theta)
        dist = math.hypot(step.x, step.y)
        self.var_lateral += (0.02 + 0.15 * abs(step.y)) ** 2 + (dist * 0.05) ** 2
        self.var_delta += (0.03 + 0.1 * abs(step.theta)) ** 2  # NAO's heading wanders
        return moved

    def update(self, line: tuple[float, float] | None, offset: float) -> bool:
        """Use a measured side line (distance m, heading rad) where it passes the gates.

        The line's angle (measured to about 0.01 rad) and its distance are gated on their
        own: a line parallel to the wall but off in distance (a skirting's top edge, a
        sofa's foot) still gives the heading.

        Returns:
            True when the distance was used.
        """
        if line is None:
            return False
        lateral, delta = line[0] - offset, line[1]
        gate = 3 * math.sqrt(self.var_delta + LINE_STD_RAD**2)
        if abs(modulo2PI(delta - self.delta)) <= max(gate, MIN_ANGLE_GATE_RAD):
            g = self.var_delta / (self.var_delta + LINE_STD_RAD**2)
            self.delta = modulo2PI(self.delta + g * modulo2PI(delta - self.delta))
            self.var_delta *= 1 - g
        if abs(lateral - self.lateral) > 3 * math.sqrt(self.var_lateral + LINE_STD_M**2):
            return False
        g = self.var_lateral / (self.var_lateral + LINE_STD_M**2)
        self.lateral += g * (lateral - self.lateral)
        self.var_lateral *= 1 - g
        return True


def _along_sides(
    along: np.ndarray,
    side_of: Sequence[int],
    vision: Sequence[dict[str, Any]],
    lengths: Sequence[float],
    offset: float,
    ends: dict[int, tuple[float, float]] | None = None,
    starts: dict[int, float] | None = None,
) -> tuple[np.ndarray, list[float | None]]:
    """Each frame's distance from its side's corner (m), from the odometry's distance walked
    mapped through anchors: the corner (0 at 0) and, where the next side's wall says where
    this side ended (``ends``: side -> (odometry along, true along) of its last frame), that
    alone; else every front-wall line, which puts the frame it was measured at
    ``length - (distance - offset)`` along the side. A side's start (odometry 0) is at
    ``starts[side]`` (m; default 0): where the previous side's last frame stood.

    Returns:
        The distances and each side's overall metres per odometry metre (None: no anchor).
    """
    out = np.full_like(along, np.nan)
    scales: list[float | None] = []
    frames_of: list[list[int]] = [[] for _ in lengths]
    for i, k in enumerate(side_of):
        frames_of[k].append(i)
    for k, (idx, length) in enumerate(zip(frames_of, lengths, strict=True)):
        anchors = [(0.0, (starts or {}).get(k, 0.0))]
        if ends is not None and k in ends and ends[k][0] > 0:
            anchors.append(ends[k])
            idx_lines: list[int] = []
        else:
            idx_lines = idx
        for j, i in enumerate(idx_lines):
            front = vision[i].get("front")
            if j == 0 or not isinstance(front, dict):
                continue
            distance = front.get("distance_m")
            if (
                isinstance(distance, (int, float))
                and math.isfinite(distance)
                and distance <= MAX_FRONT_M
            ):
                where = length - (float(distance) - offset)
                anchors.append((float(along[idx[j - 1]]), where))  # measured before the step
        anchors.sort()
        kept = [anchors[0]]
        for o, t in anchors[1:]:
            if o > kept[-1][0] + 1e-6 and t > kept[-1][1]:
                s = (t - kept[-1][1]) / (o - kept[-1][0])
                if SCALE_RANGE[0] <= s <= SCALE_RANGE[1] or len(kept) > 1:
                    kept.append((o, t))
        scale = kept[-1][1] / kept[-1][0] if len(kept) > 1 else None
        scales.append(scale if scale is None or SCALE_RANGE[0] <= scale <= SCALE_RANGE[1] else None)
        if len(kept) > 1:  # sides without an anchor stay NaN: scaled below
            xs, ys = np.array([a[0] for a in kept]), np.array([a[1] for a in kept])
            last = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
            for i in idx:
                o = along[i]
                out[i] = np.interp(o, xs, ys) if o <= xs[-1] else ys[-1] + (o - xs[-1]) * last
    known = [s for s in scales if s is not None]
    fallback = float(np.median(known)) if len(known) >= 2 else 1.0
    missing = np.isnan(out)
    out[missing] = along[missing] * fallback
    for idx, length in zip(frames_of, lengths, strict=True):
        out[idx] = np.clip(out[idx], 0.0, length + 0.5)
    return out, scales


def _inward(before: Pose2D, after: Pose2D, delta: float, turn: float) -> float:
    """The odometry step from ``before`` to ``after`` (map frame) inward, away from the side
    wall, for a robot heading ``delta`` rad off the wall's direction, m."""
    step = before.inverse() * after
    return turn * (step.x * math.sin(delta) + step.y * math.cos(delta))


def farthest_wall(seen: Sequence[float]) -> float | None:
    """The side wall's distance from the side's start (m), from what every frame saw.

    Args:
        seen: Per frame with a side line: its distance less the inward walked since the
            side began (the same value for every frame that saw the wall).

    Returns:
        The farthest value that at least ``max(3, 25 %)`` of the frames agree with (within
        :data:`WALL_CLUSTER_M`), their median; None when no value has that support.
        Furniture along the wall gives nearer values; a lone far reading (a doorway's
        line, a reflection) lacks support.
    """
    if not seen:
        return None
    values = np.sort(np.asarray(seen, np.float64))[::-1]
    need = max(MIN_WALL_FRAMES, math.ceil(WALL_SUPPORT * values.size))
    for v in values:
        near = values[np.abs(values - v) < WALL_CLUSTER_M]
        if near.size >= need:
            return float(np.median(near))
    return None


def _start_pose(entry: Any, offset: float, side_normal: float) -> Pose2D:
    """The survey start (the map frame's origin) in the wall frame."""
    line = _line(entry, offset, side_normal)
    if line is None:
        return Pose2D()
    turn = -math.copysign(1.0, side_normal)
    return Pose2D(0.0, (line[0] - offset) * turn, line[1])
