"""Small rooms and blocked walks in MuJoCo, the default honest world (issue 31).

- A 3 x 3 m home surveyed 0.5 m from its walls (a child's room): the survey finds the wall
  beside it although the robot's arm hides the floor there, walks both laps, and the map
  frame its wall poses give passes build-map's checks and matches the truth.
- A robot started 1.5 m before a wall, with a 3 m first side configured: the survey stops
  in one line before it presses into the wall, its partial dataset kept, incomplete.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

import naoloc
from naoloc.config import Config, load_config
from naoloc.data.dataset import partial_path_for, read_dataset
from naoloc.data.recorder import record_survey
from naoloc.errors import SurveyBlocked
from naoloc.geometry import Pose2D
from naoloc.mapping.checks import failed
from naoloc.mapping.from_survey import pose_survey, run_checks


def _config(
    size: tuple[float, float], start: tuple[float, float, float], **survey: object
) -> Config:
    return load_config(
        {
            "robot": {"backend": "mujoco"},
            "world": {
                "room": {"size_m": list(size), "seed": 31, "style": "home"},
                "sim": {"light": 0.6},
                "start_pose": list(start),
            },
            "survey": {"laps": 2, "step_m": 0.2, "wall_offset_m": 0.5, **survey},
        }
    )


@pytest.mark.slow
def test_a_3_by_3_m_room_surveys_and_maps_at_half_a_metre(tmp_path: Path) -> None:
    cfg = _config((3.0, 3.0), (0.5, 0.5, 0.0))
    path = tmp_path / "s.mcap"
    with naoloc.connect(cfg) as robot:
        result, frames = record_survey(robot, cfg, path)
    assert result.laps == 2 and frames > 50
    assert result.yaw_source == "floorline" and result.meta["direction"] == "ccw"  # wall right
    data = read_dataset(path)
    assert data.complete
    keyframes, _, walled = pose_survey(data, cfg.map)
    checks = run_checks(data, cfg.map, walled)
    assert not failed(checks), [c.line() for c in checks]
    # the map frame against the truth: the survey's own start, in the map frame
    origin = Pose2D.from_list(data.meta["origin_room_pose"])
    truth = np.array([(origin.inverse() * kf.true_pose).to_list() for kf in data.keyframes])
    mine = np.array([kf.pose.to_list() for kf in keyframes])
    errors = np.hypot(*(mine[:, :2] - truth[:, :2]).T)
    assert float(np.median(errors)) < 0.06
    heading = np.abs(np.remainder(mine[:, 2] - truth[:, 2] + math.pi, 2 * math.pi) - math.pi)
    assert float(np.median(heading)) < math.radians(1.5)
    # the robot kept clear of the walls all the way (the arm's side included)
    assert all(min(kf.true_pose.x, kf.true_pose.y, 3 - kf.true_pose.x, 3 - kf.true_pose.y) > 0.35
               for kf in data.keyframes)  # fmt: skip


def test_a_wall_in_the_way_stops_the_survey_before_the_robot_presses_into_it(
    tmp_path: Path,
) -> None:
    cfg = _config((4.0, 3.0), (2.0, 0.5, 0.0), side_m=[3.0, 2.0], laps=1)
    path = tmp_path / "s.mcap"
    with naoloc.connect(cfg) as robot:
        with pytest.raises(SurveyBlocked, match=r"^blocked on side 1 of lap 1 after") as info:
            record_survey(robot, cfg, path)
        assert robot.sim is not None
        x, _, _ = robot.sim.true_pose()
        assert not robot.motion.moveIsActive()
    assert "the wall ahead is" in str(info.value)
    assert 4.0 - x > 0.2  # stopped before its body (0.15 m) met the wall
    data = read_dataset(partial_path_for(path))
    assert not data.complete and data.meta["reason"].startswith("blocked on side 1")
    assert not path.exists()
