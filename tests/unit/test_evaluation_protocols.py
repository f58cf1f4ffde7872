"""Pose sampling of the evaluation protocols, frames, walls and laps."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.errors import ConfigError
from naoloc.evaluation.protocols import (
    PAPER_HEADING_JITTER_RAD,
    PAPER_POSITIONS,
    distance_to_walls,
    lap_of,
    map_to_room,
    paper_poses,
    room_to_map,
    sample_random_poses,
    wall_seen,
)
from naoloc.geometry import Pose2D


def _table(x: float, y: float, clearance: float) -> bool:
    """A room with one 1 x 1 m table centred at (1.5, 1.5)."""
    return not (1.0 - clearance < x < 2.0 + clearance and 1.0 - clearance < y < 2.0 + clearance)


def test_random_poses_stay_in_the_band_and_off_furniture() -> None:
    poses = sample_random_poses(300, 7, (6.0, 5.0), _table)
    assert len(poses) == 300
    for p in poses:
        x, y, theta = p.room_pose
        assert 0.6 <= distance_to_walls(x, y, (6.0, 5.0)) <= 1.4
        assert _table(x, y, 0.25)
        assert -math.pi < theta <= math.pi
    assert len({p.seed for p in poses}) == 300
    assert [p.index for p in poses] == list(range(300))


def test_random_poses_are_seeded_and_spread() -> None:
    a = sample_random_poses(200, 3, (6.0, 6.0), lambda x, y, c: True)
    b = sample_random_poses(200, 3, (6.0, 6.0), lambda x, y, c: True)
    c = sample_random_poses(200, 4, (6.0, 6.0), lambda x, y, c: True)
    assert a == b
    assert a != c
    xy = np.array([p.room_pose[:2] for p in a])
    # Uniform over the band: every side of the room gets poses, headings cover the circle.
    assert (xy[:, 0] < 1.5).sum() > 20 and (xy[:, 0] > 4.5).sum() > 20
    assert (xy[:, 1] < 1.5).sum() > 20 and (xy[:, 1] > 4.5).sum() > 20
    headings = np.array([p.room_pose[2] for p in a])
    assert np.histogram(headings, bins=4, range=(-math.pi, math.pi))[0].min() > 25


def test_random_poses_refuse_impossible_rooms() -> None:
    with pytest.raises(ConfigError, match="-n"):
        sample_random_poses(0, 0, (6.0, 6.0), lambda x, y, c: True)
    with pytest.raises(ConfigError, match="no floor"):
        sample_random_poses(3, 0, (1.0, 6.0), lambda x, y, c: True)
    with pytest.raises(ConfigError, match="free poses"):
        sample_random_poses(3, 0, (6.0, 6.0), lambda x, y, c: False, max_draws=500)


def test_paper_poses_land_on_table3_positions_in_the_map_frame() -> None:
    origin = (1.0, 1.0, 0.3)
    poses = paper_poses(origin, 5)
    assert len(poses) == 4 * 5
    for pos in PAPER_POSITIONS:
        mine = [p for p in poses if p.group == pos.number]
        assert len(mine) == 5
        for p in mine:
            m = room_to_map(origin, p.room_pose)
            assert m.x == pytest.approx(pos.x, abs=1e-9)
            assert m.y == pytest.approx(pos.y, abs=1e-9)
            dh = math.remainder(m.theta - pos.heading, 2 * math.pi)
            assert abs(dh) <= PAPER_HEADING_JITTER_RAD + 1e-9
        assert len({p.room_pose[2] for p in mine}) == 5  # the evaluations differ
    assert paper_poses(origin, 5) == poses


def test_paper_figures() -> None:
    errs = [p.paper_mean_error_m() for p in PAPER_POSITIONS]
    assert errs[0] > 1.0 and errs[2] > 1.3  # the paper's two bad positions
    assert errs[3] < 0.15


def test_room_map_round_trip() -> None:
    origin = (1.2, 0.8, 0.4)
    pose = Pose2D(0.5, -0.3, 1.0)
    room = map_to_room(origin, pose)
    back = room_to_map(origin, (room.x, room.y, room.theta))
    assert back.x == pytest.approx(pose.x) and back.y == pytest.approx(pose.y)
    assert back.theta == pytest.approx(pose.theta)


def test_wall_seen_numbers_walls_counter_clockwise() -> None:
    size = (6.0, 4.0)
    assert wall_seen((3.0, 1.0, 0.0), -math.pi / 2, size) == 1
    assert wall_seen((3.0, 1.0, 0.0), 0.0, size) == 2
    assert wall_seen((3.0, 1.0, 0.0), math.pi / 2, size) == 3
    assert wall_seen((3.0, 1.0, 0.0), math.pi, size) == 4
    assert wall_seen((5.5, 1.0, 0.0), math.radians(45), size) == 2  # the x = 6 wall is nearer


def test_lap_of_counts_path_length() -> None:
    # Two laps of a 1 x 1 square in 0.5 m steps: 8 poses per lap.
    pts = []
    for _ in range(2):
        for x, y in [(0.5, 0), (1, 0), (1, 0.5), (1, 1), (0.5, 1), (0, 1), (0, 0.5), (0, 0)]:
            pts.append((x, y, 0.0))
    laps = lap_of(np.array(pts), 4.0, 2)
    assert laps.tolist() == [1] * 8 + [2] * 8
