"""Floor-wall lines as a pose fix: the walls the map records, the lines the robot measures.

The survey walks a known rectangle a wall offset inside the room's walls, and its wall
poses (:mod:`naoloc.mapping.wall_poses`) place every keyframe in a wall frame W whose x axis runs
along the first wall; the map's meta keeps W's place in the map frame and the walls in W
(``meta.wall_poses.wall_frame``, ``walls_m``; :func:`map_walls`).

A floor-wall line measured at the robot (:class:`naoloc.perception.floorline.WallLine`, FRAME_ROBOT:
measured to 1-4 cm at 0.5-2 m) says how far a wall is and at which angle. The lines of one
room agree on the robot's heading modulo a quarter turn, and each gives one coordinate once
assigned to the wall it faces; furniture in front of a wall gives a coordinate too near
that wall. :func:`candidates` lists every pose the lines allow (and :func:`landmark_candidates`, on
an axis whose walls no line saw, the places the landmarks' bearings give); the pictures' landmark
matches choose among them (:func:`naoloc.behaviours.localize.localize`).

Frames: the map frame in and out (x forward at the survey start, y left, metres, radians);
W inside.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from naoloc.geometry import Pose2D, modulo2PI

if TYPE_CHECKING:
    from naoloc.mapping.mapfile import MapData
    from naoloc.perception.floorline import WallLine

# Lines agree on the heading within this, rad; their coordinates cluster within this, m.
HEADING_AGREE_RAD = 0.1
COORD_AGREE_M = 0.12
# Lines shorter than this along the floor are ignored, m.
MIN_SPAN_M = 0.25
# A candidate may put a seen line at most this far behind its wall (the lines' error at
# 2-3 m; furniture stands 0.3-0.6 m deep), m.
BEHIND_WALL_M = 0.2
# The robot's centre stays this far inside the walls, m.
WALL_CLEARANCE_M = 0.1
# At most this many candidates from the landmarks' bearings (:data:`AxisSolver`), the
# best agreed first, and only where no line's coordinate is this near on their axis (m):
# the landmarks' place is where the map's landmarks fit, 0.1-0.2 m from the wall frame's
# where the map's poses err, so near a wall's line it would out-vote the truth.
SWEEP_KEEP = 8
SWEEP_APART_M = 0.3
# A line this near the robot (m) is its wall's, so it fixes a coordinate from one side.
NEAR_LINE_M = 0.6
# A cluster of lines stays a candidate beyond a line that puts it behind a wall when it has
# this many times as many lines as those it puts behind one (:func:`_feasible`).
OUTVOTE = 3
# Lines measured before a turn in place are carried to the robot now only when the lines
# now set the turn's error modulo a quarter turn to at most this (rad): a NAO's turns err
# about 6 % of the angle, 16 deg after three quarter turns (:func:`carry_lines`).
CARRY_MAX_RAD = 0.35

#: Where along one axis of W the landmarks put the robot: ``(theta, axis, fixed, span)`` ->
#: ``[(coordinate, agreeing features), ...]`` for heading ``theta`` (W, rad), solving axis
#: ``axis`` (0 = x, 1 = y) with the other coordinate at ``fixed`` (m) inside ``span``
#: (``(low, high)``, m); e.g. :func:`naoloc.mapping.support.axis_peaks`.
AxisSolver = Callable[[float, int, float, tuple[float, float]], list[tuple[float, int]]]


@dataclass(frozen=True)
class Walls:
    """Where the room's walls stand.

    Attributes:
        frame: The wall frame W (x along the survey's first wall) in the map frame.
        bounds: The walls in W, ``(x_min, x_max, y_min, y_max)``, m.
    """

    frame: Pose2D
    bounds: tuple[float, float, float, float]

    @property
    def coords(self) -> tuple[float, float, float, float]:
        """Per side (+x, +y, -x, -y of W), its coordinate along its outward normal, m."""
        x0, x1, y0, y1 = self.bounds
        return (x1, y1, -x0, -y0)


def map_walls(vmap: MapData) -> Walls | None:
    """The room's walls as the survey's wall poses placed them (``meta.wall_poses``), or None.

    None for a map whose keyframe poses did not come from the walls (odometry poses, a map
    built before the walls were recorded).
    """
    wp = vmap.meta.get("wall_poses")
    if not isinstance(wp, dict):
        return None
    frame, bounds = wp.get("wall_frame"), wp.get("walls_m")
    if not (isinstance(frame, list) and len(frame) == 3 and isinstance(bounds, list)):
        return None
    values = [*frame, *bounds]
    if len(bounds) != 4 or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values
    ):
        return None
    x0, x1, y0, y1 = (float(v) for v in bounds)
    if not (x0 < x1 and y0 < y1):
        return None
    return Walls(Pose2D(*(float(v) for v in frame)), (x0, x1, y0, y1))


def candidates(
    lines: Sequence[WallLine], walls: Walls, heading: float | None = None
) -> list[Pose2D]:
    """Every pose the lines allow: a heading they agree on, then per axis each coordinate.

    Lines of one room agree on the robot's heading modulo a quarter turn; each line then
    gives one coordinate along the axis of the wall it faces (furniture in front of that
    wall gives one too near it). Coordinates within :data:`COORD_AGREE_M` are one, and
    only those that put no seen line behind a wall remain (:func:`_feasible`).

    Args:
        lines: Floor-wall lines measured at the robot, FRAME_ROBOT of the robot now.
        walls: The room's walls (:func:`map_walls`).
        heading: A heading to keep to (map frame, rad): only its quarter turn is tried.
            None tries all four.

    Returns:
        Robot poses in the map frame (none when fewer than two lines agree on the heading
        or an axis has no line).
    """
    return [
        walls.frame * Pose2D(x, y, modulo2PI(theta))
        for theta, _values, axes in _per_turn(lines, walls, heading)
        for x in axes[0]
        for y in axes[1]
    ]


def landmark_candidates(
    lines: Sequence[WallLine],
    walls: Walls,
    solve: AxisSolver,
    heading: float | None = None,
) -> list[Pose2D]:
    """The poses an axis no wall line gave takes from the landmarks' bearings.

    An axis whose walls no line saw (4 m away, or hidden behind furniture) has only
    furniture's coordinates or none, so :func:`candidates` has none near the truth there.
    Per heading the lines agree on, and per coordinate both walls' lines give on the other
    axis (:func:`_two_sided`), ``solve`` gives the places along that axis where the
    landmarks' bearings agree (within the lines' bounds and the walls, :func:`_span`), and
    those no line's coordinate is within :data:`SWEEP_APART_M` of are kept, the
    :data:`SWEEP_KEEP` best agreed over all.

    Args:
        lines: Floor-wall lines measured at the robot, FRAME_ROBOT of the robot now.
        walls: The room's walls (:func:`map_walls`).
        solve: The landmarks' places along an axis (:data:`AxisSolver`).
        heading: As for :func:`candidates`.

    Returns:
        Robot poses in the map frame, the best agreed first.
    """
    swept: list[tuple[int, Pose2D]] = []
    for theta, values, axes in _per_turn(lines, walls, heading):
        for axis in (0, 1):
            span = _span(values[axis], walls, axis)
            other = 1 - axis
            fixed_at = _two_sided(values[other], axes[other])
            fixed_at += [
                c for c in _near_sided(values[other], axes[other], walls, other)
                if all(abs(c - f) >= COORD_AGREE_M for f in fixed_at)
            ]  # fmt: skip
            for fixed in fixed_at:
                for coord, n in solve(theta, axis, fixed, span):
                    if any(abs(coord - v) < SWEEP_APART_M for v in axes[axis]):
                        continue  # a line gives it, or one near it
                    xy = (coord, fixed) if axis == 0 else (fixed, coord)
                    swept.append((n, walls.frame * Pose2D(*xy, modulo2PI(theta))))
    swept.sort(key=lambda t: -t[0])
    return [p for _n, p in swept[:SWEEP_KEEP]]


def carry_lines(
    earlier: Sequence[WallLine], moved: Pose2D, now: Sequence[WallLine]
) -> list[WallLine]:
    """Lines measured at an earlier pose, as the robot now would see them.

    A line ``{p : p . n = d}`` in the earlier FRAME_ROBOT is, for a robot that moved by
    ``moved`` (its pose now in the earlier frame), at normal ``n - theta`` and distance
    ``d - t . n``. The odometry's turn errs (6 % of the angle on a NAO), so the turn is
    corrected by the lines measured now: both sets agree on the robot's heading modulo a
    quarter turn (:func:`_line_heading`), and the earlier set is turned by the difference.
    Carried lines give a wall the robot saw before turning but cannot see now (behind it,
    or behind furniture from here).

    Args:
        earlier: Lines measured at the earlier pose, its FRAME_ROBOT.
        moved: The robot's pose now in the earlier FRAME_ROBOT (odometry), m and rad.
        now: Lines measured now, FRAME_ROBOT now.

    Returns:
        The earlier lines in FRAME_ROBOT now; none when either set agrees on no heading or
        the correction exceeds :data:`CARRY_MAX_RAD`.
    """
    turned = [
        dataclasses.replace(
            ln,
            normal=modulo2PI(ln.normal - moved.theta),
            distance=ln.distance - moved.x * math.cos(ln.normal) - moved.y * math.sin(ln.normal),
        )
        for ln in earlier
    ]
    here, before = _line_heading(now), _line_heading(turned)
    if here is None or before is None:
        return []
    error = math.remainder(here[1] - before[1], math.pi / 2)
    if abs(error) > CARRY_MAX_RAD:
        return []
    return [
        dataclasses.replace(ln, normal=modulo2PI(ln.normal - error))
        for ln in turned
        if ln.distance > 0.0
    ]


def _per_turn(
    lines: Sequence[WallLine], walls: Walls, heading: float | None
) -> list[tuple[float, list[list[tuple[float, bool]]], list[list[float]]]]:
    """Per heading in W the lines allow (all four quarter turns, or ``heading``'s): the
    heading, each axis's line coordinates (:func:`_axis_values`) and its feasible ones
    (:func:`_feasible`). Empty when fewer than two lines agree on a heading."""
    found = _line_heading(lines)
    if found is None:
        return []
    agreeing, base = found
    quarter = math.pi / 2
    if heading is None:
        turns = [base + k * quarter for k in range(4)]
    else:
        h = (walls.frame.inverse() * Pose2D(0.0, 0.0, heading)).theta
        turns = [base + round((h - base) / quarter) * quarter]
    out = []
    for theta in turns:
        values = _axis_values(agreeing, walls, theta)
        out.append((theta, values, [_feasible(v) for v in values]))
    return out


def check_pose(
    lines: Sequence[WallLine], walls: Walls, pose: Pose2D, metres: float, radians: float
) -> tuple[Pose2D, int] | None:
    """``pose`` sharpened by the lines where they pin it, or None when they contradict it.

    The lines contradict a pose when their heading is more than ``radians`` from its
    heading (taken in the pose's own quarter turn), or when the pose puts a
    seen line more than :data:`BEHIND_WALL_M` behind its wall and no coordinate that
    outvotes such lines (:func:`_feasible`) is within ``metres`` of it. Otherwise the pose takes
    the lines' heading and, per axis, the nearest coordinate a line gives within
    ``metres`` (:func:`_feasible`); an axis where no wall was seen (only furniture, or
    nothing) keeps the pose's coordinate. A pose the lines do not pin is not contradicted:
    a bookcase hiding its wall bounds the coordinate without giving it.

    Args:
        lines: Floor-wall lines measured at the robot, FRAME_ROBOT.
        walls: The room's walls (:func:`map_walls`).
        pose: A pose in the map frame (e.g. from PnP).
        metres: Largest move of one coordinate, m.
        radians: Largest heading change, rad.

    Returns:
        The sharpened pose in the map frame and how many of its two coordinates a line
        gave, or None. None too when fewer than two lines agree on a heading (nothing to
        check with).
    """
    found = _line_heading(lines)
    if found is None:
        return None
    agreeing, base = found
    quarter = math.pi / 2
    pose_w = walls.frame.inverse() * pose
    theta = base + round((pose_w.theta - base) / quarter) * quarter
    if abs(modulo2PI(theta - pose_w.theta)) > radians:
        return None
    coords = [pose_w.x, pose_w.y]
    pinned = 0
    for axis, values in enumerate(_axis_values(agreeing, walls, theta)):
        c = coords[axis]
        lo, hi = _bounds(values)
        near = [v for v in _feasible(values) if abs(v - c) <= metres]
        if lo <= hi and not lo <= c <= hi and not near:  # (contradicting lines bound nothing)
            return None
        if near:
            coords[axis] = min(near, key=lambda v: abs(v - c))
            pinned += 1
    return walls.frame * Pose2D(coords[0], coords[1], modulo2PI(theta)), pinned


def _line_heading(lines: Sequence[WallLine]) -> tuple[list[WallLine], float] | None:
    """The usable lines that agree on a heading in W (modulo a quarter turn), and it (rad).

    None when fewer than two usable lines (:data:`MIN_SPAN_M`) agree.
    """
    usable = [ln for ln in lines if ln.span_m >= MIN_SPAN_M and math.isfinite(ln.distance)]
    if len(usable) < 2:
        return None
    quarter = math.pi / 2
    # Headings in W modulo a quarter turn, as offsets from a quarter of each line's normal.
    d = np.asarray([math.remainder(-ln.normal, quarter) for ln in usable])
    w = np.asarray([ln.span_m for ln in usable])
    gap = np.abs(np.remainder(d[:, None] - d[None, :] + quarter / 2, quarter) - quarter / 2)
    support = (w[None, :] * (gap < HEADING_AGREE_RAD)).sum(axis=1)
    centre = int(np.argmax(support))
    agree = gap[centre] < HEADING_AGREE_RAD
    if agree.sum() < 2:
        return None
    off = d[agree] - d[centre]
    off = np.remainder(off + quarter / 2, quarter) - quarter / 2
    base = float(d[centre] + np.average(off, weights=w[agree]))
    return [ln for ln, ok in zip(usable, agree, strict=True) if ok], base


def _axis_values(
    lines: Sequence[WallLine], walls: Walls, theta: float
) -> list[list[tuple[float, bool]]]:
    """Per axis of W (x, y), the robot coordinate each line gives at heading ``theta`` (W),
    and whether its wall is the one on the axis's + side."""
    quarter = math.pi / 2
    per_axis: list[list[tuple[float, bool]]] = [[], []]
    for ln in lines:
        k = round((theta + ln.normal) / quarter) % 4
        along = walls.coords[k] - ln.distance  # robot's coordinate along the outward normal
        per_axis[k % 2].append((along if k < 2 else -along, k < 2))
    return per_axis


def _feasible(values: Sequence[tuple[float, bool]]) -> list[float]:
    """The coordinates along one axis that no line contradicts.

    A line is where the floor ends: at the wall, or at furniture in front of it. So the wall
    is never nearer than a line seen in its direction: a + side line at coordinate ``v``
    puts the robot at ``v`` (the wall's line) or below it (furniture's), a - side line at
    ``v`` or above. Of the clusters (:func:`_groups`) only those between the highest
    - side line and the lowest + side line (within :data:`BEHIND_WALL_M`) remain: the
    robot is where one of those two lines is the wall's. A cluster beyond them would put a
    seen line behind a wall, unless its own lines outnumber the lines it puts behind a wall
    :data:`OUTVOTE` times: a lone line read past its wall (the paper room: one line 0.3 m
    beyond the wall five lines agree on) does not veto the wall.

    Args:
        values: ``(coordinate, on the + side)`` per line, m in W.

    Returns:
        Cluster means, ascending (empty when there is no line). When the lines contradict
        each other (a - side line above a + side line: one of them is not where the floor
        ends, e.g. a misread edge), every cluster, as if no line bounded the axis.
    """
    if not values:
        return []
    lo, hi = _bounds(values)
    groups = _groups([v for v, _ in values])
    if lo > hi:
        return [float(np.mean(g)) for g in groups]
    out = []
    for g in groups:
        c = float(np.mean(g))
        behind = sum(
            1 for v, plus in values if (v < c - BEHIND_WALL_M if plus else v > c + BEHIND_WALL_M)
        )
        if lo <= c <= hi or len(g) >= OUTVOTE * behind:
            out.append(c)
    return out


def _bounds(values: Sequence[tuple[float, bool]]) -> tuple[float, float]:
    """The robot's coordinate range along one axis that keeps every line in front of its
    wall (within :data:`BEHIND_WALL_M`); ``lo > hi`` when the lines contradict each other."""
    lo = max((v for v, plus in values if not plus), default=-math.inf) - BEHIND_WALL_M
    hi = min((v for v, plus in values if plus), default=math.inf) + BEHIND_WALL_M
    return lo, hi


def _two_sided(values: Sequence[tuple[float, bool]], clusters: Sequence[float]) -> list[float]:
    """The clusters both walls of the axis agree on: a line of each side within
    :data:`COORD_AGREE_M`. In a wrong quarter turn the two walls' lines agree only where the
    room's width and length do (and rarely furniture's), so a place along the other axis
    is searched only from such a coordinate (three fresh rooms: the landmarks' places from
    one-sided coordinates gave poses a quarter or half turn off, with support 70-183)."""
    return [
        c
        for c in clusters
        if any(abs(v - c) < COORD_AGREE_M for v, plus in values if plus)
        and any(abs(v - c) < COORD_AGREE_M for v, plus in values if not plus)
    ]


def _near_sided(
    values: Sequence[tuple[float, bool]], clusters: Sequence[float], walls: Walls, axis: int
) -> list[float]:
    """The clusters a line within :data:`NEAR_LINE_M` of the robot gives: so near, the
    floor ends at the wall itself (furniture stands farther out), so one side suffices."""
    low, high = walls.bounds[2 * axis], walls.bounds[2 * axis + 1]
    near = [v for v, plus in values if (high - v if plus else v - low) <= NEAR_LINE_M]
    return [c for c in clusters if any(abs(v - c) < COORD_AGREE_M for v in near)]


def _span(values: Sequence[tuple[float, bool]], walls: Walls, axis: int) -> tuple[float, float]:
    """Where on one axis of W the robot may be: inside the walls, and inside the lines'
    bounds (:func:`_bounds`) unless they contradict each other, m."""
    low = walls.bounds[2 * axis] + WALL_CLEARANCE_M
    high = walls.bounds[2 * axis + 1] - WALL_CLEARANCE_M
    lo, hi = _bounds(values)
    if lo <= hi:
        low, high = max(low, lo), min(high, hi)
    return low, high


def _groups(values: Sequence[float]) -> list[list[float]]:
    """Runs of sorted ``values`` closer than :data:`COORD_AGREE_M`, ascending."""
    v = sorted(values)
    groups: list[list[float]] = [[v[0]]]
    for a in v[1:]:
        if a - groups[-1][-1] < COORD_AGREE_M:
            groups[-1].append(a)
        else:
            groups.append([a])
    return groups
