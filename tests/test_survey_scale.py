"""Metric scale: a 3 % odometry scale error no longer shows in the built map.

The survey walks on odometry that reads 3 % long (other odometry noise small); the
floor-wall line of the front wall gives metric distances (camera height from the
kinematics), build-map scales the keyframe poses, and the map's keyframe distances then
match the simulator's truth within 1 %.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

import naoloc
from naoloc.commands.build_map import apply_metric_scale, build_from_dataset
from naoloc.commands.survey import record_survey
from naoloc.config import load_config
from naoloc.dataset import read_dataset


def _path_length(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T)))


def test_three_percent_scale_error_is_gone_from_the_map(tmp_path: Path) -> None:
    cfg = load_config(
        {
            "robot": {"backend": "mujoco"},
            "world": {
                # The world the scale measurement was built in (posters, a clean camera):
                # in home rooms with NAO's lens it is not yet reliable (docs/RESULTS.md).
                "room": {"size_m": [4.2, 3.8], "seed": 5, "furniture": False, "style": "posters"},
                "camera_realism": {"profile": "ideal"},
                "odometry": {
                    "profile": "nao",
                    "seed": 1,
                    "scale_error": 0.03,
                    "turn_scale_error": 0.0,
                    "heading_bias_rad_per_m": 0.0,
                    "random_walk_m_per_sqrt_m": 0.002,
                    "heading_random_walk_rad_per_sqrt_m": 0.001,
                    "heading_random_walk_rad_per_sqrt_rad": 0.001,
                    "turn_slip_m_per_sqrt_rad": 0.001,
                },
            },
            "survey": {"laps": 2, "step_m": 0.2, "wall_offset_m": 1.0, "head_yaw_rad": -1.5708},
            "map": {"neurons": 20, "epochs": 10, "seed": 0, "apply_metric_scale": True},
        }
    )
    dataset = tmp_path / "s.mcap"
    with naoloc.connect(cfg) as robot:
        result, frames = record_survey(robot, cfg, dataset)
    assert frames == result.frames > 40  # two laps, as the paper surveys
    data = read_dataset(dataset)
    scale = data.meta["metric_scale"]
    assert scale == pytest.approx(1 / 1.03, rel=0.01)
    truth = np.array([kf.true_pose.to_list() for kf in data.keyframes])
    raw = np.array([kf.pose.to_list() for kf in data.keyframes])
    assert _path_length(raw) / _path_length(truth) == pytest.approx(1.03, rel=0.01)  # the error
    kept, applied = apply_metric_scale(data.keyframes, data.meta)
    assert applied == scale
    vmap, summary = build_from_dataset(dataset, cfg, tmp_path / "m.npz", show_progress=False)
    assert summary["metric_scale"] == pytest.approx(scale)
    assert vmap.meta["metric_scale"] == pytest.approx(scale)
    poses = np.asarray(vmap.keyframe_poses)
    assert _path_length(poses) / _path_length(truth) == pytest.approx(1.0, abs=0.01)
    # distances between keyframes far apart along the circuit, not only the path length
    i, j = 0, len(poses) // 4  # the start and the far side of the first lap
    d_map = math.dist(poses[i, :2], poses[j, :2])
    d_true = math.dist(truth[i, :2], truth[j, :2])
    assert d_map / d_true == pytest.approx(1.0, abs=0.01)
    # the robot kept its distance to the walls (the truth knows the room)
    sx, sy = 4.2, 3.8
    walls = [min(x, y, sx - x, sy - y) for x, y, _ in truth]
    assert max(abs(w - 1.0) for w in walls) < 0.15
    assert len(kept) == len(data.keyframes)
