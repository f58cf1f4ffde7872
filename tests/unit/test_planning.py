"""The floor grid and A*: around obstacles, preferring walked floor, never through walls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.geometry import Pose2D
from naoloc.navigation.grid import (
    BLOCKED,
    FREE,
    FloorGrid,
    NoPath,
    block_outside,
    grid_from_map,
    grid_of_map,
)
from naoloc.navigation.route import path_length


def _clear(grid: FloorGrid, path: list[Pose2D], start: Pose2D) -> bool:
    ok = grid.passable()
    prev = start
    for p in path:
        for f in np.linspace(0, 1, 40):
            x, y = prev.x + f * (p.x - prev.x), prev.y + f * (p.y - prev.y)
            r, c = grid.index(x, y)
            if grid.cells[r, c] == BLOCKED:
                return False
        prev = p
    return bool(ok.any())


def test_path_goes_around_a_chair() -> None:
    grid = FloorGrid.empty((-1.0, -1.0, 4.0, 4.0), 0.1, robot_radius=0.2)
    for x in np.arange(1.2, 1.8, 0.05):  # a 0.6 m chair between start and goal
        for y in np.arange(1.2, 1.8, 0.05):
            grid.mark(float(x), float(y), 0.05, BLOCKED)
    start, goal = Pose2D(2.5, 2.5), Pose2D(0.0, 0.0)
    path = grid.plan(start, goal)
    assert _clear(grid, path, start)
    assert path[-1].distance(goal) < 1e-9
    straight = start.distance(goal)
    assert straight < path_length(start, path) < straight + 1.5


def test_a_start_beside_a_pocket_the_inflation_closes_leaves_toward_the_goal() -> None:
    """Room 1995159885: a start 0.3 m from a wall, inside the inflated band; its nearest
    passable cells were a pocket that only the inflation of a wall and furniture closes, and
    go-home gave up there (no path). The path now begins at the nearest cell the goal can be
    reached from by a step that crosses nothing blocked; a start truly walled in (blocked
    cells between it and every such cell) still has no path."""
    grid = FloorGrid.empty((0.0, 0.0, 4.0, 4.0), 0.05, robot_radius=0.15)
    box = [(x, y) for x in np.arange(2.0, 2.61, 0.05) for y in (2.6,)]  # a U of furniture
    box += [(x, y) for x in (2.0, 2.6) for y in np.arange(2.0, 2.61, 0.05)]
    box += [(x, 2.0) for x in np.arange(2.0, 2.61, 0.05) if not 2.22 < x < 2.38]  # a gap
    for x, y in box:
        grid.cells[grid.index(float(x) + 0.01, float(y) + 0.01)] = BLOCKED
    ok = grid.passable()
    start, goal = Pose2D(2.3, 2.07), Pose2D(0.5, 0.5)
    r, c = grid.index(start.x, start.y)
    assert not ok[r, c]  # in the gap, inside the inflation
    pocket = grid._nearest_ok(ok, r, c)
    assert grid.centre(*pocket)[1] > 2.1  # the nearest passable cell is inside the U
    path = grid.plan(start, goal)
    assert path[-1].distance(goal) < 1e-9
    assert _clear(grid, path, start)
    # Close the gap with blocked cells: the start is walled in, nothing to escape to.
    for x in np.arange(2.2, 2.41, 0.05):
        grid.cells[grid.index(float(x) + 0.01, 2.01)] = BLOCKED
    with pytest.raises(NoPath):
        grid.plan(Pose2D(2.3, 2.3), goal)


def test_walls_are_never_crossed() -> None:
    grid = FloorGrid.empty((0.0, 0.0, 4.0, 2.0), 0.1, robot_radius=0.1)
    grid.cells[:, 19:21] = BLOCKED  # a wall across the room...
    grid.cells[0:3, 19:21] = 1  # ...with a door at the bottom
    path = grid.plan(Pose2D(0.5, 1.5), Pose2D(3.5, 1.5))
    assert min(p.y for p in path) < 0.5  # through the door
    grid.cells[0:3, 19:21] = BLOCKED
    with pytest.raises(NoPath, match="no passable path"):
        grid.plan(Pose2D(0.5, 1.5), Pose2D(3.5, 1.5))


def test_walked_floor_is_preferred() -> None:
    grid = FloorGrid.empty((0.0, 0.0, 4.0, 4.0), 0.1, robot_radius=0.1)
    for x in np.arange(0.2, 3.8, 0.1):  # the survey walked along y = 0.5 and x = 3.5
        grid.mark(float(x), 0.5, 0.3, FREE)
    for y in np.arange(0.5, 3.8, 0.1):
        grid.mark(3.5, float(y), 0.3, FREE)
    path = grid.plan(Pose2D(3.5, 3.5), Pose2D(0.5, 0.5))
    # The L along walked floor (6 m at cost 1) beats the unknown diagonal (4.2 m at cost 1.6).
    assert path_length(Pose2D(3.5, 3.5), path) > 5.0


def test_grid_from_map_blocks_furniture_and_frees_the_circuit() -> None:
    rng = np.random.default_rng(0)
    side = np.linspace(0, 4, 21)
    circuit = np.array(
        [[x, 0, 0] for x in side] + [[4, y, 0] for y in side] + [[x, 4, 0] for x in side[::-1]]
        + [[0, y, 0] for y in side[::-1]]
    )  # fmt: skip
    walls = [[rng.uniform(-1, 5), -1, rng.uniform(0, 1)] for _ in range(100)]
    walls += [[rng.uniform(-1, 5), 5, rng.uniform(0, 1)] for _ in range(100)]
    walls += [[-1, rng.uniform(-1, 5), rng.uniform(0, 1)] for _ in range(100)]
    walls += [[5, rng.uniform(-1, 5), rng.uniform(0, 1)] for _ in range(100)]
    table = [[rng.uniform(1.8, 2.2), rng.uniform(1.8, 2.2), 0.7] for _ in range(30)]
    floor = [[rng.uniform(0, 4), rng.uniform(0, 4), 0.0] for _ in range(30)]  # floor texture
    grid = grid_from_map(circuit, np.array(walls + table + floor))
    assert grid.cells[grid.index(2.0, 2.0)] == BLOCKED  # the table
    assert grid.cells[grid.index(2.0, 0.0)] == FREE  # walked
    assert grid.cells[grid.index(5.6, 2.0)] == BLOCKED  # beyond the wall
    assert grid.cells[grid.index(1.0, 3.0)] != BLOCKED  # floor features are not obstacles
    path = grid.plan(Pose2D(3.0, 3.0), Pose2D(0.0, 0.0))
    assert _clear(grid, path, Pose2D(3.0, 3.0)) and math.isfinite(path_length(Pose2D(3, 3), path))


def test_the_survey_start_is_free_and_the_filter_may_stand_by_furniture() -> None:
    """Room 1789164527: a bench's landmarks 0.1-0.8 m beside the survey start, whose first
    keyframe was taken 0.27 m on (here 0.4 m). The start (the map origin, home) was blocked by the
    bench's clearance, and the particle filter, given the passable cells, dropped every
    particle that stood where the robot truly stood: go-home ended 0.13-0.55 m from home.
    The origin is walked floor; the filter's test keeps no clearance."""
    circuit = np.array([[0.35, 0.2, 0.0], [0.56, 0.3, 0.0], [0.8, 0.4, 0.0]])
    walls = [[x, y, 0.5] for x in np.linspace(-1.0, 2.0, 31) for y in (-1.0, 2.0)]
    walls += [[x, y, 0.5] for y in np.linspace(-1.0, 2.0, 31) for x in (-1.0, 2.0)]
    bench = [[x, y, 0.4] for x in np.linspace(-0.4, 0.6, 11) for y in (-0.2, -0.5, -0.8)]
    grid = grid_from_map(circuit, np.array(walls + bench))
    assert grid.cells[grid.index(0.0, 0.0)] == FREE  # where the survey started
    assert grid.cells[grid.index(0.0, -0.5)] == BLOCKED  # the bench
    standing = grid.free_test(clearance=False)
    passing = grid.free_test()
    at = (np.array([0.0, 0.0, 0.0]), np.array([0.0, -0.1, -0.5]))
    assert standing(*at).tolist() == [True, True, False]
    assert not passing(np.array([0.0]), np.array([-0.3]))[0]  # a path keeps its clearance
    assert standing(np.array([0.0]), np.array([-0.3]))[0]


