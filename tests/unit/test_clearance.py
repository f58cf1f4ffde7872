"""The step away from the walls a look saw (naoloc.navigation.clearance), by table."""

from __future__ import annotations

import math

import pytest

from naoloc.geometry import Pose2D
from naoloc.localization.observations import LineScan
from naoloc.navigation.clearance import away_from_walls
from naoloc.perception.floorline import WallLine


def _line(distance: float, normal: float) -> WallLine:
    return WallLine(distance, normal, inliers=200, fraction=0.9, rms_m=0.003, span_m=1.0)


def _scan(*lines: WallLine, at: Pose2D | None = None) -> LineScan:
    return LineScan(tuple(lines), at or Pose2D(), 0.0)


@pytest.mark.parametrize(
    ("lines", "expect"),
    [
        # A wall 0.4 m to the right: step left.
        ([(0.4, -math.pi / 2)], (0.0, 1.0)),
        # A wall 0.3 m ahead: step back.
        ([(0.3, 0.0)], (-1.0, 0.0)),
        # A corner, walls 0.4 m ahead and 0.4 m to the left: out of it, back and right.
        ([(0.4, 0.0), (0.4, math.pi / 2)], (-math.sqrt(0.5), -math.sqrt(0.5))),
        # Walls 1.5 m away: none is near, no step.
        ([(1.5, 0.0), (1.6, math.pi / 2)], None),
        # A corridor, walls 0.5 m on either side: no way is more open, no step.
        ([(0.5, math.pi / 2), (0.5, -math.pi / 2)], None),
        # Nothing seen: no step.
        ([], None),
    ],
)
def test_the_way_out_leads_away_from_the_near_walls(
    lines: list[tuple[float, float]], expect: tuple[float, float] | None
) -> None:
    way = away_from_walls([_scan(*(_line(d, n) for d, n in lines))], Pose2D(), near_m=1.0)
    if expect is None:
        assert way is None
    else:
        assert way == pytest.approx(expect, abs=1e-9)


def test_lines_seen_before_a_turn_push_in_the_robot_frame_now() -> None:
    # Seen straight ahead 0.4 m away; the robot has since turned a quarter turn left in
    # place, so that wall is on its right now: step left.
    seen = _scan(_line(0.4, 0.0), at=Pose2D(2.0, 1.0, 0.3))
    way = away_from_walls([seen], Pose2D(2.0, 1.0, 0.3 + math.pi / 2), near_m=1.0)
    assert way == pytest.approx((0.0, 1.0), abs=1e-9)
    # Having stepped 0.5 m back since, it is 0.9 m from that wall: near enough to push
    # within 1 m, not within 0.8 m.
    back = Pose2D(2.0 - 0.5 * math.cos(0.3), 1.0 - 0.5 * math.sin(0.3), 0.3)
    assert away_from_walls([seen], back, near_m=1.0) == pytest.approx((-1.0, 0.0), abs=1e-9)
    assert away_from_walls([seen], back, near_m=0.8) is None
