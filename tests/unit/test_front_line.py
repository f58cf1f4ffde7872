"""Which floor line ahead ends a side: across the robot's way, and not the floor's seam.

Tables, not simulations: the lines are what the detector returns (FRAME_ROBOT), and the
head is the fake backend's (its HeadPitch says which view the eye is looking through).
"""

from __future__ import annotations

import math

import pytest

import naoloc
from naoloc.behaviours.survey import trusted_front
from naoloc.behaviours.wall_follow import (
    FRONT_NEAR_PITCH,
    FRONT_PITCH,
    HEAD_HEIGHT_M,
    heading_views,
    measure_front,
)
from naoloc.config import load_config
from naoloc.constants import BOTTOM_CAMERA_IN_HEAD
from naoloc.perception.floorline import WallLine
from naoloc.perception.wall_gate import crosses_path


def _line(distance: float, normal: float, ends: tuple[float, float] | None) -> WallLine:
    return WallLine(distance, normal, 100, 1.0, 0.003, 1.0, ends)


@pytest.mark.parametrize(
    ("distance", "normal", "ends", "crosses"),
    [
        (1.0, 0.0, (-1.0, 1.0), True),  # a wall across the way
        (1.0, 0.0, (-1.4, -0.4), False),  # a table's face 0.4-1.4 m to the right
        (1.0, 0.0, (0.35, 1.2), False),  # a cabinet's face to the left
        (1.0, 0.0, (-0.15, 0.1), True),  # a chair's leg in the way
        (1.0, 0.0, None, True),  # ends unknown: taken to cross
        (1.0, 0.3, (-0.6, -0.2), True),  # a slanted wall: the way meets it at -0.31 m
        (1.0, 0.3, (0.0, 0.5), False),  # the slanted line's part left of the way
        (0.8, 1.4, (-3.0, -2.0), True),  # a line along the way (a side wall): not judged
    ],
)
def test_a_line_ahead_crosses_the_way_where_its_inliers_lie(
    distance: float, normal: float, ends: tuple[float, float] | None, crosses: bool
) -> None:
    assert crosses_path(_line(distance, normal, ends)) is crosses


def test_a_face_beside_the_way_is_not_the_corner() -> None:
    wall = _line(1.6, 0.0, (-1.1, 0.6))
    assert trusted_front(wall, 1.0, 0.7, 4.0) is wall
    assert trusted_front(_line(1.6, 0.0, (-1.4, -0.41)), 1.0, 0.7, 4.0) is None


class _Eye:
    """The bottom camera's lines per head pitch, as the detector returns them."""

    def __init__(self, robot: naoloc.Robot, by_pitch: dict[float, list[WallLine]]) -> None:
        self.robot, self.by_pitch, self.last_pitch = robot, by_pitch, None

    def candidates(self, normal: float, tolerance: float = 0.5, blur: int = 0) -> list[WallLine]:
        pitch = self.robot.motion.getAngles("HeadPitch", True)[0]
        for p, lines in self.by_pitch.items():
            if abs(p - pitch) < 0.02:
                return [ln for ln in lines if abs(ln.normal - normal) <= tolerance]
        return []


@pytest.fixture
def robot() -> naoloc.Robot:
    with naoloc.connect(load_config({"robot": {"backend": "fake"}})) as r:
        yield r


def test_a_seam_nearer_than_a_wall_the_head_up_view_saw_is_no_front(
    robot: naoloc.Robot,
) -> None:
    wall = _line(2.6, 0.05, (-1.6, 0.6))  # head up: the wall, beyond the trusted range
    seam = _line(0.87, 0.18, (-0.65, 0.28))  # level: a plank's seam
    eye = _Eye(robot, {FRONT_PITCH: [wall], FRONT_NEAR_PITCH: [seam]})
    always = lambda line: True  # noqa: E731
    near_only = lambda line: line.distance <= 2.2  # noqa: E731
    assert measure_front(robot, eye, 2.9, near_only) is None  # type: ignore[arg-type]
    assert measure_front(robot, eye, 2.9, always) is wall  # type: ignore[arg-type]
    assert eye.last_pitch == FRONT_PITCH
    # the level view first (the corner expected near): its line is not judged by the other
    assert measure_front(robot, eye, 0.5, near_only) is seam  # type: ignore[arg-type]
    # a view's best line is judged, not the one behind it (a second line is most often
    # a rug's edge or a piece of furniture's foot partly across the way)
    chair = _line(0.9, 0.0, (-0.1, 0.3))
    far_wall = _line(1.9, 0.0, (-1.0, 1.0))
    eye = _Eye(robot, {FRONT_PITCH: [far_wall, chair]})
    assert measure_front(robot, eye, 1.9, lambda line: line.distance > 1.5) is far_wall  # type: ignore[arg-type]
    assert measure_front(robot, eye, 1.9, lambda line: line.distance < 1.5) is None  # type: ignore[arg-type]


@pytest.mark.parametrize("offset", [0.5, 0.65, 0.8, 1.0, 1.2])
def test_the_start_heading_views_look_at_the_wall_foot_beside(offset: float) -> None:
    (_, _, height), tilt = BOTTOM_CAMERA_IN_HEAD
    views = heading_views(offset)
    assert len(views) == 3 and len({yaw for yaw, _, _ in views}) == 3
    for yaw, pitch, blur in views:
        assert 1.2 < yaw < 2.1 and blur == 0  # ahead of, beside and behind the shoulder
        # the bottom camera's centre ray meets the floor at the offset
        reach = (HEAD_HEIGHT_M + height) / math.tan(pitch + tilt)
        assert reach == pytest.approx(offset, rel=1e-6)
