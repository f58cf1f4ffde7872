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
sideboard is. Where the line jumps between frames, another thing is seen; the side's wall
is the *farthest* of those levels that a fifth of the side's lines (and at least three)
see, and every frame's distance from the wall is its line plus how far its stretch stands
in front of the wall (:func:`side_distances`; the survey's own start included, whose line
may see only the furniture it was put beside). The next side's
wall is the front wall this side turned at: it says where the side ended, better than the
front lines near a corner (furniture stands there too), which only the last side needs.

Frames: the wall frame W has its origin at the circuit's first corner (where the survey
starts), x along the first side, y to the left; the result is in the map frame (the
robot's pose at the survey start), as the odometry poses were. Distances in metres, angles
in radians.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from naoloc.geometry import Pose2D, modulo2PI
from naoloc.perception.wall_gate import (
    SIDE_ANGLE_ERROR_RAD,
    in_far_front_range,
    in_front_range,
    side_line_angle,
)
from naoloc.robot.keyframe import Keyframe

SCALE_RANGE: Final = (0.7, 1.4)  # a side's metres per odometry metre outside this: not used
TURN_SCALE_RANGE: Final = (0.8, 1.25)  # odometry turn per true turn outside this: not used
MIN_CORNER_FRACTION: Final = 0.5  # sides whose corner a front line must have placed
FRONT_AGREE_M: Final = 0.12  # a front line within this of the corners' walk also anchors, m
FRONT_HEADING_M: Final = 4.0  # a far wall's line gives the start's heading (angle, not distance)
LINE_STD_M: Final = 0.03  # a floor line's distance, one sigma (NAO's lens reads 2-4 cm long)
LINE_STD_RAD: Final = 0.01  # and its angle
MIN_ANGLE_GATE_RAD: Final = 0.12  # an angle this close to the prediction is always used
# A side line that jumps more than this between frames sees another thing, m. Less than a
# doorway's recess (0.2 m): at 0.2 m the paper room's doorway was entered but its end missed
# where the robot stepped 0.12 m toward the wall, and a whole side read 0.18 m off. Over 30
# surveys 0.15 m made no map pose worse (mean of the medians 0.050 -> 0.049 m, paper room
# 0.077 -> 0.047 m); lines err 1-4 cm and a step's sideways odometry 1-2 cm.
EDGE_M: Final = 0.15
# The survey start's heading to its wall is its own line's, unless side 0's frames within
# this walk (m), each turned back by the odometry's turn since the start, agree on another
# (their median more than START_GATE_RAD away): one line at the start, seen past a piece of
# furniture, once turned a whole map 0.2 rad. The frames carry the odometry's turn error
# (6 % of the survey's first steering), so the start's own line is preferred.
START_HEADING_M: Final = 1.0
START_GATE_RAD: Final = 0.06
CLEAN_RMS_M: Final = 0.006  # the start's views: lines scattered more are not its heading's
# nor those with less of their boundary on them: a start view centred on the wall's foot
# also shows the wall behind or a piece of furniture, 0.45-0.6 of its boundary on the side
# wall's line (0.6 left 992322877's start one view, 1.2 deg off, where five agreed within
# 0.2 deg; over 52 surveys the start heading's p90 error 0.76 -> 0.63 deg with 0.4)
CLEAN_FRACTION: Final = 0.4
# A survey start beside furniture: its distance from the wall is carried back by the
# odometry's walk inward from side 0's frames that see the wall within this many frames
# (their median), not taken from its stretch's depth (room 1327980321: two chests 0.36 and
# 0.45 m deep, 0.09 m apart, read as one stretch put the start, and every map pose, 9.7 cm
# off; the walk back errs 1-5 cm).
START_FROM_WALL_FRAMES: Final = 8
# The start's own line places it unless those frames, carried back, disagree by more than
# this (m): in a corner the one view that sees the wall at 0.5 m can read the wall behind.
START_AGREE_M: Final = 0.04
# ... unless the start's views agree with its line: at least this many within
# START_VIEWS_M of it. Views repeated from the standing robot measure where it stands; the
# frames carried back add the odometry's sideways walk, which another NAO's heading error
# bends 0.01-0.06 m per 0.2 m step (with each room's own odometry, 8 of 18 origins 0.05-0.11 m
# off). A start seen once, or by two views that disagree, is a corner's or the arm's
# misreading as often (the 3 x 3 m room at 0.5 m: one view, 0.1 m long).
START_VIEWS: Final = 3
START_VIEWS_M: Final = 0.015
END_FRAMES: Final = 3  # a side's last frames whose wall lines place where it ended
WALL_LEVEL_M: Final = 0.1  # stretches whose levels are this close see the same thing
MIN_WALL_FRAMES: Final = 3  # frames that must see a side's wall
WALL_SUPPORT: Final = 0.2  # and the share of the side's lines that must


@dataclass(frozen=True)
class WallPoses:
    """The wall-referenced keyframe poses and how they were found.

    Attributes:
        keyframes: The keyframes with ``pose`` replaced (map frame).
        side_scales: Metres per odometry metre of each side walked (None: no corner seen).
        lines_used: Keyframes whose pose used their side wall's line.
        turn_scale: The odometry's turn per true turn at the survey's corners (the walls
            give the true headings), None when no corner was turned or it reads implausibly;
            the localizer undoes it in the turns it makes in place.
        wall_frame: The wall frame W's origin (the circuit's first corner) in the map frame.
        walls: The room's walls in W, ``(x_min, x_max, y_min, y_max)`` (m): the circuit
            widened by the wall offset; the floor-line sensor model
            (:mod:`naoloc.localization.walls`) uses them.
        sides_of: Each keyframe's side (0, 1, 2, ... over all laps).
        lines_seen: Whether each keyframe had a usable side line (near the offset, at the
            expected angle).
        wall_seen: Whether that line saw its side's wall (not furniture before it).
        residuals: For consecutive keyframes of a side whose lines both saw the wall, the
            lines' change less the odometry's walk away from the wall between them, m (a
            straight wall and a true odometry give zero; the map checks use them).
        skirting: How far the skirting boards stand out of the walls (m): ``walls`` are the
            wall surfaces; a floor line sees the boards' face this much nearer.
        start_own: The survey start's heading to side 0's wall from its own lines (rad;
            None: it saw none).
        start_frames: The same from side 0's first frames' lines, less the odometry's turn
            since the start (rad; None: none).
    """

    keyframes: list[Keyframe]
    side_scales: list[float | None]
    lines_used: int
    turn_scale: float | None = None
    wall_frame: Pose2D | None = None
    walls: tuple[float, float, float, float] | None = None
    sides_of: list[int] = dataclasses.field(default_factory=list)
    lines_seen: list[bool] = dataclasses.field(default_factory=list)
    wall_seen: list[bool] = dataclasses.field(default_factory=list)
    residuals: list[float] = dataclasses.field(default_factory=list)
    skirting: float = 0.0
    start_own: float | None = None
    start_frames: float | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-able facts for the map's meta."""
        known = [s for s in self.side_scales if s is not None]
        return {
            "skirting_m": self.skirting,
            "sides": len(self.side_scales),
            "sides_with_corner": len(known),
            "median_scale": None if not known else round(float(np.median(known)), 4),
            "lines_used": self.lines_used,
            "frames": len(self.keyframes),
            "turn_scale": None if self.turn_scale is None else round(self.turn_scale, 4),
            **(
                {}
                if self.wall_frame is None or self.walls is None
                else {
                    "wall_frame": [
                        round(v, 5)
                        for v in (self.wall_frame.x, self.wall_frame.y, self.wall_frame.theta)
                    ],
                    "walls_m": [round(v, 4) for v in self.walls],
                }
            ),
        }


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
    delta = side_line_angle(distance, normal, offset, side_normal)
    return None if delta is None else (float(distance), float(delta))


def wall_poses(
    keyframes: Sequence[Keyframe],
    meta: dict[str, Any],
    *,
    offset: float,
    skirting: float = 0.0,
) -> WallPoses | None:
    """Keyframe poses from the survey's rectangle, its floor lines and the odometry.

    Args:
        keyframes: The survey's keyframes, in the order taken (odometry poses, map frame).
        meta: The survey meta: ``sides_m``, ``vision`` (per-frame side_index, side and front lines),
            ``wall_follow.side_normal`` and optionally ``start_side``.
        offset: ``survey.wall_offset_m``, m.
        skirting: ``survey.skirting_m``: how far the skirting boards stand out of the walls,
            m. The floor lines see the boards' face; the room (and so the circuit) is
            measured wall to wall, so every line's distance is taken this much longer.

    Returns:
        The poses, or None when the meta lacks what this needs (no vision, a survey that
        did not follow walls) or when fewer than half of the corners were placed (by the
        next side's wall or a front line): the odometry poses are then kept.
    """
    meta = _to_walls(meta, skirting)
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
    marks = [v.get("side_index") if isinstance(v, dict) else None for v in vision]
    side_of = [k for k in marks if isinstance(k, int) and not isinstance(k, bool) and k >= 0]
    if len(side_of) != len(marks) or side_of != sorted(side_of):
        return None  # each frame names its side (older datasets: see naoloc.data.dataset)
    side_normal = float(follow["side_normal"])
    turn = -math.copysign(1.0, side_normal)  # wall on the right: the corners turn left
    n_sides = side_of[-1] + 1
    frames_of: list[list[int]] = [[] for _ in range(n_sides)]  # frame indices of each side
    for i, k in enumerate(side_of):
        frames_of[k].append(i)
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
    lines: list[tuple[float, float] | None] = []  # each frame's trusted side line
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
        lines.append(line)
        fallback.append(track.lateral)
    # The survey's origin stands before side 0's first frame: its line belongs to side 0.
    start_inward = -_inward(keyframes[0].pose, 0.0 if start_line is None
                            else start_line[1], turn)  # fmt: skip

    # Pass 2, per side: what each line saw, the wall or furniture standing in front of it
    # (:func:`side_distances`), and so every frame's distance from the side's wall.
    dist: list[float | None] = [None] * len(keyframes)
    wall_seen = [False] * len(keyframes)  # the frame's line saw its side's wall
    residuals: list[float] = []  # consecutive lines on the wall against the odometry
    start_dist: float | None = None
    used = 0
    for k in range(n_sides):
        idx = frames_of[k]
        m = [None if (line := lines[i]) is None else line[0] for i in idx]
        dy = [0.0] + [inward_m[i] - inward_m[j] for j, i in itertools.pairwise(idx)]
        if k == 0:  # the survey's origin stands before side 0's first frame
            m = [None if start_line is None else start_line[0], *m]
            dy = [0.0, -start_inward, *dy[1:]]
        found = side_distances(m, dy)
        if found is None:
            continue
        dists, on_wall = found
        if k == 0:
            back = _start_from_wall(dists, on_wall, dy)
            agrees = on_wall[0] and (
                abs(dists[0] - back) <= START_AGREE_M
                or start_views_agree(
                    meta.get("start_views"), dists[0] - skirting, offset, side_normal
                )
            )
            start_dist = dists[0] if agrees else back
            dists, on_wall = dists[1:], on_wall[1:]
        used += sum(on_wall)
        for i, v, w in zip(idx, dists, on_wall, strict=True):
            dist[i], wall_seen[i] = v, w
        for j, i in itertools.pairwise(idx):
            if wall_seen[i] and wall_seen[j]:
                li, lj = lines[i], lines[j]
                assert li is not None and lj is not None  # a line that saw the wall
                residuals.append(li[0] - lj[0] - (inward_m[i] - inward_m[j]))

    # A side starts where the previous one ended: as far along it as that side's last
    # frame stood inward of its circuit.
    laterals = [fallback[i] if (di := dist[i]) is None else di - offset for i in range(len(dist))]
    ends: dict[int, tuple[float, float]] = {}
    starts: dict[int, float] = {}
    for k in range(n_sides - 1):
        if not frames_of[k]:
            continue  # a side the survey found itself at the end of: no step, no picture
        last = frames_of[k][-1]
        starts[k + 1] = _end_lateral(frames_of[k], laterals, wall_seen, inward_m)
        nxt = dist[last + 1] if side_of[last + 1] == k + 1 else None
        if nxt is None:
            continue
        ahead = deltas[last] - turn * math.pi / 2  # heading off side k+1's direction
        corner = keyframes[last].pose.inverse() * keyframes[last + 1].pose  # the turn's step
        behind = -_inward(corner, ahead, turn)
        to_go = nxt + behind  # from the last frame to side k+1's wall, m
        ends[k] = (float(along[last]), lengths[k] - (to_go - offset))
    true_along, scales = _along_sides(along, frames_of, vision, lengths, offset, ends, starts)
    if sum(1 for x in scales if x is not None) < MIN_CORNER_FRACTION * n_sides:
        # Neither the next side's wall nor a front line placed enough corners: the robot
        # may not have walked the known rectangle, which these poses assume.
        return None

    poses: list[Pose2D] = []
    for i, lateral in enumerate(laterals):
        k = side_of[i]
        d = k * turn * math.pi / 2
        u = np.array([math.cos(d), math.sin(d)])
        inward = np.array([-math.sin(d), math.cos(d)]) * turn  # away from the wall
        position = corners[k] + true_along[i] * u + lateral * inward
        poses.append(Pose2D(float(position[0]), float(position[1]), modulo2PI(d + deltas[i])))

    # The survey start (the map frame's origin) in the wall frame.
    own, clean = _own_heading(meta, offset, side_normal)
    heading, frames_heading = _start_heading(own, keyframes, lines, frames_of[0], along, clean)
    start = Pose2D(0.0, 0.0, heading or 0.0)
    if start_dist is not None:  # the origin's distance from side 0's wall, not what it saw
        start = Pose2D(0.0, (start_dist - offset) * turn, start.theta)
    elif start_line is not None:
        start = Pose2D(0.0, (start_line[0] - offset) * turn, start.theta)
    out = [
        dataclasses.replace(kf, pose=start.inverse() * p, command_pose=None)
        for kf, p in zip(keyframes, poses, strict=True)
    ]
    # The walls in W: side 0's beside the first corner, the others a side's length beyond.
    far_y = turn * (float(sides_m[1]) + offset)
    walls = (
        -offset, float(sides_m[0]) + offset, min(-turn * offset, far_y), max(-turn * offset, far_y)
    )  # fmt: skip
    return WallPoses(
        out,
        scales,
        used,
        _turn_scale(keyframes, side_of, lines, turn),
        start.inverse(),
        walls,
        sides_of=list(side_of),
        lines_seen=[line is not None for line in lines],
        wall_seen=wall_seen,
        residuals=residuals,
        skirting=skirting,
        start_own=own,
        start_frames=frames_heading,
    )


def _end_lateral(
    idx: Sequence[int],
    laterals: Sequence[float],
    wall_seen: Sequence[bool],
    inward_m: Sequence[float],
) -> float:
    """Where a side's last frame stood inward of its circuit (m): the median of its last
    :data:`END_FRAMES` frames whose lines saw the wall, each carried to the
    last frame by the odometry's walk inward (a corner's plant or sideboard is often all
    the last frame's line sees); the last frame's own lateral without such frames."""
    last = idx[-1]
    votes = [
        laterals[i] + (inward_m[last] - inward_m[i]) for i in idx[-END_FRAMES:] if wall_seen[i]
    ]
    return float(np.median(votes)) if votes else laterals[last]


def _to_walls(meta: dict[str, Any], skirting: float) -> dict[str, Any]:
    """The survey meta with every floor line's distance ``skirting`` m longer (from the
    boards' face to the wall behind them)."""
    if skirting == 0.0:
        return meta

    def moved(entry: Any) -> Any:
        if not isinstance(entry, dict) or not isinstance(entry.get("distance_m"), (int, float)):
            return entry
        return {**entry, "distance_m": float(entry["distance_m"]) + skirting}

    out = dict(meta)
    for key in ("start_side", "start_front", "start_across"):
        if key in out:
            out[key] = moved(out[key])
    vision = out.get("vision")
    if isinstance(vision, list):
        out["vision"] = [
            {**v, **{k: moved(v[k]) for k in ("side", "front", "far_front") if k in v}}
            if isinstance(v, dict)
            else v
            for v in vision
        ]
    return out


def _turn_scale(
    keyframes: Sequence[Keyframe],
    side_of: Sequence[int],
    lines: Sequence[tuple[float, float] | None],
    turn: float,
) -> float | None:
    """Odometry turn per true turn at the corners.

    At each corner with a side line on both frames around it, the true turn is the quarter
    turn plus the change of the robot's heading to its wall, as the two lines read it (raw:
    the filtered headings lag a turn); the odometry's is its own heading change.
    """
    odo = true = 0.0
    for i in range(1, len(keyframes)):
        if side_of[i] == side_of[i - 1]:
            continue
        before, after = lines[i - 1], lines[i]
        if before is None or after is None:
            continue
        quarter = turn * math.pi / 2 * (side_of[i] - side_of[i - 1])
        true += abs(quarter + after[1] - before[1])
        odo += abs(modulo2PI(keyframes[i].pose.theta - keyframes[i - 1].pose.theta))
    if true == 0.0 or not TURN_SCALE_RANGE[0] <= odo / true <= TURN_SCALE_RANGE[1]:
        return None
    return odo / true


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
        moved = _inward(step, self.delta, turn)
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
    frames_of: Sequence[Sequence[int]],
    vision: Sequence[dict[str, Any]],
    lengths: Sequence[float],
    offset: float,
    ends: dict[int, tuple[float, float]] | None = None,
    starts: dict[int, float] | None = None,
) -> tuple[np.ndarray, list[float | None]]:
    """Each frame's distance from its side's corner (m), from the odometry's distance walked
    mapped through anchors (``frames_of``: each side's frame indices, in walking order):
    the corner (0 at 0) and, where the next side's wall says where this side ended
    (``ends``: side -> (odometry along, true along) of its last frame), that and the
    front-wall lines that agree with it; else every front-wall line. A front line puts the
    frame it was measured at ``length - (distance - offset)`` along the side. The front
    lines are the survey's (``front``, up to :data:`~naoloc.perception.wall_gate.FRONT_RANGE_M`
    ahead, measured before the frame's step) and its far pictures' level look ahead
    (``far_front``, up to :data:`~naoloc.perception.wall_gate.FAR_FRONT_RANGE_M`, at the
    frame's stop): between the corner and the first front line only the odometry places
    the frames, and its random walk is largest in the middle of a long side. A side's start
    (odometry 0) is at ``starts[side]`` (m; default 0): where the previous side's last frame
    stood.

    Returns:
        The distances and each side's overall metres per odometry metre (None: no anchor).
    """
    out = np.full_like(along, np.nan)
    scales: list[float | None] = []
    for k, (idx, length) in enumerate(zip(frames_of, lengths, strict=True)):
        anchors = [(0.0, (starts or {}).get(k, 0.0))]
        fronts = []
        for j, i in enumerate(idx):
            front = vision[i].get("front")
            if j == 0 or not isinstance(front, dict):
                continue
            distance = front.get("distance_m")
            if (
                isinstance(distance, (int, float))
                and math.isfinite(distance)
                and in_front_range(distance)
            ):
                where = length - (float(distance) - offset)
                fronts.append((float(along[idx[j - 1]]), where))  # measured before the step
        for i in idx:  # the far pictures' level look ahead, at the frame's own stop
            far = vision[i].get("far_front")
            distance = far.get("distance_m") if isinstance(far, dict) else None
            if (
                isinstance(distance, (int, float))
                and math.isfinite(distance)
                and in_far_front_range(distance)
            ):
                fronts.append((float(along[i]), length - (float(distance) - offset)))
        if ends is not None and k in ends and ends[k][0] > 0:
            # The next wall placed the side's end; front lines that agree with the walk
            # between the corners (within FRONT_AGREE_M) place the frames near the end too
            # (a front line that sees furniture before the wall does not agree).
            (o0, t0), (o1, t1) = anchors[0], ends[k]
            anchors.append(ends[k])
            anchors += [
                (o, t) for o, t in fronts
                if o < o1 and abs(t - (t0 + (o - o0) * (t1 - t0) / (o1 - o0))) <= FRONT_AGREE_M
            ]  # fmt: skip
        else:
            anchors += agreeing_fronts(anchors[0], fronts)
        anchors.sort()
        kept = [anchors[0]]
        for o, t in anchors[1:]:
            if o > kept[-1][0] + 1e-6 and t > kept[-1][1]:
                s = (t - kept[-1][1]) / (o - kept[-1][0])
                if SCALE_RANGE[0] <= s <= SCALE_RANGE[1] or len(kept) > 1:
                    kept.append((o, t))
        # metres per odometry metre between the side's first and last anchors (its start
        # may stand off the corner: where the previous side's last frame stood)
        scale = (kept[-1][1] - kept[0][1]) / (kept[-1][0] - kept[0][0]) if len(kept) > 1 else None
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


