"""Metric scale recovery: odometry with a known distance scale error, the map against truth.

For each ``--scale-errors`` value e (odometry reads ``1 + e`` times the true distance), runs
a two-lap survey on MuJoCo (4.2 x 3.8 m room, other odometry noise small, as the test in
tests/test_survey_scale.py), builds the map, and prints: the survey's ``metric_scale``
against the truth ``1 / (1 + e)``, and the ratio of the keyframes' path length to the true
one before (raw odometry) and after (the built map's keyframe poses). With ``--honest``
the odometry keeps the ``nao`` profile's noise (random walks, slip) besides e.

Usage:
    MUJOCO_GL=egl PYTHONPATH=. .venv/bin/python tools/survey_scale.py
        [--scale-errors 0.03 -0.05] [--honest]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

import naoloc
from naoloc.app.commands.build_map import build_from_dataset
from naoloc.config import load_config
from naoloc.data.dataset import read_dataset
from naoloc.data.recorder import record_survey


def _path(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T)))


def run(error: float, honest: bool, seed: int = 1) -> dict[str, float | None]:
    """One survey and map; the figures."""
    odometry: dict[str, float | str] = {"profile": "nao", "seed": seed, "scale_error": error}
    if not honest:
        odometry.update(
            turn_scale_error=0.0, heading_bias_rad_per_m=0.0, random_walk_m_per_sqrt_m=0.002,
            heading_random_walk_rad_per_sqrt_m=0.001, heading_random_walk_rad_per_sqrt_rad=0.001,
            turn_slip_m_per_sqrt_rad=0.001,
        )  # fmt: skip
    cfg = load_config(
        {
            "robot": {"backend": "mujoco"},
            "world": {
                "room": {"size_m": [4.2, 3.8], "seed": 5, "furniture": False},
                "odometry": odometry,
            },
            "survey": {"laps": 2, "step_m": 0.2, "wall_offset_m": 1.0, "head_yaw_rad": -1.5708},
            "map": {"neurons": 20, "epochs": 10, "seed": 0},
        }
    )
    with tempfile.TemporaryDirectory() as tmp:
        dataset = Path(tmp) / "s.mcap"
        with naoloc.connect(cfg) as robot:
            record_survey(robot, cfg, dataset)
        data = read_dataset(dataset)
        truth = np.array([kf.true_pose.to_list() for kf in data.keyframes if kf.true_pose])
        raw = np.array([kf.pose.to_list() for kf in data.keyframes])
        vmap, _ = build_from_dataset(dataset, cfg, Path(tmp) / "m.npz", show_progress=False)
        built = np.asarray(vmap.keyframe_poses)[: vmap.wall_images]  # the walk
    scale = data.meta.get("metric_scale")
    return {
        "scale_error": error,
        "metric_scale": None if scale is None else round(float(scale), 4),
        "truth": round(1.0 / (1.0 + error), 4),
        "raw_path_ratio": round(_path(raw) / _path(truth), 4),
        "map_path_ratio": round(_path(built) / _path(truth), 4),
    }


def main() -> None:
    """Print one row per scale error."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scale-errors", type=float, nargs="+", default=[0.03, -0.05])
    ap.add_argument("--honest", action="store_true")
    args = ap.parse_args()
    print("scale_error | metric_scale | truth 1/(1+e) | raw path / true | map path / true")
    for e in args.scale_errors:
        r = run(e, args.honest)
        keys = ("scale_error", "metric_scale", "truth", "raw_path_ratio", "map_path_ratio")
        print(" | ".join(str(r[k]) for k in keys), flush=True)


if __name__ == "__main__":
    main()
