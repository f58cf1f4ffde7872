"""One gate for floor-wall lines: the survey steers by the lines the map is built from."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.behaviours.wall_follow import trusted
from naoloc.mapping.wall_poses import _line
from naoloc.perception.floorline import WallLine
from naoloc.perception.wall_gate import (
    FRONT_RANGE_M,
    SIDE_ANGLE_ERROR_RAD,
    SIDE_OFFSET_ERROR_M,
    in_front_range,
    side_line_angle,
)


def test_side_line_angle_gates_distance_and_angle() -> None:
    right = -math.pi / 2
    assert side_line_angle(1.0, right, 1.0, right) == pytest.approx(0.0)
    assert side_line_angle(1.0, right + 0.1, 1.0, right) == pytest.approx(-0.1)
    assert side_line_angle(1.0 + SIDE_OFFSET_ERROR_M + 0.01, right, 1.0, right) is None
    assert side_line_angle(1.0, right + SIDE_ANGLE_ERROR_RAD + 0.01, 1.0, right) is None
    # wrapped: a normal a whole turn away is the same direction
    assert side_line_angle(1.0, right + 2 * math.pi, 1.0, right) == pytest.approx(0.0)


def test_front_range() -> None:
    assert in_front_range(FRONT_RANGE_M) and not in_front_range(FRONT_RANGE_M + 0.01)


def test_survey_and_map_trust_the_same_side_lines() -> None:
    rng = np.random.default_rng(7)
    offset, side = 1.0, math.pi / 2
    for distance, normal in zip(
        rng.uniform(0.2, 2.0, 400), rng.uniform(0.5, 2.6, 400), strict=True
    ):
        line = WallLine(float(distance), float(normal), 100, 1.0, 0.003, 1.0)
        steered = trusted(line, offset, side) is not None
        mapped = _line({"distance_m": distance, "normal_rad": normal}, offset, side) is not None
        assert steered == mapped, (distance, normal)