def agreeing_fronts(
    start: tuple[float, float], fronts: Sequence[tuple[float, float]]
) -> list[tuple[float, float]]:
    """The front lines of one side that agree with one walk along it.

    Each front line puts the frame it was measured at somewhere along the side; over one
    side those places lie on one line against the odometry's distance walked (its slope the
    metres per odometry metre). A line that saw a plank's seam or a rug's edge instead of
    the wall does not. The walk taken is the line through two of the points (the side's
    start among them) with a slope in :data:`SCALE_RANGE` that most front lines agree
    with, within :data:`FRONT_AGREE_M` (ties: the smaller sum of residuals).

    Args:
        start: The side's start: (odometry along, true along), m.
        fronts: The front lines' (odometry along, true along), m.

    Returns:
        The front lines that agree (all of them with fewer than two, or no walk with two
        agreeing).
    """
    if len(fronts) < 2:
        return list(fronts)
    o = np.array([f[0] for f in fronts])
    t = np.array([f[1] for f in fronts])
    best: tuple[int, float] = (1, 0.0)
    kept: list[tuple[float, float]] = list(fronts)
    for a, b in itertools.combinations([start, *fronts], 2):
        if abs(b[0] - a[0]) < 1e-6:
            continue
        slope = (b[1] - a[1]) / (b[0] - a[0])
        if not SCALE_RANGE[0] <= slope <= SCALE_RANGE[1]:
            continue
        residual = np.abs(t - (a[1] + slope * (o - a[0])))
        inliers = residual <= FRONT_AGREE_M
        count, total = int(inliers.sum()), float(residual[inliers].sum())
        if count > best[0] or (count == best[0] and count > 1 and total < best[1]):
            best = (count, total)
            kept = [f for f, k in zip(fronts, inliers, strict=True) if k]
    return kept


