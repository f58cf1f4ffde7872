"""``naoloc demo [-o OUTDIR] [-c CFG]``: survey -> build map -> localize at several poses.

Runs in one simulated robot (the default paper room): the survey is written to
``OUTDIR/survey.mcap``, the map to ``OUTDIR/map.npz`` (and ``map.png``), then the robot is
teleported to the paper's Table 3 positions (scaled to the survey rectangle) and to two
seeded random poses 0.6-1.4 m from the walls, and localized at each. A table of truth,
estimate and error is printed, and a picture of all estimates is written.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import Config
from naoloc.errors import BackendError
from naoloc.geometry import Pose2D
from naoloc.robot import Robot

# The paper's Table 3 positions in the map frame, as fractions of the 4 x 4 m survey square.
TABLE3_FRACTIONS: tuple[tuple[float, float], ...] = ((0.875, 0.125), (0, 0), (0.125, 0.875), (1, 1))


def demo_poses(robot: Robot, meta: dict[str, Any], sides: tuple[float, float], seed: int = 0,
               extra: int = 2) -> list[Pose2D]:  # fmt: skip
    """Demo test poses in the room frame: Table 3's (scaled) plus ``extra`` random ones.

    Args:
        robot: A simulated robot (``robot.sim`` answers room size and free space).
        meta: Survey meta with ``origin_room_pose`` and ``direction``.
        sides: Survey rectangle sides, m.
        seed: Seed of headings and random positions.
        extra: Random poses 0.6-1.4 m from the nearest wall, on free floor.

    Returns:
        Poses (x, y m; theta rad) in the room frame.
    """
    if robot.sim is None or meta.get("origin_room_pose") is None:
        raise BackendError("the demo needs a simulated robot (world.* config, mujoco or fake)")
    rng = np.random.default_rng(seed)
    origin = Pose2D.from_list(meta["origin_room_pose"])
    turn = 1.0 if meta.get("direction", "ccw") == "ccw" else -1.0
    poses: list[Pose2D] = []
    for fx, fy in TABLE3_FRACTIONS:
        p = origin * Pose2D(
            fx * sides[0], turn * fy * sides[1], float(rng.uniform(-math.pi, math.pi))
        )
        poses.append(p.normalized())
    sx, sy = robot.sim.room_size()
    tries = 0
    while len(poses) < len(TABLE3_FRACTIONS) + extra and tries < 10000:
        tries += 1
        x, y = float(rng.uniform(0, sx)), float(rng.uniform(0, sy))
        wall = min(x, y, sx - x, sy - y)
        if 0.6 <= wall <= 1.4 and robot.sim.is_free(x, y, 0.3):
            poses.append(Pose2D(x, y, float(rng.uniform(-math.pi, math.pi))))
    return poses


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Survey, build the map and localize at several poses; print a table and summarize."""
    from naoloc.behaviours.localize import localize
    from naoloc.cli import write_resolved_config
    from naoloc.commands.build_map import build_from_dataset
    from naoloc.commands.survey import interruptible, record_survey
    from naoloc.plots import plot_estimates
    from naoloc.progress import Progress
    from naoloc.registry import connect

    t0 = time.monotonic()
    out: Path = args.output
    out.mkdir(parents=True, exist_ok=True)
    dataset, map_path = out / "survey.mcap", out / "map.npz"
    rows: list[dict[str, Any]] = []
    with interruptible(), connect(cfg) as robot:
        room = cfg.world.room
        print(
            f"demo: backend {robot.backend}, room {room.size_m[0]:g} x {room.size_m[1]:g} m "
            f"(seed {room.seed}), map {cfg.map.features} {cfg.map.neurons} neurons, "
            f"localize mode {cfg.localize.mode}",
            flush=True,
        )
        with Progress(None, "survey") as bar:
            surveyed, frames = record_survey(robot, cfg, dataset, bar)
        print(
            f"demo: survey {frames} frames, {surveyed.laps} laps, {surveyed.path_m:.1f} m, "
            f"{surveyed.wall_s:.1f} s -> {dataset}"
        )
        vmap, built = build_from_dataset(dataset, cfg, map_path)
        print(
            f"demo: map {built['neurons']} neurons, {built['distinct_poses']} distinct poses, "
            f"{built['total_s']:.1f} s -> {map_path}"
        )
        poses = demo_poses(robot, surveyed.meta, cfg.survey_sides(), seed=cfg.map.seed)
        pairs: list[tuple[Pose2D, Pose2D | None]] = []
        for i, pose in enumerate(poses):
            robot.sim.teleport(*pose)  # type: ignore[union-attr]  # demo_poses checked sim
            loc = localize(robot, vmap, cfg)
            est = loc.estimate
            pairs.append((Pose2D(est.x, est.y, est.theta), loc.truth))
            truth = loc.truth
            rows.append(
                {
                    "truth": None if truth is None else [round(v, 3) for v in truth],
                    "estimate": [round(est.x, 3), round(est.y, 3), round(est.theta, 3)],
                    "error_m": _rounded(loc.error_m, 3),
                    "heading_error_deg": _rounded(loc.heading_error_deg, 2),
                    "confidence": round(float(est.confidence), 3),
                    "localize_s": round(loc.wall_s, 3),
                }
            )
            err = math.nan if loc.error_m is None else loc.error_m
            print(f"demo: pose {i + 1}/{len(poses)}: error {err:.2f} m", flush=True)
    png = plot_estimates(vmap, pairs, out / "localize.png")
    write_resolved_config(cfg, out / "config.yaml")  # with the outputs it describes
    _print_table(rows)
    errors = [r["error_m"] for r in rows if r["error_m"] is not None]
    headings = [r["heading_error_deg"] for r in rows if r["heading_error_deg"] is not None]
    summary = {
        "backend": cfg.robot.backend,
        "frames": frames,
        "images": built["images"],
        "neurons": built["neurons"],
        "distinct_poses": built["distinct_poses"],
        "map_build_s": built["total_s"],
        "n": len(rows),
        "median_error_m": round(statistics.median(errors), 3) if errors else None,
        "max_error_m": round(max(errors), 3) if errors else None,
        "median_heading_error_deg": round(statistics.median(headings), 2) if headings else None,
        "localize_s_median": round(statistics.median(r["localize_s"] for r in rows), 3),
        "wall_s": round(time.monotonic() - t0, 1),
        "dataset": str(dataset),
        "map": str(map_path),
        "png": str(png),
        "positions": rows,
    }
    return summary


def _rounded(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


def _nan(value: float | None) -> float:
    return math.nan if value is None else value


def _print_table(rows: list[dict[str, Any]]) -> None:
    print(f"{'#':>2}  {'truth (map frame)':>24}  {'estimate':>24}  {'error m':>8}  {'head deg':>8}")
    for i, r in enumerate(rows):
        t, e = r["truth"] or [math.nan] * 3, r["estimate"]
        print(
            f"{i + 1:>2}  ({t[0]:6.2f}, {t[1]:6.2f}, {t[2]:5.2f})  "
            f"({e[0]:6.2f}, {e[1]:6.2f}, {e[2]:5.2f})  {_nan(r['error_m']):8.2f}  "
            f"{_nan(r['heading_error_deg']):8.1f}"
        )
