"""How far recorded floor lines stand from the map's walls at the true pose: the line noise.

Usage::

    python tools/line_noise.py OUT [OUT ...]

Each ``OUT`` is an output folder of ``tools/eval_unseen_rooms.py --record``. For every
recorded localization in a room whose map passed its checks, every floor-line scan is put
at the simulator's true pose of the moment it was taken (the final truth carried back by
the odometry, a few centimetres of walking at most), and each line is compared with the
map's walls and furniture fronts within 0.12 rad of its direction. Printed per range of
distance: the lines, the share within 0.1 m of a wall or front, the median and robust
standard deviation (1.4826 MAD) of the distance residual of those within 0.1 m, the same
for the direction, and the share of lines 0.1-0.5 m before a wall (furniture fronts along
it). These figures set ``localize.filter.line_sigma_*``.

The residual includes the map's own error around the pose (walls placed to 1-2 cm) and the
odometry's between the scan and the end; it is the noise the filter sees.
"""

from __future__ import annotations

import argparse
import glob
import json
import sys
from pathlib import Path

import numpy as np

from naoloc.data.recording import read_recording
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.localization.observations import LineScan
from naoloc.localization.walls import WallMap, wall_map
from naoloc.mapping.map import load_map

RANGES = ((0.0, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 2.5), (2.5, 3.0), (3.0, 4.5))
SAME_DIRECTION_RAD = 0.12  # a line this near a wall's direction is compared with it
NEAR_M = 0.1  # a line this near a wall or front is its foot (the core of the noise)


def _residuals(walls: WallMap, scan: LineScan, pose: np.ndarray) -> list[tuple[float, ...]]:
    """Each line of ``scan`` seen from ``pose``: (distance, residual to the nearest wall or
    front, residual to the wall, direction residual), m and rad."""
    normals = np.concatenate([walls.normals, walls.faces[:, 0]])
    coords = np.concatenate([walls.coords, walls.faces[:, 1]])
    n = np.column_stack([np.cos(normals), np.sin(normals)])
    dist = coords - n @ pose[:2]
    direction = np.angle(np.exp(1j * (normals - pose[2])))
    out = []
    for line in scan.lines:
        turn = np.angle(np.exp(1j * (line.normal - direction)))
        ok = np.flatnonzero(np.abs(turn) < SAME_DIRECTION_RAD)
        if not ok.size:
            continue
        r = line.distance - dist[ok]
        j = int(np.argmin(np.abs(r)))
        walls_r = [float(x) for x, k in zip(r, ok, strict=True) if k < len(walls.normals)]
        out.append((line.distance, float(r[j]), walls_r[0] if walls_r else np.nan,
                    float(turn[ok[j]])))  # fmt: skip
    return out


def collect(folder: Path) -> list[tuple[float, ...]]:
    """Every recorded line's residuals in one evaluation output (checked maps only)."""
    summary = json.loads((folder / "unseen_rooms.json").read_text(encoding="utf-8"))
    checked = {r["seed"] for r in summary["rooms"] if r.get("map_checked")}
    rows: list[tuple[float, ...]] = []
    for room in sorted(glob.glob(str(folder / "room_*"))):
        if int(room.rsplit("_", 1)[-1]) not in checked:
            continue
        walls = wall_map(load_map(f"{room}/maps/akaze-300.npz").meta)
        if walls is None:
            continue
        estimates = json.loads(Path(room, "estimates.json").read_text(encoding="utf-8"))
        truth = {e["index"]: e["truth"] for e in estimates if e["variant"] == "main"}
        for path in sorted(glob.glob(f"{room}/recordings/main_*.mcap")):
            index = int(Path(path).stem.rsplit("_", 1)[-1])
            obs = read_recording(path).observations
            if not obs or index not in truth:
                continue
            end, at_end = obs[-1].odometry, Pose2D(*truth[index])
            for o in obs:
                if isinstance(o, LineScan):
                    t = at_end * (end.inverse() * o.odometry)
                    rows += _residuals(walls, o, np.array([t.x, t.y, t.theta]))
    return rows


def _robust_std(v: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(v - np.median(v)))) if v.size else float("nan")


def main() -> int:
    """Print the line noise per range of distance."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("outs", type=Path, nargs="+", help="eval_unseen_rooms --record outputs")
    args = parser.parse_args()
    rows: list[tuple[float, ...]] = []
    try:
        for folder in args.outs:
            rows += collect(folder)
    except (NaolocError, OSError, KeyError, ValueError) as err:
        print(f"line_noise: {err}", file=sys.stderr)
        return 2
    if not rows:
        print("line_noise: no recorded floor lines", file=sys.stderr)
        return 2
    a = np.array(rows)
    print(f"{len(a)} lines")
    print("range (m) | lines | within 0.1 m | distance median / robust std (m) | "
          "direction robust std (rad) | 0.1-0.5 m before a wall")  # fmt: skip
    for lo, hi in RANGES:
        s = (a[:, 0] >= lo) & (a[:, 0] < hi)
        if not s.any():
            continue
        near = s & (np.abs(a[:, 1]) < NEAR_M)
        wall = a[s, 2][np.isfinite(a[s, 2])]
        before = float(np.mean((wall < -NEAR_M) & (wall > -0.5))) if wall.size else 0.0
        print(f"{lo:.1f}-{hi:.1f} | {int(s.sum())} | {near.sum() / s.sum():.2f} | "
              f"{np.median(a[near, 1]):+.4f} / {_robust_std(a[near, 1]):.4f} | "
              f"{_robust_std(a[near, 3]):.3f} | {before:.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