def _inward(step: Pose2D, delta: float, turn: float) -> float:
    """An odometry step (in the robot's frame before it) inward, away from the side wall,
    for a robot heading ``delta`` rad off the wall's direction, m."""
    return turn * (step.x * math.sin(delta) + step.y * math.cos(delta))


def side_distances(
    measured: Sequence[float | None], inward: Sequence[float]
) -> tuple[list[float], list[bool]] | None:
    """Every frame's distance from one side's wall, from its floor lines (m).

    A line sees the wall or something standing in front of it (a bookcase, a sideboard):
    where the line jumps by more than :data:`EDGE_M` between frames, beyond what the
    robot's own walk inward explains, a new stretch begins, one level nearer or farther.
    The wall is the farthest level that at least ``max(3, 20 %)`` of the lines see (a lone
    far line, a doorway's or a reflection's, lacks that support); a frame's distance is
    its line plus how far its stretch stands in front of the wall, or its own line when its
    stretch is within :data:`WALL_LEVEL_M` of the wall's level (it sees the wall: such
    levels differ only by the odometry's sideways error between them). Frames without a line
    take the nearest frame's distance moved by the odometry's walk inward (only the
    odometry's short-range motion is used: a NAO's sideways odometry drifts 0.3 m along a
    5 m side).

    Args:
        measured: Per frame in walking order: the side line's distance (m) or None.
        inward: Per frame: the odometry's walk inward (away from the wall) since the
            previous frame (m; the first is not used).

    Returns:
        ``(distances, whether each frame's line saw the wall)``; None when no level has
        that support.
    """
    levels: list[float | None] = []
    level, last, walked = 0.0, None, 0.0
    for i, m in enumerate(measured):
        walked += inward[i] if i else 0.0
        if m is None:
            levels.append(None)
            continue
        if last is not None:
            jump = m - last - walked
            if abs(jump) > EDGE_M:
                level += jump
        levels.append(level)
        last, walked = m, 0.0
    seen = [v for v in levels if v is not None]
    if not seen:
        return None
    need = max(MIN_WALL_FRAMES, math.ceil(WALL_SUPPORT * len(seen)))
    wall = None
    for v in sorted(set(seen), reverse=True):
        near = [u for u in seen if abs(u - v) < WALL_LEVEL_M]
        if len(near) >= need:
            wall = max(set(near), key=near.count)  # the stretch most of its lines are on
            break
    if wall is None:
        return None
    on_wall = [v is not None and abs(v - wall) < WALL_LEVEL_M for v in levels]
    # A line on the wall's level sees the wall: its own distance, not the level's (levels
    # closer than WALL_LEVEL_M differ only by the odometry's sideways error in between).
    out: list[float | None] = [
        m if seen else None if (m is None or v is None) else m + (wall - v)
        for m, v, seen in zip(measured, levels, on_wall, strict=True)
    ]
    for i in range(1, len(out)):  # forward: carry the last distance by the walk inward
        prev = out[i - 1]
        if out[i] is None and prev is not None:
            out[i] = prev + inward[i]
    for i in range(len(out) - 2, -1, -1):  # the frames before the first line
        nxt = out[i + 1]
        if out[i] is None and nxt is not None:
            out[i] = nxt - inward[i + 1]
    return [float(v) for v in out if v is not None], on_wall


