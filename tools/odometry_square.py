"""Odometry against the truth on a NAO-like walk: a 2 m square and a 2 m straight line.

For odometry seeds 1-5 (``world.odometry.seed``), in the default world (profile ``nao``)
or with ``--profile ideal``, prints one row per seed:

- the end error of the sensor odometry (``getRobotPosition(True)``) against the true pose
  after four ``moveTo(2, 0, 0)`` legs and four ``moveTo(0, 0, pi/2)`` quarter turns, in
  metres and degrees (both measured in the start frame);
- after a fresh ``moveTo(2, 0, 0)``: what the odometry reads and the true distance walked.

Then the medians. Acceptance of issue 11: profile nao, median end error 0.10-1 m and at
least 2 deg; profile ideal under 1 cm; the true 2 m differs by at least 0.5 % in 3 of 5 seeds.

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/odometry_square.py [--backend mujoco|fake]
        [--profile nao|ideal] [--seeds 1 2 3 4 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import naoloc
from naoloc.geometry import Pose2D, modulo2PI, relative_pose
from naoloc.robot import pose_of


def _config(backend: str, profile: str, seed: int) -> dict[str, Any]:
    return {
        "robot": {"backend": backend},
        "world": {
            "odometry": {"profile": profile, "seed": seed},
            "room": {"furniture": False},
            "start_pose": [1.0, 1.0, 0.0],
        },
    }


def square(backend: str, profile: str, seed: int) -> dict[str, float]:
    """Walk the square and the line for one seed; errors in m and deg."""
    with naoloc.connect(_config(backend, profile, seed)) as robot:
        assert robot.sim is not None
        truth0, odo0 = Pose2D(*robot.sim.true_pose()), pose_of(robot.motion, True)
        for _ in range(4):
            robot.motion.moveTo(2.0, 0.0, 0.0)
            robot.motion.moveTo(0.0, 0.0, math.pi / 2)
        truth = relative_pose(truth0, Pose2D(*robot.sim.true_pose()))
        odo = relative_pose(odo0, pose_of(robot.motion, True))
    with naoloc.connect(_config(backend, profile, seed)) as robot:
        assert robot.sim is not None
        start = Pose2D(*robot.sim.true_pose())
        robot.motion.moveTo(2.0, 0.0, 0.0)
        line_odo = pose_of(robot.motion, True).x
        line_true = relative_pose(start, Pose2D(*robot.sim.true_pose()))
    return {
        "seed": seed,
        "end_error_m": math.hypot(odo.x - truth.x, odo.y - truth.y),
        "heading_error_deg": abs(math.degrees(modulo2PI(odo.theta - truth.theta))),
        "line_odometry_m": line_odo,
        "line_true_m": math.hypot(line_true.x, line_true.y),
    }


def main() -> None:
    """Print the table (and optionally the JSON) for the chosen backend and profile."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--backend", default="mujoco", choices=["mujoco", "fake"])
    ap.add_argument("--profile", default="nao", choices=["nao", "ideal"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = [square(args.backend, args.profile, s) for s in args.seeds]
    print(f"backend {args.backend}, odometry profile {args.profile}")
    print("seed  end error m  heading deg  line odometry m  line true m  line diff %")
    for r in rows:
        diff = 100 * (r["line_true_m"] - 2.0) / 2.0
        print(
            f"{r['seed']:4d}  {r['end_error_m']:11.3f}  {r['heading_error_deg']:11.2f}  "
            f"{r['line_odometry_m']:15.4f}  {r['line_true_m']:11.4f}  {diff:+11.2f}"
        )
    summary = {
        "backend": args.backend,
        "profile": args.profile,
        "median_end_error_m": statistics.median(r["end_error_m"] for r in rows),
        "median_heading_error_deg": statistics.median(r["heading_error_deg"] for r in rows),
        "line_off_by_0_5pct": sum(abs(r["line_true_m"] - 2.0) >= 0.01 for r in rows),
    }
    print(
        f"median end error {summary['median_end_error_m']:.3f} m, median heading error "
        f"{summary['median_heading_error_deg']:.2f} deg, true 2 m off by >= 0.5 % in "
        f"{summary['line_off_by_0_5pct']} of {len(rows)} seeds"
    )
    if args.json:
        print(json.dumps({**summary, "rows": rows}))


if __name__ == "__main__":
    main()
