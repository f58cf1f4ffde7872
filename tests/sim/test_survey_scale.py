"""Metric scale: a 3 % odometry scale error no longer shows in the built map.

The survey walks on odometry that reads 3 % long (other odometry noise small). Two ways
to metric keyframes are checked on it: the default wall-referenced poses (the known
circuit and the floor-wall lines, :mod:`naoloc.mapping.wall_poses`) and the floor-line metric
scale (``map.apply_metric_scale``: the front wall's distances, camera height from the
kinematics). Either way the map's keyframe distances match the simulator's truth.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

import naoloc
from naoloc.app.commands.build_map import build_from_dataset
from naoloc.config import Config, load_config
from naoloc.data.dataset import read_dataset
from naoloc.data.recorder import record_survey
from naoloc.geometry import Pose2D
from naoloc.mapping.from_survey import apply_metric_scale


def _path_length(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T)))


def _config(wall_poses: bool) -> Config:
    return load_config(
        {
            "robot": {"backend": "mujoco"},
            "world": {
                # The world the scale measurement was built in (posters, a clean camera):
                # in home rooms with NAO's lens it is not yet reliable (docs/history/RESULTS.md).
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
            "map": {
                "neurons": 20,
                "epochs": 10,
                "seed": 0,
                "apply_metric_scale": True,
                "wall_poses": wall_poses,
            },
        }
    )


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cfg = _config(False)
    path = tmp_path_factory.mktemp("scale") / "s.mcap"
    with naoloc.connect(cfg) as robot:
        result, frames = record_survey(robot, cfg, path)
    assert frames == result.frames > 40  # two laps, as the paper surveys
    return path


def test_wall_poses_take_the_scale_error_out_of_the_map(dataset: Path, tmp_path: Path) -> None:
    cfg = _config(True)
    data = read_dataset(dataset)
    truth = np.array([kf.true_pose.to_list() for kf in data.keyframes])
    vmap, summary = build_from_dataset(dataset, cfg, tmp_path / "m.npz", show_progress=False)
    assert summary["metric_scale"] is None
    assert summary["wall_poses"]["sides_with_corner"] == 8
    poses = np.asarray(vmap.keyframe_poses)[: vmap.wall_images]  # the far pictures follow
    assert _path_length(poses) / _path_length(truth) == pytest.approx(1.0, abs=0.01)
    i, j = 0, len(poses) // 4
    d_map = math.dist(poses[i, :2], poses[j, :2])
    assert d_map / math.dist(truth[i, :2], truth[j, :2]) == pytest.approx(1.0, abs=0.01)
    origin = Pose2D(*data.meta["origin_room_pose"])
    in_map = np.array([(origin.inverse() * kf.true_pose).to_list() for kf in data.keyframes])
    errors = np.hypot(*(poses[:, :2] - in_map[:, :2]).T)
    assert float(np.median(errors)) < 0.05
    raw = np.array([kf.pose.to_list() for kf in data.keyframes])
    assert float(np.median(np.hypot(*(raw[:, :2] - in_map[:, :2]).T))) > float(np.median(errors))


def test_floor_line_scale_takes_the_scale_error_out_of_the_map(
    dataset: Path, tmp_path: Path
) -> None:
    cfg = _config(False)
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
    poses = np.asarray(vmap.keyframe_poses)[: vmap.wall_images]  # the far pictures follow
    # the floor-line scale reads about 1 % low (its front lines read 1-2 cm short at 2 m):
    # 0.990 on main at d4539f2, 0.989 with issue 31's survey; the raw odometry errs 3 %
    assert _path_length(poses) / _path_length(truth) == pytest.approx(1.0, abs=0.012)
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