def _start_from_wall(
    dists: Sequence[float], on_wall: Sequence[bool], inward: Sequence[float]
) -> float:
    """The survey start's distance from side 0's wall from its first frames (m): when its
    own line saw furniture, or disagrees with them by more than :data:`START_AGREE_M`
    while its views do not repeat it (:func:`start_views_agree`).

    Each of the first :data:`START_FROM_WALL_FRAMES` frames whose line sees the wall gives
    its distance less the odometry's walk inward since the start; their median. Without
    such a frame, the start's distance from its stretch (``dists[0]``).

    Args:
        dists: :func:`side_distances` of side 0, the start first.
        on_wall: Whether each line saw the wall, the start first.
        inward: The walk inward before each, the start first (m).
    """
    walked = np.cumsum([0.0, *inward[1:]])
    back = [
        dists[j] - walked[j]
        for j in range(1, min(len(dists), START_FROM_WALL_FRAMES + 1))
        if on_wall[j]
    ]
    return float(np.median(back)) if back else float(dists[0])


def start_views_agree(views: Any, distance: float, offset: float, side_normal: float) -> bool:
    """Whether the survey start's views repeat its side line's distance: at least
    :data:`START_VIEWS` trusted side lines (:func:`_line`) within :data:`START_VIEWS_M` of it.

    Args:
        views: The survey meta's ``start_views`` (line dicts as the survey wrote them).
        distance: The start's side line distance, as seen (m, before the skirting).
        offset: ``survey.wall_offset_m``, m.
        side_normal: Where the side wall is, rad (FRAME_ROBOT).
    """
    if not isinstance(views, list):
        return False
    lines = [_line(view, offset, side_normal) for view in views]
    near = [ln for ln in lines if ln is not None and abs(ln[0] - distance) <= START_VIEWS_M]
    return len(near) >= START_VIEWS