def test_the_maps_walls_bound_the_grid() -> None:
    """Landmarks triangulated behind their wall (far pictures) put the landmarks' box
    0.4 m beyond it; the walls the survey placed block the floor beyond them, so a path
    keeps the robot's clearance from the wall itself."""
    from naoloc.localization.walls import WallMap

    rng = np.random.default_rng(1)
    side = np.linspace(0, 3, 16)
    circuit = np.array([[x, 0, 0] for x in side] + [[3, y, 0] for y in side])
    # walls at x = -1 and 4, y = -1 and 4; the landmarks of the x = 4 wall stand 0.2-0.8 m behind
    pts = [[rng.uniform(-1, 4), y, 0.5] for _ in range(80) for y in (-1.0, 4.0)]
    pts += [[-1.0, rng.uniform(-1, 4), 0.5] for _ in range(80)]
    pts += [[rng.uniform(4.2, 4.8), rng.uniform(-1, 4), 0.5] for _ in range(80)]
    walls = WallMap.of(Pose2D(0.0, 0.0, 0.0), (-1.0, 4.0, -1.0, 4.0))
    grid = grid_from_map(circuit, np.array(pts))
    assert grid.cells[grid.index(4.15, 2.0)] != BLOCKED  # beyond the wall, inside the box
    block_outside(grid, walls)
    assert grid.cells[grid.index(4.15, 2.0)] == BLOCKED
    assert grid.cells[grid.index(3.85, 2.0)] != BLOCKED
    passing = grid.free_test()
    assert not passing(np.array([3.9]), np.array([2.0]))[0]  # the clearance from the wall
    path = grid.plan(Pose2D(3.0, 0.0), Pose2D(3.0, 3.0))
    assert max(p.x for p in path) < 4.0 - grid.robot_radius


def test_a_maps_grid_takes_its_walls_from_the_meta() -> None:
    from types import SimpleNamespace

    side = np.linspace(0, 3, 16)
    poses = np.array([[x, 0, 0] for x in side] + [[3, y, 0] for y in side])
    pts = np.array([[4.5, y, 0.5] for y in np.linspace(-1, 4, 60)]
                   + [[-1.0, y, 0.5] for y in np.linspace(-1, 4, 60)])  # fmt: skip
    meta = {"wall_poses": {"wall_frame": [0.0, 0.0, 0.0], "walls_m": [-1.0, 4.0, -1.0, 4.0]}}
    with_walls = grid_of_map(SimpleNamespace(keyframe_poses=poses, kp_points=pts, meta=meta))
    without = grid_of_map(SimpleNamespace(keyframe_poses=poses, kp_points=pts, meta={}))
    assert with_walls.cells[with_walls.index(4.2, 1.0)] == BLOCKED
    assert without.cells[without.index(4.2, 1.0)] != BLOCKED
