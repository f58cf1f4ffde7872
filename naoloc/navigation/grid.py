"""Paths on the floor: a free-space grid learned from the survey, and A* over it.

The grid covers the map frame (metres). Each cell is *free* (the robot walked there during
the survey), *unknown* (never walked, nothing seen there), or *blocked* (outside the room's
walls, furniture seen as landmarks near the floor, or a place where a walk was blocked).
Paths prefer free cells, may cross unknown ones at a higher cost, never blocked ones, and
keep the robot's radius from every blocked cell. A found path is shortened to the fewest
waypoints that keep line of sight on passable cells.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.localization.walls import WallMap, wall_map

FREE, UNKNOWN, BLOCKED = 0, 1, 2
# Step cost per metre over free and unknown cells: walking where the survey walked is safe.
FREE_COST, UNKNOWN_COST = 1.0, 1.6


class NoPath(NaolocError):
    """No passable path between two places of the grid."""


# A start inside an inflated obstacle tries this many of the nearest passable cells the goal
# can be reached from for a straight step that crosses no blocked cell (:meth:`FloorGrid.plan`).
ESCAPE_TRIES = 400
# Failing that, the nearest such cell within this (m), across blocked cells: near a wall the
# landmarks of a skirting or a radiator block cells the robot stands among (room
# 1995159885: a start 0.3 m from a wall fenced in by them, 0.36 m from open floor).
ESCAPE_M = 0.6


@dataclass
class FloorGrid:
    """An occupancy grid of the floor in the map frame.

    Attributes:
        origin: Map-frame (x, y) of the corner of cell (0, 0), m.
        resolution: Cell side, m.
        cells: ``(ny, nx)`` int8 of FREE, UNKNOWN, BLOCKED.
        robot_radius: Clearance kept from blocked cells, m.
    """

    origin: tuple[float, float]
    resolution: float
    cells: np.ndarray
    robot_radius: float = 0.2

    @classmethod
    def empty(
        cls,
        bounds: tuple[float, float, float, float],
        resolution: float = 0.1,
        robot_radius: float = 0.2,
    ) -> FloorGrid:
        """An all-unknown grid over ``(xmin, ymin, xmax, ymax)`` (map frame, m)."""
        x0, y0, x1, y1 = bounds
        nx = max(1, math.ceil((x1 - x0) / resolution))
        ny = max(1, math.ceil((y1 - y0) / resolution))
        if nx * ny > 4_000_000:
            raise NaolocError(f"floor grid of {nx} x {ny} cells is too large")
        cells = np.full((ny, nx), UNKNOWN, dtype=np.int8)
        return cls((x0, y0), resolution, cells, robot_radius)

    # ------------------------------------------------------------------ cells
    def index(self, x: float, y: float) -> tuple[int, int]:
        """(row, column) of the cell holding map-frame ``(x, y)``, clipped to the grid."""
        ny, nx = self.cells.shape
        c = int(np.clip(math.floor((x - self.origin[0]) / self.resolution), 0, nx - 1))
        r = int(np.clip(math.floor((y - self.origin[1]) / self.resolution), 0, ny - 1))
        return r, c

    def centre(self, r: int, c: int) -> tuple[float, float]:
        """Map-frame centre of cell (r, c), m."""
        return (
            self.origin[0] + (c + 0.5) * self.resolution,
            self.origin[1] + (r + 0.5) * self.resolution,
        )

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Map-frame x and y of every cell's centre, m: two ``(ny, nx)`` arrays."""
        ny, nx = self.cells.shape
        xs = self.origin[0] + (np.arange(nx) + 0.5) * self.resolution
        ys = self.origin[1] + (np.arange(ny) + 0.5) * self.resolution
        gx, gy = np.meshgrid(xs, ys)
        return gx, gy

    def _disc(self, x: float, y: float, radius: float) -> tuple[slice, slice, np.ndarray]:
        r0, c0 = self.index(x - radius, y - radius)
        r1, c1 = self.index(x + radius, y + radius)
        rows, cols = np.mgrid[r0 : r1 + 1, c0 : c1 + 1]
        cx = self.origin[0] + (cols + 0.5) * self.resolution
        cy = self.origin[1] + (rows + 0.5) * self.resolution
        return slice(r0, r1 + 1), slice(c0, c1 + 1), np.hypot(cx - x, cy - y) <= radius

    def mark(self, x: float, y: float, radius: float, state: int, *, force: bool = False) -> None:
        """Set the cells within ``radius`` m of map-frame ``(x, y)``.

        FREE overwrites BLOCKED only with ``force`` (the robot walked there, so it is free).
        """
        rs, cs, inside = self._disc(x, y, radius)
        view = self.cells[rs, cs]
        if state == FREE and not force:
            view[inside & (view != BLOCKED)] = FREE
        else:
            view[inside] = state

    def passable(self) -> np.ndarray:
        """Boolean ``(ny, nx)``: cells whose centre is at least robot_radius from blocked ones."""
        blocked = self.cells == BLOCKED
        if not blocked.any():
            return np.ones_like(blocked)
        k = math.ceil(self.robot_radius / self.resolution)
        grown = blocked.copy()
        ny, nx = blocked.shape
        for dr in range(-k, k + 1):
            for dc in range(-k, k + 1):
                if dr * dr + dc * dc > k * k:
                    continue
                src = blocked[max(0, -dr) : ny - max(0, dr), max(0, -dc) : nx - max(0, dc)]
                grown[max(0, dr) : ny - max(0, -dr), max(0, dc) : nx - max(0, -dc)] |= src
        return np.asarray(~grown)

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of the grid, map frame (m)."""
        ny, nx = self.cells.shape
        x0, y0 = self.origin
        return (x0, y0, x0 + nx * self.resolution, y0 + ny * self.resolution)

    def free_test(
        self, *, clearance: bool = True
    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """A vectorised ``free(xs, ys)`` (as of now), False off the grid.

        Args:
            clearance: Passable cells, robot_radius from every blocked one (where a path
                may lead); False: every cell not blocked itself (where the robot may stand:
                a particle filter's test, since furniture's landmarks are placed to a
                decimetre or two and a robot stands closer to a table than a path keeps).
        """
        ok = self.passable() if clearance else self.cells != BLOCKED
        ny, nx = ok.shape
        x0, y0, res = self.origin[0], self.origin[1], self.resolution

        def free(xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
            c = np.floor((np.asarray(xs) - x0) / res).astype(np.int64)
            r = np.floor((np.asarray(ys) - y0) / res).astype(np.int64)
            inside = (c >= 0) & (c < nx) & (r >= 0) & (r < ny)
            out = np.zeros(c.shape, dtype=bool)
            out[inside] = ok[r[inside], c[inside]]
            return out

        return free

    # ------------------------------------------------------------------ search
    def plan(self, start: Pose2D, goal: Pose2D) -> list[Pose2D]:
        """The cheapest passable path from ``start`` to ``goal`` (map frame).

        A goal inside an inflated obstacle is moved to the nearest passable cell. So is a
        start, but to the nearest one the goal can be reached from and that a straight step
        reaches without crossing a blocked cell, or else the nearest one the goal can be
        reached from within :data:`ESCAPE_M`: the nearest passable cell may lie in a pocket
        that only the inflation closes (room 1995159885: a start 0.3 m from a wall, its
        nearest passable cells five cells fenced in, and go-home gave up there). The path
        then steps to that cell first.

        Returns:
            Waypoints after ``start``, ending at ``goal`` (positions; headings 0).

        Raises:
            NoPath: The goal cannot be reached over passable cells.
        """
        ok = self.passable()
        if not ok.any():
            raise NoPath("the floor grid has no passable cell")
        g = self._nearest_ok(ok, *self.index(goal.x, goal.y))
        s = self._start_cell(ok, g, start)
        cost = np.where(self.cells == FREE, FREE_COST, UNKNOWN_COST) * self.resolution
        cells = _astar(ok, cost, s, g)
        if cells is None:
            raise NoPath(
                f"no passable path from ({start.x:.2f}, {start.y:.2f}) to "
                f"({goal.x:.2f}, {goal.y:.2f}) m"
            )
        pts = [self.centre(r, c) for r, c in _shortcut(ok, cost, cells)]
        pts[-1] = (goal.x, goal.y) if ok[self.index(goal.x, goal.y)] else pts[-1]
        # A start moved out of an inflated obstacle steps to its cell first (a straight step
        # that crosses nothing blocked), then on.
        moved = s != self.index(start.x, start.y) and len(pts) > 1
        return [Pose2D(x, y) for x, y in pts[0 if moved else 1 :]] or [Pose2D(goal.x, goal.y)]

    def _start_cell(self, ok: np.ndarray, goal: tuple[int, int], start: Pose2D) -> tuple[int, int]:
        """Where a path from ``start`` begins (see :meth:`plan`)."""
        r, c = self.index(start.x, start.y)
        if ok[r, c]:
            return r, c
        rows, cols = np.nonzero(_reachable(ok, goal))
        order = np.argsort((rows - r) ** 2 + (cols - c) ** 2, kind="stable")
        for k in order[:ESCAPE_TRIES]:
            cell = (int(rows[k]), int(cols[k]))
            if self._clear_step(start, self.centre(*cell)):
                return cell
        if len(order):  # blocked cells on every step: maybe landmarks, not furniture
            cell = (int(rows[order[0]]), int(cols[order[0]]))
            if math.dist(self.centre(*cell), (start.x, start.y)) <= ESCAPE_M:
                return cell  # a walk that meets something stops, marks it and re-plans
        return self._nearest_ok(ok, r, c)

    def _clear_step(self, start: Pose2D, end: tuple[float, float]) -> bool:
        """Whether the straight step from ``start`` to ``end`` (map frame) crosses no
        blocked cell (inflated ones are crossed: the robot already stands in one)."""
        n = max(2, math.ceil(math.dist((start.x, start.y), end) / (0.5 * self.resolution)) + 1)
        for f in np.linspace(0.0, 1.0, n):
            x, y = start.x + f * (end[0] - start.x), start.y + f * (end[1] - start.y)
            if self.cells[self.index(x, y)] == BLOCKED:
                return False
        return True

    def _nearest_ok(self, ok: np.ndarray, r: int, c: int) -> tuple[int, int]:
        if ok[r, c]:
            return r, c
        rows, cols = np.nonzero(ok)
        k = int(np.argmin((rows - r) ** 2 + (cols - c) ** 2))
        return int(rows[k]), int(cols[k])


def _reachable(ok: np.ndarray, cell: tuple[int, int]) -> np.ndarray:
    """The passable cells 8-connected to ``cell`` (itself passable), as A* moves."""
    import cv2

    _n, labels = cv2.connectedComponents(ok.astype(np.uint8), connectivity=8)
    out: np.ndarray = labels == labels[cell]
    return out


def _astar(
    ok: np.ndarray, cost: np.ndarray, start: tuple[int, int], goal: tuple[int, int]
) -> list[tuple[int, int]] | None:
    """8-connected A* over passable cells; ``cost`` is the per-cell step cost (m)."""
    ny, nx = ok.shape
    best = np.full(ok.shape, np.inf)
    parent = np.full((ny, nx, 2), -1, dtype=np.int64)
    best[start] = 0.0
    h0 = FREE_COST * math.hypot(goal[0] - start[0], goal[1] - start[1]) * float(cost.min())
    heap: list[tuple[float, float, int, int]] = [(h0, 0.0, *start)]
    steps = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))
    unit = float(cost.min())
    while heap:
        _f, g, r, c = heapq.heappop(heap)
        if (r, c) == goal:
            path = [(r, c)]
            while (r, c) != start:
                r, c = (int(v) for v in parent[r, c])
                path.append((r, c))
            return path[::-1]
        if g > best[r, c]:
            continue
        for dr, dc in steps:
            rr, cc = r + dr, c + dc
            if not (0 <= rr < ny and 0 <= cc < nx) or not ok[rr, cc]:
                continue
            ng = g + cost[rr, cc] * (math.sqrt(2.0) if dr and dc else 1.0)
            if ng < best[rr, cc]:
                best[rr, cc] = ng
                parent[rr, cc] = (r, c)
                h = unit * math.hypot(goal[0] - rr, goal[1] - cc)
                heapq.heappush(heap, (ng + h, ng, rr, cc))
    return None


def _line(a: tuple[int, int], b: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    n = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2 + 1
    rr = np.rint(np.linspace(a[0], b[0], n)).astype(int)
    cc = np.rint(np.linspace(a[1], b[1], n)).astype(int)
    return rr, cc


def _shortcut(
    ok: np.ndarray, cost: np.ndarray, cells: list[tuple[int, int]]
) -> list[tuple[int, int]]:
    """Fewest waypoints: skip ahead while the straight line is passable and no dearer."""
    steps = [0.0]
    for (r0, c0), (r1, c1) in itertools.pairwise(cells):
        steps.append(steps[-1] + cost[r1, c1] * math.hypot(r1 - r0, c1 - c0))
    out = [cells[0]]
    i = 0
    while i < len(cells) - 1:
        j = len(cells) - 1
        while j > i + 1:
            rr, cc = _line(cells[i], cells[j])
            if ok[rr, cc].all():
                length = math.hypot(cells[j][0] - cells[i][0], cells[j][1] - cells[i][1])
                line_cost = float(cost[rr, cc].mean()) * length
                if line_cost <= (steps[j] - steps[i]) * 1.001:
                    break
            j -= 1
        out.append(cells[j])
        i = j
    return out


def grid_from_map(
    keyframe_poses: np.ndarray,
    landmarks: np.ndarray,
    *,
    resolution: float = 0.1,
    robot_radius: float = 0.2,
    walked_radius: float = 0.3,
    obstacle_heights: tuple[float, float] = (0.05, 0.9),
    wall_margin: float = 0.35,
) -> FloorGrid:
    """The floor grid a map implies (map frame).

    - The room's walls are where the landmarks are: outside the 2nd-98th percentile box of
      the landmarks' x and y the floor is blocked.
    - Landmarks between ``obstacle_heights`` (m above the floor) and more than
      ``wall_margin`` inside the walls are furniture or clutter: blocked.
    - Every survey keyframe pose, and the map origin where the survey started, marks a disc
      of ``walked_radius`` free (it was walked).

    Args:
        keyframe_poses: ``(N, 3)`` survey poses, map frame.
        landmarks: ``(M, 3)`` landmark points (x, y, z), map frame; NaN rows are ignored.
        resolution: Cell side, m.
        robot_radius: Clearance kept from blocked cells, m.
        walked_radius: Free disc around each survey pose, m.
        obstacle_heights: Landmark heights that count as obstacles, m.
        wall_margin: Landmarks this close to the walls' box are on the walls, m.
    """
    poses = np.asarray(keyframe_poses, dtype=np.float64).reshape(-1, 3)
    pts = np.asarray(landmarks, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) >= 20:
        lo = np.percentile(pts[:, :2], 2, axis=0)
        hi = np.percentile(pts[:, :2], 98, axis=0)
    else:  # too few landmarks to see the walls: the survey's extent plus a metre
        lo, hi = poses[:, :2].min(axis=0) - 1.0, poses[:, :2].max(axis=0) + 1.0
    lo = np.minimum(lo, poses[:, :2].min(axis=0) - walked_radius)
    hi = np.maximum(hi, poses[:, :2].max(axis=0) + walked_radius)
    grid = FloorGrid.empty(
        (float(lo[0]) - 0.5, float(lo[1]) - 0.5, float(hi[0]) + 0.5, float(hi[1]) + 0.5),
        resolution,
        robot_radius,
    )
    gx, gy = grid.centres()
    grid.cells[(gx < lo[0]) | (gx > hi[0]) | (gy < lo[1]) | (gy > hi[1])] = BLOCKED
    z0, z1 = obstacle_heights
    inner = (
        (pts[:, 2] > z0)
        & (pts[:, 2] < z1)
        & (pts[:, 0] > lo[0] + wall_margin)
        & (pts[:, 0] < hi[0] - wall_margin)
        & (pts[:, 1] > lo[1] + wall_margin)
        & (pts[:, 1] < hi[1] - wall_margin)
    )
    for x, y, _z in pts[inner]:
        grid.mark(float(x), float(y), resolution, BLOCKED)
    # Where the survey walked is free, whatever a stray landmark said; it started at the
    # map origin (the odometry's origin), where no keyframe may have been taken.
    for x, y, _t in np.vstack([poses, np.zeros((1, 3))]):
        grid.mark(float(x), float(y), walked_radius, FREE, force=True)
    return grid


def block_outside(grid: FloorGrid, walls: WallMap) -> None:
    """Block every cell whose centre lies beyond one of the map's walls (map frame).

    The landmarks' extent places the walls only roughly: a far picture's landmarks
    triangulate up to decimetres behind their wall, and a path planned to the 98th
    percentile of them ran along, or into, the wall itself.
    """
    grid.cells[walls.depth(*grid.centres()) < 0.0] = BLOCKED


def grid_of_map(vmap: Any) -> FloorGrid:
    """The floor grid of a map: keyframe poses walked free, landmarks near the floor blocked,
    and beyond the walls the survey placed (``meta["wall_poses"]``) blocked."""
    refined = getattr(vmap, "refined_poses", None)
    poses = np.asarray(vmap.keyframe_poses if refined is None else refined)
    points = getattr(vmap, "kp_points", None)
    pts = np.empty((0, 3)) if points is None else np.asarray(points)
    grid = grid_from_map(poses, pts)
    meta = getattr(vmap, "meta", None)
    walls = wall_map(meta) if isinstance(meta, dict) else None
    if walls is not None:
        block_outside(grid, walls)
    return grid