def _own_heading(
    meta: dict[str, Any], offset: float, side_normal: float
) -> tuple[float | None, bool]:
    """The survey start's heading to side 0's direction (rad) from the lines the start
    itself saw: the median of its side wall's (``start_side`` and every view's,
    ``start_views``: one view's line can mix in a corner's other wall), else of the
    farther walls' (:func:`_far_headings`: the walls ahead and across are square and
    parallel to side 0, their lines err more). None without any; and whether it comes
    from clean views of the side wall."""
    votes = []
    views = meta.get("start_views")
    entries = views if isinstance(views, list) and views else [meta.get("start_side")]
    clean = [e for e in entries if isinstance(e, dict) and _clean(e)]
    for entry in clean or entries:
        line = _line(entry, offset, side_normal)
        if line is not None:
            votes.append(line[1])
    from_clean = bool(votes) and bool(clean)
    if not votes:  # the far walls' lines err more: only without the side wall's
        votes = _far_headings(meta, side_normal)
    return (float(np.median(votes)) if votes else None), from_clean


def _clean(entry: dict[str, Any]) -> bool:
    """Whether a line's fit is clean: most of its boundary on it, little scatter about it
    (a line mixing in a corner's other wall or furniture is neither)."""
    rms, fraction = entry.get("rms_m"), entry.get("fraction")
    return (
        isinstance(rms, (int, float))
        and isinstance(fraction, (int, float))
        and rms <= CLEAN_RMS_M
        and fraction >= CLEAN_FRACTION
    )


