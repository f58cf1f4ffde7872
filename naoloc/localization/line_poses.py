"""Poses the floor-wall lines allow: proposals for the filter's hypotheses.

A floor-wall line measured at the robot (:class:`naoloc.perception.floorline.WallLine`,
FRAME_ROBOT) says how far a wall is and at which angle. The lines of one room agree on the
robot's heading modulo a quarter turn, and each gives one coordinate once assigned to the
wall it faces (furniture in front of a wall gives a coordinate too near that wall). Every
combination is a pose the lines allow; the filter's picture evidence chooses among them.

Frames: the map frame in and out (m, rad); the wall frame W of :class:`WallMap` inside.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from naoloc.config import FilterTuning
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.localization.walls import WallMap
from naoloc.perception.floorline import WallLine

__all__ = ["line_poses"]


def line_poses(
    lines: Sequence[WallLine], walls: WallMap, tun: FilterTuning, heading: float | None = None
) -> list[np.ndarray]:
    """Every pose the lines allow: a heading they agree on, then per axis each coordinate.

    Args:
        lines: Floor-wall lines at the robot now, FRAME_ROBOT.
        walls: The map's walls.
        tun: The filter's tuning (``line_agree_*``, ``min_line_span_m``, ``behind_wall_m``).
        heading: Keep to this heading's quarter turn (map frame, rad); None tries all four.

    Returns:
        ``(x, y, theta)`` robot poses in the map frame (none when fewer than two lines agree
        on the heading or an axis has no line).
    """
    found = _line_heading(lines, tun)
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
        xs, ys = (_feasible(v, tun) for v in values)
        for x in xs:
            for y in ys:
                p = walls.frame * Pose2D(x, y, modulo2PI(theta))
                out.append(np.array([p.x, p.y, p.theta]))
    return out


def _line_heading(
    lines: Sequence[WallLine], tun: FilterTuning
) -> tuple[list[WallLine], float] | None:
    """The usable lines that agree on a heading in W (modulo a quarter turn), and it (rad)."""
    usable = [ln for ln in lines if ln.span_m >= tun.min_line_span_m and math.isfinite(ln.distance)]
    if len(usable) < 2:
        return None
    quarter = math.pi / 2
    d = np.asarray([math.remainder(-ln.normal, quarter) for ln in usable])
    w = np.asarray([ln.span_m for ln in usable])
    gap = np.abs(np.remainder(d[:, None] - d[None, :] + quarter / 2, quarter) - quarter / 2)
    support = (w[None, :] * (gap < tun.line_agree_rad)).sum(axis=1)
    centre = int(np.argmax(support))
    agree = gap[centre] < tun.line_agree_rad
    if agree.sum() < 2:
        return None
    off = np.remainder(d[agree] - d[centre] + quarter / 2, quarter) - quarter / 2
    base = float(d[centre] + np.average(off, weights=w[agree]))
    return [ln for ln, ok in zip(usable, agree, strict=True) if ok], base


def _axis_values(
    lines: Sequence[WallLine], walls: WallMap, theta: float
) -> list[list[tuple[float, bool]]]:
    """Per axis of W (x, y), the robot coordinate each line gives at heading ``theta`` (W),
    and whether its wall is the one on the axis's + side."""
    x0, x1, y0, y1 = walls.bounds
    coords = (x1, y1, -x0, -y0)  # each side's coordinate along its outward normal, in W
    per_axis: list[list[tuple[float, bool]]] = [[], []]
    for ln in lines:
        k = round((theta + ln.normal) / (math.pi / 2)) % 4
        along = coords[k] - ln.distance
        per_axis[k % 2].append((along if k < 2 else -along, k < 2))
    return per_axis


def _feasible(values: Sequence[tuple[float, bool]], tun: FilterTuning) -> list[float]:
    """The coordinates along one axis that put no seen line behind its wall.

    A line is where the floor ends: at the wall, or at furniture in front of it, so the
    robot is where one of the nearest lines on either side is the wall's. Clusters of the
    lines' coordinates (within ``line_agree_m``) that would put a line more than
    ``behind_wall_m`` behind a wall are dropped, unless the lines contradict each other.
    """
    if not values:
        return []
    behind = tun.behind_wall_m
    lo = max((v for v, plus in values if not plus), default=-math.inf) - behind
    hi = min((v for v, plus in values if plus), default=math.inf) + behind
    ordered = sorted(v for v, _ in values)
    groups: list[list[float]] = [[ordered[0]]]
    for a in ordered[1:]:
        if a - groups[-1][-1] < tun.line_agree_m:
            groups[-1].append(a)
        else:
            groups.append([a])
    means = [float(np.mean(g)) for g in groups]
    if lo > hi:
        return means
    return [c for c in means if lo <= c <= hi]
