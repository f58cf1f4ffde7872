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
in radians. The thresholds, each with its reasons, are ``map.tuning.wall_poses``
(:class:`naoloc.config.WallPoseTuning`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.config import WallPoseTuning
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.perception.wall_gate import (
    SIDE_ANGLE_ERROR_RAD,
    in_far_front_range,
    in_front_range,
    side_line_angle,
)
from naoloc.robot.keyframe import Keyframe


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
        heading_std: The map frame's heading error, one sigma (rad), as the start's heading
            was found (:func:`_start_heading`); None without a heading. The whole map turns
            with it about the origin: a pose r m from it is off by r times it, across.
        faces: The fronts of furniture standing along the walls that the side lines saw
            (:func:`furniture_faces`): ``(wall, depth, xa, ya, xb, yb)``, the wall's index
            (0: x_max, 1: y_max, 2: x_min, 3: y_min), how far before that wall's floor line
            the front stands (m) and the two ends of the stretch seen, in W (m).
        hidden: The sides that followed a front hiding their wall all along
            (:func:`_hidden_front`): (side, the front's depth before the wall, m).
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
    heading_std: float | None = None
    faces: list[tuple[int, float, float, float, float, float]] = dataclasses.field(
        default_factory=list
    )
    hidden: list[tuple[int, float]] = dataclasses.field(default_factory=list)

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
            "hidden": [[k, round(d, 4)] for k, d in self.hidden],
            **({} if self.heading_std is None else {"heading_std_rad": round(self.heading_std, 5)}),
            **(
                {}
                if self.wall_frame is None or self.walls is None
                else {
                    "wall_frame": [
                        round(v, 5)
                        for v in (self.wall_frame.x, self.wall_frame.y, self.wall_frame.theta)
                    ],
                    "walls_m": [round(v, 4) for v in self.walls],
                    "faces": [[f[0], *(round(v, 4) for v in f[1:])] for f in self.faces],
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
    tuning: WallPoseTuning | None = None,
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
        tuning: ``map.tuning.wall_poses`` (None: the defaults).

    Returns:
        The poses, or None when the meta lacks what this needs (no vision, a survey that
        did not follow walls) or when fewer than half of the corners were placed (by the
        next side's wall or a front line): the odometry poses are then kept.
    """
    tun = WallPoseTuning() if tuning is None else tuning
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
    track = _SideTrack(tun)
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
        found = side_distances(m, dy, tuning=tun)
        if found is None:
            continue
        dists, on_wall = found
        if k == 0:
            back = _start_from_wall(dists, on_wall, dy, tuning=tun)
            agrees = on_wall[0] and (
                abs(dists[0] - back) <= tun.start_agree_m
                or start_views_agree(
                    meta.get("start_views"), dists[0] - skirting, offset, side_normal, tuning=tun
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
    hidden: list[tuple[int, float]] = []  # (side whose wall furniture hid, its depth)
    hidden_at: dict[int, float] = {}  # the same per wall (side mod 4), as first found
    for k in range(n_sides - 1):
        if not frames_of[k]:
            continue  # a side the survey found itself at the end of: no step, no picture
        last = frames_of[k][-1]
        starts[k + 1] = _end_lateral(frames_of[k], laterals, wall_seen, inward_m, tun.end_frames)
        nxt = dist[last + 1] if side_of[last + 1] == k + 1 else None
        if nxt is None:
            continue
        ahead = deltas[last] - turn * math.pi / 2  # heading off side k+1's direction
        corner = keyframes[last].pose.inverse() * keyframes[last + 1].pose  # the turn's step
        behind = -_inward(corner, ahead, turn)
        to_go = nxt + behind  # from the last frame to side k+1's wall, m
        # (not side 0's wall: the start stands beside it and places the map frame by it)
        depth = None if (k + 1) % 4 == 0 else _hidden_front(
            frames_of[k], frames_of[k + 1], along, vision, lines, wall_seen, to_go,
            lengths[k] + offset - starts.get(k, 0.0), tun, known=hidden_at.get((k + 1) % 4),
        )  # fmt: skip
        if depth is not None:
            hidden_at.setdefault((k + 1) % 4, depth)
            # Side k+1 followed a front standing `depth` before its wall all along: its
            # frames stood that much farther from the wall, and side k ended that early.
            hidden.append((k + 1, depth))
            for i in frames_of[k + 1]:
                if (di := dist[i]) is not None:
                    dist[i], wall_seen[i] = di + depth, False
                    laterals[i] = di + depth - offset
            to_go += depth
        ends[k] = (float(along[last]), lengths[k] - (to_go - offset))
    true_along, scales = _along_sides(
        along, frames_of, vision, lengths, offset, ends, starts, tuning=tun
    )
    if sum(1 for x in scales if x is not None) < tun.min_corner_fraction * n_sides:
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
    own, clean, spread = _own_heading(meta, offset, side_normal, tuning=tun)
    heading, frames_heading, heading_std = _start_heading(
        own, keyframes, lines, frames_of[0], along, tun, clean, spread
    )
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
    faces = furniture_faces(poses, side_of, lines, dist, wall_seen, turn, walls, tun)
    return WallPoses(
        out,
        scales,
        used,
        _turn_scale(keyframes, side_of, lines, turn, tun.turn_scale_range),
        start.inverse(),
        walls,
        sides_of=list(side_of),
        lines_seen=[line is not None for line in lines],
        wall_seen=wall_seen,
        residuals=residuals,
        skirting=skirting,
        start_own=own,
        start_frames=frames_heading,
        heading_std=heading_std,
        faces=faces,
        hidden=hidden,
    )


@dataclasses.dataclass
class _Run:
    """Consecutive frames whose side lines saw one front before a wall."""

    wall: int
    frame: int
    depths: list[float]
    feet: list[tuple[float, float]]


def furniture_faces(
    poses: Sequence[Pose2D],
    side_of: Sequence[int],
    lines: Sequence[tuple[float, float] | None],
    dist: Sequence[float | None],
    wall_seen: Sequence[bool],
    turn: float,
    walls: tuple[float, float, float, float],
    tuning: WallPoseTuning,
) -> list[tuple[int, float, float, float, float, float]]:
    """The fronts of furniture along the walls, as the survey's side lines saw them (W).

    A side line that saw something standing before its wall (:func:`side_distances`) puts
    that thing's front ``depth`` = the frame's distance from the wall less the line's
    before the wall's floor line. Consecutive frames of a side whose depths agree within
    ``map.tuning.wall_poses.level_m``, at least ``face_frames`` of them and at least
    ``face_min_m`` deep, are one front: from the first frame's foot on it to the last's,
    widened by ``face_margin_m``. Fronts of the same wall (both laps) that overlap and agree
    merge. The floor-line sensor model (:mod:`naoloc.localization.walls`) then explains a
    line on such a front as the front, not as the wall seen from a wrong pose.

    Args:
        poses: The keyframes' poses in W.
        side_of: Each frame's side.
        lines: Each frame's side line (distance, angle) as measured (skirting included).
        dist: Each frame's distance from its side's wall (m), None when unknown.
        wall_seen: Whether each frame's line saw its wall.
        turn: +1 when the corners turn left (the wall on the right), -1 otherwise.
        walls: The walls in W, ``(x_min, x_max, y_min, y_max)``.
        tuning: ``map.tuning.wall_poses``.

    Returns:
        ``(wall, depth, xa, ya, xb, yb)`` per front (see :class:`WallPoses`).
    """
    runs: list[_Run] = []
    for i, (pose, k) in enumerate(zip(poses, side_of, strict=True)):
        line, d = lines[i], dist[i]
        if line is None or d is None or wall_seen[i] or d - line[0] < tuning.face_min_m:
            continue
        out = k * turn * math.pi / 2 - turn * math.pi / 2  # the wall's outward normal
        wall = round(out / (math.pi / 2)) % 4  # 0: +x, 1: +y, 2: -x, 3: -y
        foot = (pose.x + line[0] * math.cos(out), pose.y + line[0] * math.sin(out))
        depth = d - line[0]
        last = runs[-1] if runs else None
        if (
            last is not None
            and last.wall == wall
            and last.frame == i - 1
            and abs(float(np.median(last.depths)) - depth) <= tuning.level_m
        ):
            last.depths.append(depth)
            last.feet.append(foot)
            last.frame = i
        else:
            runs.append(_Run(wall, i, [depth], [foot]))
    faces: list[list[Any]] = []
    for run in runs:
        if len(run.depths) < tuning.face_frames:
            continue
        wall = run.wall
        axis = 1 if wall in (0, 2) else 0  # the coordinate along the wall
        along = [f[axis] for f in run.feet]
        lo, hi = min(along) - tuning.face_margin_m, max(along) + tuning.face_margin_m
        depth = float(np.median(run.depths))
        for face in faces:  # the same front seen on another lap
            if (
                face[0] == wall
                and face[2] <= hi
                and lo <= face[3]
                and abs(face[1] - depth) <= tuning.level_m
            ):
                face[1] = (face[1] + depth) / 2
                face[2], face[3] = min(face[2], lo), max(face[3], hi)
                break
        else:
            faces.append([wall, depth, lo, hi])
    x0, x1, y0, y1 = walls
    out_faces = []
    for wall, depth, lo, hi in faces:
        if wall in (0, 2):
            x = x1 if wall == 0 else x0
            out_faces.append((wall, depth, x, lo, x, hi))
        else:
            y = y1 if wall == 1 else y0
            out_faces.append((wall, depth, lo, y, hi, y))
    return out_faces


def _hidden_front(
    idx: Sequence[int],
    nxt: Sequence[int],
    along: np.ndarray,
    vision: Sequence[dict[str, Any]],
    lines: Sequence[tuple[float, float] | None],
    wall_seen: Sequence[bool],
    to_go: float,
    wall_ahead: float,
    tuning: WallPoseTuning,
    *,
    known: float | None = None,
) -> float | None:
    """How far before its wall a front stood that the next side followed all along (m), or
    None.

    The next side's lines saw one level only, so :func:`side_distances` took it for the
    wall. It was not when side ``idx``'s first lines ahead (the far pictures' and the
    front lines within ``hidden_early_m`` of its start, where the odometry is good to a
    few centimetres) all put what it walked towards ``hidden_min_m`` or more nearer than
    the room's wall (``wall_ahead``: the wall's distance from the side's start, m), and the
    line ahead at its end read nearer the distance the next side's line then did than that
    plus the depth (the robot turned before what it then followed, not before a chest in
    the corner with the wall beside it). A wardrobe or a bed along a whole wall does this; the
    room's size would otherwise stretch the circuit's sides by its depth.

    Args:
        idx: Side k's frame indices; ``nxt``: side k+1's.
        along: Each frame's odometry distance from its side's start (m).
        vision: The survey's per-frame lines.
        lines: Each frame's side line (distance, angle) or None.
        wall_seen: Whether each frame's side line saw its wall.
        to_go: From side k's last frame to what side k+1 followed (m).
        wall_ahead: Side k's wall ahead from its start, by the room's size (m).
        tuning: ``map.tuning.wall_poses``.
        known: The depth a lap before found before the same wall: taken again unless this
            side's own lines ahead (at least one) read otherwise.
    """
    seen = [i for i in nxt if lines[i] is not None]
    if len(seen) < tuning.min_wall_frames or not all(wall_seen[i] for i in seen):
        return None  # the next side saw its wall behind something, or too little
    fronts, fars = _front_readings(idx, vision)
    early = [float(along[i]) + d for i, d in fronts + fars if along[i] <= tuning.hidden_early_m]
    if known is not None:
        if any(abs(wall_ahead - e - known) > tuning.front_agree_m for e in early):
            return None  # this lap's lines ahead read another depth
        depth = known
    else:
        if len(early) < tuning.level_lines:
            return None
        reach = float(np.median(early))
        if any(abs(e - reach) > tuning.front_agree_m for e in early):
            return None  # the lines ahead disagree: one of them saw something else
        depth = wall_ahead - reach
        if not tuning.hidden_min_m <= depth <= tuning.hidden_max_m:
            return None
    if not fronts:
        return None
    i, d = max(fronts, key=lambda f: along[f[0]])
    if abs(d - (along[idx[-1]] - along[i]) - to_go) > depth / 2:
        return None  # it turned before something the next side did not follow
    return depth


def _end_lateral(
    idx: Sequence[int],
    laterals: Sequence[float],
    wall_seen: Sequence[bool],
    inward_m: Sequence[float],
    end_frames: int,
) -> float:
    """Where a side's last frame stood inward of its circuit (m): the median of its last
    ``end_frames`` (``map.tuning.wall_poses.end_frames``) frames whose lines saw the wall,
    each carried to the last frame by the odometry's walk inward (a corner's plant or
    sideboard is often all the last frame's line sees); the last frame's own lateral
    without such frames."""
    last = idx[-1]
    votes = [
        laterals[i] + (inward_m[last] - inward_m[i]) for i in idx[-end_frames:] if wall_seen[i]
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
    plausible: tuple[float, float],
) -> float | None:
    """Odometry turn per true turn at the corners (None outside ``plausible``:
    ``map.tuning.wall_poses.turn_scale_range``).

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
    if true == 0.0 or not plausible[0] <= odo / true <= plausible[1]:
        return None
    return odo / true


class _SideTrack:
    """Heading to the side wall and distance inward of the circuit, along one side.

    The odometry's relative motion between frames predicts both; a side line that
    disagrees with the prediction by more than its gate (a chair's foot, a rug's edge) is
    not used, unless the prediction has grown too uncertain to judge. The lines' sigmas and
    the least angle gate are ``map.tuning.wall_poses``' ``line_std_m``, ``line_std_rad`` and
    ``min_angle_gate_rad``.
    """

    def __init__(self, tuning: WallPoseTuning) -> None:
        self.line_std_m = tuning.line_std_m
        self.line_std_rad = tuning.line_std_rad
        self.min_angle_gate_rad = tuning.min_angle_gate_rad
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
        gate = 3 * math.sqrt(self.var_delta + self.line_std_rad**2)
        if abs(modulo2PI(delta - self.delta)) <= max(gate, self.min_angle_gate_rad):
            g = self.var_delta / (self.var_delta + self.line_std_rad**2)
            self.delta = modulo2PI(self.delta + g * modulo2PI(delta - self.delta))
            self.var_delta *= 1 - g
        if abs(lateral - self.lateral) > 3 * math.sqrt(self.var_lateral + self.line_std_m**2):
            return False
        g = self.var_lateral / (self.var_lateral + self.line_std_m**2)
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
    *,
    tuning: WallPoseTuning,
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
    stood. A side no next wall ended (the survey's last) whose side a lap before was ended
    takes the front lines that agree with the walk to where that side ended, or that end
    when none does. ``tuning``: ``map.tuning.wall_poses`` (``scale_range``,
    ``front_agree_m``).

    Returns:
        The distances and each side's overall metres per odometry metre (None: no anchor).
    """
    low, high = tuning.scale_range
    out = np.full_like(along, np.nan)
    scales: list[float | None] = []
    ends = dict(ends or {})
    for k, (idx, length) in enumerate(zip(frames_of, lengths, strict=True)):
        anchors = [(0.0, (starts or {}).get(k, 0.0))]
        before = frames_of[k - 4] if k >= 4 else []
        lap_end = None
        if k not in ends and idx and before and ends.get(k - 4, (0.0, 0.0))[0] > 0:
            # No next wall ended this side (the survey's last): it ended about where the
            # same side a lap before did, which the next wall placed. Both stopped where the
            # same front wall read the same distance, furniture before it and all.
            lap_end = (float(along[idx[-1]]), float(out[before[-1]]))
        fronts, fars = _front_lines(idx, along, vision, length, offset)
        start, agree_m = anchors[0], tuning.front_agree_m
        if k in ends and ends[k][0] > 0:
            # The next wall placed the side's end; front lines that agree with the walk
            # between the corners place the frames near the end too (a front line that
            # sees furniture before the wall does not agree).
            end = ends[k]
            anchors.append(end)
            anchors += _on_walk([f for f in fronts + fars if f[0] < end[0]], start, end, agree_m)
        elif lap_end is not None:
            # The front lines that agree with the walk to where the lap before ended place
            # the frames; that end itself only when none does (the two laps' ends differ
            # by a few centimetres, a front line on the wall reads within 2).
            # A line may see, as the lap before's did, something standing before that
            # wall: it places its frame as far before that thing as it reads.
            lines = [f for f in fronts + fars if f[0] <= lap_end[0]]
            shifts = _front_levels(before, vision, lengths[k - 4], offset, out, tuning)
            anchors += _on_walk(lines, start, lap_end, agree_m, shifts) or [lap_end]
        else:
            # The survey's own front lines (near, read within a few cm) give the walk; a far
            # picture's line places its frame where it agrees with that walk, carried back
            # from the first of them to the side's start.
            near = agreeing_fronts(start, fronts, tuning=tuning)
            anchors += near
            if near:
                first = min(near)
                lines = [f for f in fars if start[0] < f[0] < first[0]]
                anchors += _on_walk(lines, start, first, agree_m)
            else:
                anchors += agreeing_fronts(start, fars, tuning=tuning)
        anchors.sort()
        kept = [anchors[0]]
        for o, t in anchors[1:]:
            if o > kept[-1][0] + 1e-6 and t > kept[-1][1]:
                s = (t - kept[-1][1]) / (o - kept[-1][0])
                if low <= s <= high or len(kept) > 1:
                    kept.append((o, t))
        # metres per odometry metre between the side's first and last anchors (its start
        # may stand off the corner: where the previous side's last frame stood)
        scale = (kept[-1][1] - kept[0][1]) / (kept[-1][0] - kept[0][0]) if len(kept) > 1 else None
        scales.append(scale if scale is None or low <= scale <= high else None)
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


def _distance(line: Any, in_range: Callable[[float], bool]) -> float | None:
    """A recorded floor line's distance (m), when it is a finite one ``in_range`` accepts."""
    distance = line.get("distance_m") if isinstance(line, dict) else None
    if isinstance(distance, (int, float)) and math.isfinite(distance) and in_range(distance):
        return float(distance)
    return None


def _front_readings(
    idx: Sequence[int], vision: Sequence[dict[str, Any]]
) -> tuple[list[tuple[int, float]], list[tuple[int, float]]]:
    """One side's front lines as (the frame where measured, distance m): the survey's own
    (``front``, measured at the frame before its step) and the far pictures' level look
    ahead (``far_front``, at the frame's own stop)."""
    fronts = []
    for j, i in enumerate(idx[1:], start=1):
        distance = _distance(vision[i].get("front"), in_front_range)
        if distance is not None:
            fronts.append((idx[j - 1], distance))
    fars = []
    for i in idx:
        distance = _distance(vision[i].get("far_front"), in_far_front_range)
        if distance is not None:
            fars.append((i, distance))
    return fronts, fars


def _front_lines(
    idx: Sequence[int],
    along: np.ndarray,
    vision: Sequence[dict[str, Any]],
    length: float,
    offset: float,
) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """One side's front lines (:func:`_front_readings`) as (odometry along where measured,
    true along it gives if it saw the wall), m."""
    fronts, fars = _front_readings(idx, vision)
    return (
        [(float(along[i]), length - (d - offset)) for i, d in fronts],
        [(float(along[i]), length - (d - offset)) for i, d in fars],
    )


def _front_levels(
    idx: Sequence[int],
    vision: Sequence[dict[str, Any]],
    length: float,
    offset: float,
    placed: np.ndarray,
    tuning: WallPoseTuning,
) -> list[float]:
    """Where a placed side's front lines saw something standing before its front wall: how
    far before it their frames stood than the wall would say (m, <= 0), for each level at
    least ``map.tuning.wall_poses.level_lines`` lines saw within
    ``map.tuning.wall_poses.level_m`` of each other (a sideboard before the corner reads the
    same from every frame). ``placed``: the frames' true along (NaN: not placed)."""
    fronts, fars = _front_readings(idx, vision)
    shifts = sorted(
        shift
        for i, d in fronts + fars
        if math.isfinite(shift := float(placed[i]) - (length - (d - offset)))
        and shift < -tuning.level_m
    )
    levels: list[float] = []
    for s in shifts:
        near = [u for u in shifts if abs(u - s) <= tuning.level_m]
        if len(near) >= tuning.level_lines:
            level = float(np.median(near))
            if not levels or abs(level - levels[-1]) > tuning.level_m:
                levels.append(level)
    return levels


def _on_walk(
    lines: Sequence[tuple[float, float]],
    a: tuple[float, float],
    b: tuple[float, float],
    within: float,
    shifts: Sequence[float] = (),
) -> list[tuple[float, float]]:
    """The front lines (odometry along, true along; m) within ``within`` m of the straight
    walk from place ``a`` to place ``b`` (``map.tuning.wall_poses.front_agree_m``). With
    ``shifts`` (:func:`_front_levels`), a line may instead have seen one of those things
    before the wall: it then places its frame that much farther back, if that agrees."""
    (o0, t0), (o1, t1) = a, b
    out = []
    for o, t in lines:
        walk = t0 + (o - o0) * (t1 - t0) / (o1 - o0)
        best = min((t + s for s in (0.0, *shifts)), key=lambda v: abs(v - walk))
        if abs(best - walk) <= within:
            out.append((o, best))
    return out


def agreeing_fronts(
    start: tuple[float, float],
    fronts: Sequence[tuple[float, float]],
    *,
    tuning: WallPoseTuning | None = None,
) -> list[tuple[float, float]]:
    """The front lines of one side that agree with one walk along it.

    Each front line puts the frame it was measured at somewhere along the side; over one
    side those places lie on one line against the odometry's distance walked (its slope the
    metres per odometry metre). A line that saw a plank's seam or a rug's edge instead of
    the wall does not. The walk taken is the line through two of the points (the side's
    start among them) with a slope in ``map.tuning.wall_poses.scale_range`` that most front
    lines agree with, within ``map.tuning.wall_poses.front_agree_m`` (ties: the smaller sum
    of residuals).

    Args:
        start: The side's start: (odometry along, true along), m.
        fronts: The front lines' (odometry along, true along), m.
        tuning: ``map.tuning.wall_poses`` (None: the defaults).

    Returns:
        The front lines that agree (all of them with fewer than two, or no walk with two
        agreeing).
    """
    tun = WallPoseTuning() if tuning is None else tuning
    low, high = tun.scale_range
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
        if not low <= slope <= high:
            continue
        residual = np.abs(t - (a[1] + slope * (o - a[0])))
        inliers = residual <= tun.front_agree_m
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
    measured: Sequence[float | None],
    inward: Sequence[float],
    *,
    tuning: WallPoseTuning | None = None,
) -> tuple[list[float], list[bool]] | None:
    """Every frame's distance from one side's wall, from its floor lines (m).

    A line sees the wall or something standing in front of it (a bookcase, a sideboard):
    where the line jumps by more than ``edge_m`` (of ``map.tuning.wall_poses``) between
    frames, beyond what the robot's own walk inward explains, a new stretch begins, one
    level nearer or farther. The wall is the farthest level that at least
    ``max(min_wall_frames, wall_support)`` (3, 20 %) of the lines see (a lone far line, a
    doorway's or a reflection's, lacks that support); a frame's distance is its line plus
    how far its stretch stands in front of the wall, or its own line when its stretch is
    within ``wall_level_m`` of the wall's level (it sees the wall: such levels differ only
    by the odometry's sideways error between them). Frames without a line take the nearest
    frame's distance moved by the odometry's walk inward (only the odometry's short-range
    motion is used: a NAO's sideways odometry drifts 0.3 m along a 5 m side).

    Args:
        measured: Per frame in walking order: the side line's distance (m) or None.
        inward: Per frame: the odometry's walk inward (away from the wall) since the
            previous frame (m; the first is not used).
        tuning: ``map.tuning.wall_poses`` (None: the defaults).

    Returns:
        ``(distances, whether each frame's line saw the wall)``; None when no level has
        that support.
    """
    tun = WallPoseTuning() if tuning is None else tuning
    levels: list[float | None] = []
    level, last, walked = 0.0, None, 0.0
    for i, m in enumerate(measured):
        walked += inward[i] if i else 0.0
        if m is None:
            levels.append(None)
            continue
        if last is not None:
            jump = m - last - walked
            if abs(jump) > tun.edge_m:
                level += jump
        levels.append(level)
        last, walked = m, 0.0
    seen = [v for v in levels if v is not None]
    if not seen:
        return None
    need = max(tun.min_wall_frames, math.ceil(tun.wall_support * len(seen)))
    wall = None
    for v in sorted(set(seen), reverse=True):
        near = [u for u in seen if abs(u - v) < tun.wall_level_m]
        if len(near) >= need:
            wall = max(set(near), key=near.count)  # the stretch most of its lines are on
            break
    if wall is None:
        return None
    walls = [wall, *wall_seen_again(measured, levels, wall, tuning=tun)]
    on_wall = [v is not None and any(abs(v - w) < tun.wall_level_m for w in walls) for v in levels]
    # A line on the wall's level sees the wall: its own distance, not the level's (levels
    # closer than wall_level_m differ only by the odometry's sideways error in between).
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


def wall_seen_again(
    measured: Sequence[float | None],
    levels: Sequence[float | None],
    wall: float,
    *,
    tuning: WallPoseTuning | None = None,
) -> list[float]:
    """The levels of one side's lines, nearer or farther, that are its wall seen again.

    Levels are chained by the jumps between stretches: each stretch of fronts between two
    stretches of the wall adds its own error, and a run of fronts of several depths steered
    along as one adds up theirs (a map origin 0.136 m off: the start's stretch of wall was
    put 0.136 m before the wall it saw; another's 0.106 m, where a second stretch of wall
    seen again came first). A level is the wall again when

    - at least ``map.tuning.wall_poses.min_wall_frames`` lines see it (not the wall's
      share of the side: a lone far line is what that rules out, and the reading below
      does too),
    - it never borders the wall's level (a jump seen directly, from one line to the next,
      measures a front's depth to 1-4 cm: such a level stays a front), and
    - its lines read as the wall's do, their medians within
      ``map.tuning.wall_poses.wall_again_m`` (the survey keeps the wall at its offset; a
      front stands nearer by its depth).

    Args:
        measured: Per frame in walking order: the side line's distance (m) or None.
        levels: Each line's level from :func:`side_distances` (None without a line), m.
        wall: The wall's level, m.
        tuning: ``map.tuning.wall_poses`` (None: the defaults).

    Returns:
        Every level that is the wall seen again, in ascending order; none when there is
        none. Several runs of fronts each err their own way.
    """
    tun = WallPoseTuning() if tuning is None else tuning
    pairs = zip(levels, measured, strict=True)
    lines = [(v, m) for v, m in pairs if v is not None and m is not None]

    def on(level: float) -> list[bool]:
        return [abs(v - level) < tun.wall_level_m for v, _ in lines]

    def reads(group: list[bool]) -> float:
        return float(np.median([m for (_, m), g in zip(lines, group, strict=True) if g]))

    on_wall = on(wall)
    wall_reads = reads(on_wall)
    # nearer levels and farther ones (a chain can err the other way too, leaving a stretch
    # beyond the wall with fewer lines than the wall's share of the side asks: once in 121
    # surveys)
    again: list[float] = []
    for level in sorted({v for v, _ in lines if abs(v - wall) >= tun.wall_level_m}):
        # its own lines: a level within wall_level_m of the wall's shares some of them
        group = [g and not w for g, w in zip(on(level), on_wall, strict=True)]
        borders = any(
            (a and d) or (b and c)
            for (a, b), (c, d) in itertools.pairwise(zip(group, on_wall, strict=True))
        )
        if (
            sum(group) >= tun.min_wall_frames
            and not borders
            and abs(reads(group) - wall_reads) <= tun.wall_again_m
        ):
            again.append(level)
    return again


def _start_from_wall(
    dists: Sequence[float],
    on_wall: Sequence[bool],
    inward: Sequence[float],
    *,
    tuning: WallPoseTuning | None = None,
) -> float:
    """The survey start's distance from side 0's wall from its first frames (m): when its
    own line saw furniture, or disagrees with them by more than
    ``map.tuning.wall_poses.start_agree_m`` while its views do not repeat it
    (:func:`start_views_agree`).

    Each of the first ``map.tuning.wall_poses.start_from_wall_frames`` frames whose line
    sees the wall gives its distance less the odometry's walk inward since the start; their
    median. Without such a frame, the start's distance from its stretch (``dists[0]``).

    Args:
        dists: :func:`side_distances` of side 0, the start first.
        on_wall: Whether each line saw the wall, the start first.
        inward: The walk inward before each, the start first (m).
        tuning: ``map.tuning.wall_poses`` (None: the defaults).
    """
    tun = WallPoseTuning() if tuning is None else tuning
    walked = np.cumsum([0.0, *inward[1:]])
    back = [
        dists[j] - walked[j]
        for j in range(1, min(len(dists), tun.start_from_wall_frames + 1))
        if on_wall[j]
    ]
    return float(np.median(back)) if back else float(dists[0])


def start_views_agree(
    views: Any,
    distance: float,
    offset: float,
    side_normal: float,
    *,
    tuning: WallPoseTuning | None = None,
) -> bool:
    """Whether the survey start's views repeat its side line's distance: at least
    ``map.tuning.wall_poses.start_views`` trusted side lines (:func:`_line`) within
    ``map.tuning.wall_poses.start_views_m`` of it.

    Args:
        views: The survey meta's ``start_views`` (line dicts as the survey wrote them).
        distance: The start's side line distance, as seen (m, before the skirting).
        offset: ``survey.wall_offset_m``, m.
        side_normal: Where the side wall is, rad (FRAME_ROBOT).
        tuning: ``map.tuning.wall_poses`` (None: the defaults).
    """
    tun = WallPoseTuning() if tuning is None else tuning
    if not isinstance(views, list):
        return False
    lines = [_line(view, offset, side_normal) for view in views]
    near = [ln for ln in lines if ln is not None and abs(ln[0] - distance) <= tun.start_views_m]
    return len(near) >= tun.start_views


def _own_heading(
    meta: dict[str, Any],
    offset: float,
    side_normal: float,
    *,
    tuning: WallPoseTuning | None = None,
) -> tuple[float | None, bool, float]:
    """The survey start's heading to side 0's direction (rad) from the lines the start
    itself saw: the median of its side wall's (``start_side`` and every view's,
    ``start_views``: one view's line can mix in a corner's other wall), else of the
    farther walls' (:func:`_far_headings`: the walls ahead and across are square and
    parallel to side 0, their lines err more). None without any; whether it comes
    from clean views of the side wall (:func:`_clean`); and the votes' spread (their
    standard deviation, rad; 0 for one vote). ``tuning``: ``map.tuning.wall_poses`` (None:
    the defaults)."""
    tun = WallPoseTuning() if tuning is None else tuning
    votes = []
    views = meta.get("start_views")
    entries = views if isinstance(views, list) and views else [meta.get("start_side")]
    clean = [e for e in entries if isinstance(e, dict) and _clean(e, tun)]
    for entry in clean or entries:
        line = _line(entry, offset, side_normal)
        if line is not None:
            votes.append(line[1])
    from_clean = bool(votes) and bool(clean)
    if not votes:  # the far walls' lines err more: only without the side wall's
        votes = _far_headings(meta, side_normal, tun.front_heading_m)
    if not votes:
        return None, from_clean, 0.0
    return float(np.median(votes)), from_clean, float(np.std(votes))


def _clean(entry: dict[str, Any], tuning: WallPoseTuning) -> bool:
    """Whether a line's fit is clean: most of its boundary on it, little scatter about it
    (a line mixing in a corner's other wall or furniture is neither): ``tuning``'s
    ``clean_fraction`` and ``clean_rms_m``."""
    rms, fraction = entry.get("rms_m"), entry.get("fraction")
    return (
        isinstance(rms, (int, float))
        and isinstance(fraction, (int, float))
        and rms <= tuning.clean_rms_m
        and fraction >= tuning.clean_fraction
    )


def _far_headings(meta: dict[str, Any], side_normal: float, within_m: float) -> list[float]:
    """The survey start's heading to side 0's direction (rad) from each farther wall it
    saw, within ``within_m`` (``map.tuning.wall_poses.front_heading_m``): the wall ahead
    (``start_front``, square to side 0) and the wall across (``start_across``, parallel to
    it)."""
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
        if distance <= within_m and abs(delta) <= SIDE_ANGLE_ERROR_RAD:
            found.append(delta)
    return found


def _start_heading(
    own: float | None,
    keyframes: Sequence[Keyframe],
    lines: Sequence[tuple[float, float] | None],
    side0: Sequence[int],
    along: np.ndarray,
    tuning: WallPoseTuning,
    clean: bool = False,
    spread: float = 0.0,
) -> tuple[float | None, float | None, float | None]:
    """The survey start's heading to side 0's wall (rad), or None without any line; what
    side 0's first frames say of it (None: nothing); and the heading's one sigma (rad;
    None without a heading).

    ``own`` is what the start itself saw: its side line's angle, or (a side wall too near
    to be seen) a farther wall's (:func:`_far_headings`). Side 0's frames' lines within
    ``start_heading_m`` (of ``map.tuning.wall_poses``) of walk, each less the odometry's
    turn from the start to its frame (the map frame is the start's odometry frame), say it
    too: their median. A ``clean`` own line (the side wall's, seen whole and straight from
    the start: :func:`_clean`) is kept: the frames carry the odometry's turn error, and a
    NAO's odometry can turn 0.1 rad in the first metre. Otherwise the two are weighed by
    their variances: the own line's one sigma is ``start_view_std_rad``, or its views'
    ``spread`` (rad) when larger; the frames' ``start_frames_std_rad``. A clean own line's
    sigma is ``start_clean_std_rad``; a weighed heading's, the weighing's.
    """
    votes = []
    for i in side0:
        if along[i] > tuning.start_heading_m:
            break
        if (line := lines[i]) is not None:
            votes.append(modulo2PI(line[1] - keyframes[i].pose.theta))
    frames = float(np.median(votes)) if votes else None
    own_std = tuning.start_clean_std_rad if clean else max(tuning.start_view_std_rad, spread)
    if own is None:
        return frames, frames, None if frames is None else tuning.start_frames_std_rad
    if frames is None or clean:
        return own, frames, own_std
    w_own = 1.0 / own_std**2
    w_frames = 1.0 / tuning.start_frames_std_rad**2
    weighed = modulo2PI(own + w_frames / (w_own + w_frames) * modulo2PI(frames - own))
    return weighed, frames, 1.0 / math.sqrt(w_own + w_frames)