def _far_headings(meta: dict[str, Any], side_normal: float) -> list[float]:
    """The survey start's heading to side 0's direction (rad) from each farther wall it
    saw, within :data:`FRONT_HEADING_M`: the wall ahead (``start_front``, square to side
    0) and the wall across (``start_across``, parallel to it)."""
    found: list[float] = []
    for key, expected in (("start_front", 0.0), ("start_across", -side_normal)):
        entry = meta.get(key)
        if not isinstance(entry, dict):
            continue
        distance, normal = entry.get("distance_m"), entry.get("normal_rad")
        if not isinstance(distance, (int, float)) or not isinstance(normal, (int, float)):
            continue
        if not (math.isfinite(distance) and math.isfinite(normal)):
            continue
        delta = modulo2PI(expected - float(normal))
        if distance <= FRONT_HEADING_M and abs(delta) <= SIDE_ANGLE_ERROR_RAD:
            found.append(delta)
    return found


def _start_heading(
    own: float | None,
    keyframes: Sequence[Keyframe],
    lines: Sequence[tuple[float, float] | None],
    side0: Sequence[int],
    along: np.ndarray,
    clean: bool = False,
) -> tuple[float | None, float | None]:
    """The survey start's heading to side 0's wall (rad), or None without any line, and
    what side 0's first frames say of it (None: nothing).

    ``own`` is what the start itself saw: its side line's angle, or (a side wall too near
    to be seen) a farther wall's (:func:`_far_headings`). That, unless side 0's frames'
    lines within :data:`START_HEADING_M` of walk, each less the odometry's turn from the
    start to its frame (the map frame is the start's odometry frame), have a median more
    than :data:`START_GATE_RAD` away from it: then that median. A ``clean`` own line (the
    side wall's, seen whole and straight from the start: :func:`_clean`) is kept: the
    frames' lines are less the odometry's turn, and a NAO's odometry can turn 0.1 rad in
    the first metre.
    """
    votes = []
    for i in side0:
        if along[i] > START_HEADING_M:
            break
        if (line := lines[i]) is not None:
            votes.append(modulo2PI(line[1] - keyframes[i].pose.theta))
    frames = float(np.median(votes)) if votes else None
    if own is None or frames is None:
        return (frames if own is None else own), frames
    if clean:
        return own, frames
    return (own if abs(modulo2PI(frames - own)) <= START_GATE_RAD else frames), frames
