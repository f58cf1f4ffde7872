"""How well the survey keeps its circuit on a NAO's odometry: drift, closure, wall distance.

For odometry seeds 1-5 (``world.odometry.seed``, profile ``nao``, the default honest world)
in ``configs/sim_paper_room.yaml``, runs the survey (``naoloc.behaviours.survey``, head yaw
from the room's layout as ``naoloc survey`` does on simulators) and prints one row per seed:

- ``drift``: the last keyframe's odometry pose against its true pose (both in the map
  frame: the truth is taken relative to the true start), m and deg;
- ``closure``: where the robot truly ends against where it truly started, m and deg (a
  closed circuit ends where it began);
- ``wall``: mean and max of |distance to the nearest wall - survey.wall_offset_m| over the
  keyframes (truth), and the nearest any keyframe came to a wall, m;
- ``scale``: the survey's ``metric_scale`` (metres per odometry metre, None when not
  measured) and the true one (true path / odometry path between keyframes).

Runs the code on ``PYTHONPATH``: point it at another checkout to measure that one (this is
how docs/history/RESULTS.md's "before" column was taken, from main's tree).

Usage:
    MUJOCO_GL=egl PYTHONPATH=. .venv/bin/python tools/survey_wall_follow.py
        [--config configs/sim_paper_room.yaml] [--seeds 1 2 3 4 5] [--laps 2] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import naoloc
from naoloc.behaviours import survey
from naoloc.behaviours.nearest_wall import nearest_side_in_room
from naoloc.config import load_config
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.robot.keyframe import Keyframe


def run(config: Path, seed: int, laps: int) -> dict[str, Any]:
    """One survey; the row's figures (m, deg)."""
    raw = load_config(config).to_dict()
    raw["world"]["odometry"] = {"profile": "nao", "seed": seed}
    raw["survey"]["laps"] = laps
    cfg = load_config(raw)
    frames: list[Keyframe] = []
    row: dict[str, Any] = {"seed": seed}
    t0 = time.monotonic()
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        size = robot.sim.room_size()
        start = Pose2D.from_list(robot.sim.true_pose())
        side = nearest_side_in_room(size, start.to_list())
        try:
            res = survey(robot, cfg, lambda kf, lap, odo: frames.append(kf), head_yaw=side.head_yaw)
            row.update(frames=res.frames, laps=res.laps, error=None)
            meta = res.meta
        except Exception as err:  # a survey that walked into a wall is a result here
            row.update(frames=len(frames), laps=None, error=f"{type(err).__name__}: {err}")
            meta = {}
        end = Pose2D.from_list(robot.sim.true_pose())
    row["wall_s"] = round(time.monotonic() - t0, 1)
    if not frames:
        return row
    last = frames[-1]
    assert last.true_pose is not None
    truth = relative_pose(start, last.true_pose)
    row["drift_m"] = round(math.hypot(last.pose.x - truth.x, last.pose.y - truth.y), 3)
    row["drift_deg"] = round(abs(math.degrees(modulo2PI(last.pose.theta - truth.theta))), 1)
    row["closure_m"] = round(math.hypot(end.x - start.x, end.y - start.y), 3)
    row["closure_deg"] = round(abs(math.degrees(modulo2PI(end.theta - start.theta))), 1)
    offset = cfg.survey.wall_offset_m
    walls = []
    for kf in frames:
        assert kf.true_pose is not None
        x, y = kf.true_pose.x, kf.true_pose.y
        walls.append(min(x, y, size[0] - x, size[1] - y))
    dev = np.abs(np.asarray(walls) - offset)
    row["wall_dev_mean_m"] = round(float(dev.mean()), 3)
    row["wall_dev_max_m"] = round(float(dev.max()), 3)
    row["nearest_wall_m"] = round(float(min(walls)), 3)
    odo = np.array([kf.pose.to_list() for kf in frames])[:, :2]
    tru = np.array([kf.true_pose.to_list() for kf in frames if kf.true_pose])[:, :2]
    path_odo = float(np.sum(np.hypot(*np.diff(odo, axis=0).T)))
    path_true = float(np.sum(np.hypot(*np.diff(tru, axis=0).T)))
    row["true_scale"] = round(path_true / path_odo, 4) if path_odo > 0 else None
    scale = meta.get("metric_scale")
    row["metric_scale"] = None if scale is None else round(float(scale), 4)
    return row


def main() -> None:
    """Print the table (and optionally the JSON)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--config", type=Path, default=Path("configs/sim_paper_room.yaml"))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--laps", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = []
    cols = [
        "seed", "frames", "drift_m", "drift_deg", "closure_m", "closure_deg",
        "wall_dev_mean_m", "wall_dev_max_m", "nearest_wall_m", "metric_scale", "true_scale",
        "error",
    ]  # fmt: skip
    print(" | ".join(cols))
    for seed in args.seeds:
        row = run(args.config, seed, args.laps)
        rows.append(row)
        print(" | ".join(str(row.get(c, "-")) for c in cols), flush=True)
    for key in ("drift_m", "closure_m", "wall_dev_mean_m", "wall_dev_max_m"):
        vals = [r[key] for r in rows if r.get(key) is not None]
        if vals:
            print(f"median {key}: {statistics.median(vals):.3f}")
    errs = [
        abs(r["metric_scale"] / r["true_scale"] - 1)
        for r in rows
        if r.get("metric_scale") and r.get("true_scale")
    ]
    if errs:
        print(f"median |metric_scale / true_scale - 1|: {100 * statistics.median(errs):.1f} %")
    if args.json:
        print(json.dumps(rows))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
