"""How much of a map's floor grid lies beyond the walls the survey placed.

Usage::

    python tools/grid_walls.py MAP.npz [MAP.npz ...]

For each map: the passable cells (robot_radius from every blocked one) of the grid the
landmarks alone give (:func:`naoloc.navigation.grid.grid_from_map`: the room's extent is
the landmarks' 2nd-98th percentile box) that lie beyond a wall or within 0.2 m of one,
against the same for the grid go-home and the walks plan on
(:func:`naoloc.navigation.grid.grid_of_map`, bounded by ``meta.wall_poses``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from naoloc.errors import NaolocError
from naoloc.localization.walls import wall_map
from naoloc.mapping.map import load_map
from naoloc.navigation.grid import grid_from_map, grid_of_map


def main() -> int:
    """Print the figures of each map."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("maps", type=Path, nargs="+")
    args = parser.parse_args()
    for path in args.maps:
        try:
            vmap = load_map(path)
        except NaolocError as err:
            print(f"grid_walls: {err}", file=sys.stderr)
            return 1
        walls = wall_map(vmap.meta)
        if walls is None:
            print(f"{path}: no walls recorded (not a wall-referenced survey)")
            continue
        refined = getattr(vmap, "refined_poses", None)
        poses = np.asarray(vmap.keyframe_poses if refined is None else refined)
        for name, grid in (
            ("landmarks' box", grid_from_map(poses, np.asarray(vmap.kp_points))),
            ("walls", grid_of_map(vmap)),
        ):
            ok = grid.passable()
            d = walls.depth(*grid.centres())
            print(
                f"{path}: {name}: {int(ok.sum())} passable cells, {int((ok & (d < 0)).sum())} "
                f"beyond a wall, {int((ok & (d < 0.2)).sum())} beyond or within 0.2 m"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
