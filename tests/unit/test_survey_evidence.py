"""The survey's own evidence (issue 31): a missing floor line is unseen, not far; a step the
pictures, the lines or the contacts contradict stops the survey with one line.

Pure: the decision and the watch are fed measurements, no robot walks.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from naoloc.behaviours.nearest_wall import decide_side
from naoloc.behaviours.survey import check_offset
from naoloc.behaviours.walk_watch import WalkWatch, expected_shift_px
from naoloc.behaviours.wall_follow import MIN_OFFSET_M, SideMemory, carry, side_views
from naoloc.errors import ConfigError, SurveyBlocked
from naoloc.geometry import Pose2D
from naoloc.perception.floorline import WallLine


def _line(distance: float, normal: float) -> WallLine:
    return WallLine(distance, normal, 100, 1.0, 0.01, 1.0)


def test_a_side_with_no_line_is_unseen_not_far() -> None:
    # the room: the near wall (0.5 m, right) hidden, the far one seen at 2.5 m
    assert decide_side(2.48, None, offset=0.5) is None  # the far line says nothing
    assert decide_side(None, 0.49, offset=0.5) == "right"  # a line at the offset decides
    assert decide_side(0.52, None, offset=0.5) == "left"
    assert decide_side(2.48, 0.49, offset=0.5) == "right"  # both seen: the nearer
    assert decide_side(0.7, 0.6, offset=0.5) == "right"
    # Furniture 0.67 m to the left, the wall 1.03 m to the right, the robot set 1.05 m from
    # its wall (room 530663737): the line at the offset is the wall's, not the nearer one.
    assert decide_side(0.67, 1.03, offset=1.05) == "right"
    assert decide_side(0.67, 1.03) == "left"  # without the offset: the paper's nearest
    assert decide_side(None, None, offset=0.5) is None
    assert decide_side(3.0, 3.0, offset=0.75) is None  # the middle of a room: no wall beside
    # without a survey offset (localize's use) a lone line still decides, as before
    assert decide_side(2.48, None) == "left"


def test_offsets_below_the_smallest_that_works_are_refused_naming_it() -> None:
    check_offset(MIN_OFFSET_M)
    check_offset(1.0)
    with pytest.raises(ConfigError, match=f"smallest offset that works is {MIN_OFFSET_M:g} m"):
        check_offset(0.4)


def test_small_offsets_look_behind_the_arm_first() -> None:
    near, far = side_views(0.5), side_views(1.0)
    assert near[0][0] > math.pi / 2  # behind the shoulder: the forearm is held forward
    assert far[0][0] == pytest.approx(math.pi / 2)  # beside: a wall 0.5-4 m away
    assert set(near) >= set(far[:1])  # the other view is still tried when one sees nothing


def test_a_carried_line_follows_the_odometry() -> None:
    wall = _line(0.6, -math.pi / 2)  # on the right
    moved = carry(wall, Pose2D(0.2, -0.1, 0.05))  # forward, 0.1 m toward it, turned left
    assert moved.distance == pytest.approx(0.5)
    assert moved.normal == pytest.approx(-math.pi / 2 - 0.05)
    assert moved.inliers == 0  # carried, not measured
    memory = SideMemory()
    memory.seen_side(wall, Pose2D())
    assert memory.steer(Pose2D()) is wall  # measured here
    assert memory.steer(Pose2D(0.4, 0.0, 0.0)) is not None
    assert memory.steer(Pose2D(2.0, 0.0, 0.0)) is None  # too far to trust the odometry
    memory.seen_front(_line(0.55, 0.0), Pose2D(0.4, 0.0, 0.0))
    memory.turned()  # the front wall is the next side's, on the right after a left turn
    side = memory.steer(Pose2D(0.4, 0.0, math.pi / 2))
    assert side is not None
    assert side.distance == pytest.approx(0.55) and side.normal == pytest.approx(-math.pi / 2)


def _watch() -> WalkWatch:
    robot = SimpleNamespace(sim=None)  # a real NAO: no simulator contacts
    return WalkWatch(robot, offset=0.5, wall="right", look_ahead=0.77, f_px=272.0)  # type: ignore[arg-type]


def test_a_wall_ahead_that_does_not_come_nearer_stops_the_survey() -> None:
    watch = _watch()
    watch.new_side(0, 1)
    watch.stepped(0.4)
    watch.front_line(_line(1.5, 0.0), Pose2D(0.4, 0.0, 0.0), 2.6, 3.0)
    watch.stepped(0.4)
    watch.front_line(_line(1.1, 0.0), Pose2D(0.8, 0.0, 0.0), 2.2, 3.0)  # came 0.4 m nearer
    watch.stepped(0.4)
    watch.front_line(_line(1.08, 0.0), Pose2D(1.2, 0.0, 0.0), 1.8, 3.0)  # stuck: one strike
    watch.stepped(0.4)
    with pytest.raises(SurveyBlocked, match=r"^blocked on side 2 of lap 1 after 1\.6 m: the wall"):
        watch.front_line(_line(1.07, 0.0), Pose2D(1.6, 0.0, 0.0), 1.4, 3.0)


def test_lines_ahead_that_are_not_one_wall_across_the_way_are_no_evidence() -> None:
    # A table's face beside the way, then another line: different things at each look,
    # whose distances say nothing of the walk (room 225772294 stopped on such a pair).
    beside = WallLine(1.05, 0.0, 100, 1.0, 0.01, 1.0, (-1.4, -0.4))
    watch = _watch()
    watch.new_side(0, 1)
    for k in range(1, 5):
        watch.stepped(0.2)
        watch.front_line(beside, Pose2D(0.2 * k, 0.0, 0.0), 2.6 - 0.2 * k, 3.0)
    # one wall across, then a line 0.3 rad turned from it (a seam, a skirting's corner)
    watch = _watch()
    watch.new_side(0, 1)
    for k in range(1, 5):
        watch.stepped(0.2)
        turned = 0.3 * (k % 2)
        watch.front_line(_line(1.1, turned), Pose2D(0.2 * k, 0.0, 0.0), 2.6 - 0.2 * k, 3.0)


def test_walking_into_the_wall_ahead_is_refused_before_the_step() -> None:
    watch = _watch()
    watch.new_side(0, 0)
    # a wall 0.9 m ahead at the start where the odometry has the whole side to walk: a
    # robot that faced a wall; the survey looks ahead at every stop from then on
    watch.front_line(_line(0.9, 0.0), Pose2D(), 3.0, 3.0)
    assert watch.wants_front
    watch.front_line(_line(0.55, 0.0), Pose2D(0.35, 0.0, 0.0), 2.65, 3.0)  # one strike
    with pytest.raises(SurveyBlocked, match="the wall ahead is 0.52 m away with 2.6 m"):
        watch.front_line(_line(0.52, 0.0), Pose2D(0.4, 0.0, 0.0), 2.6, 3.0)
    # at the side's end it is the corner, not an obstacle
    corner = _watch()
    corner.front_line(_line(0.55, 0.0), Pose2D(2.9, 0.0, 0.0), 0.1, 3.0)
    corner.front_line(_line(0.54, 0.0), Pose2D(2.9, 0.0, 0.0), 0.1, 3.0)
    assert not corner.wants_front


def test_furniture_before_the_wall_steers_as_the_wall_behind_it() -> None:
    memory = SideMemory()
    right = -math.pi / 2
    memory.seen_side(_line(0.8, right), Pose2D())
    # a sideboard 0.42 m deep begins: its foot is not the wall, the robot keeps its course
    wall = memory.seen_side(_line(0.38, right), Pose2D(0.2, 0.0, 0.0))
    assert wall is not None and wall.distance == pytest.approx(0.8)
    assert memory.level == pytest.approx(0.42)
    # along the sideboard, past the carried line's reach, its foot still gives the wall
    for i in range(2, 8):
        wall = memory.seen_side(_line(0.40, right), Pose2D(0.2 * i, 0.0, 0.0))
    assert wall is not None and wall.distance == pytest.approx(0.82)  # drifted 2 cm out
    steer = memory.steer(Pose2D(1.4, 0.0, 0.0))
    assert steer is not None and steer.distance == pytest.approx(0.82)
    # past its end the wall itself: the stretch ends
    memory.seen_side(_line(0.81, right), Pose2D(1.6, 0.0, 0.0))
    assert memory.level == 0.0


def test_a_wrong_start_angle_gives_way_to_two_lines_that_agree() -> None:
    """A survey start in a corner read the wall behind into its line (room 95028395: the
    start's line turned 0.21 rad from the wall, every later line 0.21 rad the other way);
    the carried wall's angle steered the robot into the wall for a whole side."""
    left = math.pi / 2
    memory = SideMemory()
    memory.start(_line(0.6, left + 0.21), Pose2D(), 0.55)
    first = memory.seen_side(_line(0.59, left - 0.2), Pose2D(0.2, 0.0, 0.0))
    assert first is not None and first.normal == pytest.approx(left + 0.21)  # one line: doubt
    second = memory.seen_side(_line(0.57, left - 0.2), Pose2D(0.4, 0.0, 0.0))
    assert second is not None and second.normal == pytest.approx(left - 0.2)  # two: the wall
    # one line turned once (the arm, a corner) still keeps the wall's angle
    third = memory.seen_side(_line(0.57, left + 0.1), Pose2D(0.6, 0.0, 0.0))
    assert third is not None and third.normal == pytest.approx(left - 0.2)


def test_a_side_wall_that_ignores_the_steps_toward_it_is_a_robot_sliding() -> None:
    watch = _watch()  # the wall on the right: toward it is -y in the map frame
    right = -math.pi / 2
    watch.side_line(_line(0.62, right), Pose2D(0.0, 0.0, 0.0))
    watch.side_line(_line(0.50, right), Pose2D(0.2, -0.12, 0.0))  # stepped toward: closed
    watch.side_line(_line(0.50, right), Pose2D(0.4, -0.24, 0.0))  # stepped, stayed: strike
    watch.side_line(_line(0.18, right), Pose2D(0.6, -0.36, 0.0))  # the arm's edge: not judged
    watch.side_line(_line(0.50, right), Pose2D(0.6, -0.48, 0.0))  # nothing to compare with
    watch.side_line(_line(0.38, right), Pose2D(0.8, -0.6, 0.0), level=0.4)  # a sideboard
    watch.side_line(_line(0.50, right), Pose2D(0.8, -0.72, 0.0))
    watch.side_line(_line(0.49, right), Pose2D(1.0, -0.84, 0.0))  # stayed: strike
    with pytest.raises(SurveyBlocked, match="sliding along the wall on the right: it stayed"):
        watch.side_line(_line(0.49, right), Pose2D(1.2, -0.96, 0.0))


def test_pictures_that_do_not_move_are_a_robot_that_did_not() -> None:
    rng = np.random.default_rng(0)
    wall = (rng.random((240, 420)) * 255).astype(np.uint8)
    import cv2

    wall = cv2.GaussianBlur(wall, (0, 0), 2.0)
    wall = cv2.normalize(wall, None, 0, 255, cv2.NORM_MINMAX)
    watch = _watch()
    expected = expected_shift_px(0.2, 0.5, 0.77, 272.0)
    assert 40 < expected < 80
    first = watch.picture(wall[:, 0:320], 0.2)
    assert first["shift_px"] is None  # nothing to compare with yet
    moved = watch.picture(wall[:, 50:370], 0.2)  # the view slid 50 px: the robot walked
    assert moved["shift_px"] == pytest.approx(50, abs=2)
    watch.picture(wall[:, 50:370], 0.2)  # the same view after a step: one strike
    with pytest.raises(SurveyBlocked, match=r"the pictures did not move \(100 % of their"):
        watch.picture(wall[:, 50:370], 0.2)


def test_the_simulator_contacts_stop_the_survey() -> None:
    sim = SimpleNamespace(true_pose=lambda: (0.1, 1.0, 0.0), is_free=lambda x, y, c: False)
    watch = WalkWatch(SimpleNamespace(sim=sim), 0.5, "right", 0.77, 272.0)  # type: ignore[arg-type]
    with pytest.raises(SurveyBlocked, match="simulator reports the body touching"):
        watch.stepped(0.2)


def test_a_start_beside_a_sideboard_keeps_the_wall_behind_it() -> None:
    memory = SideMemory()
    right = -math.pi / 2
    wall = memory.start(_line(0.55, right), Pose2D(), offset=1.0)  # set 1 m from the wall
    assert wall is not None and wall.distance == pytest.approx(1.0)
    assert memory.level == pytest.approx(0.45)
    assert memory.start(_line(0.95, right), Pose2D(), offset=1.0).distance == pytest.approx(0.95)


def test_a_wall_ahead_that_vanishes_near_is_carried_not_forgotten() -> None:
    watch = _watch()
    watch.new_side(0, 0)
    watch.front_line(_line(0.7, 0.0), Pose2D(1.3, 0.0, 0.0), 1.7, 3.0)  # seen, then unseen
    watch.front_line(None, Pose2D(1.52, 0.0, 0.0), 1.48, 3.0)  # carried: 0.48 m, one strike
    with pytest.raises(SurveyBlocked, match="the wall ahead is 0.26 m away"):
        watch.front_line(None, Pose2D(1.74, 0.0, 0.0), 1.26, 3.0)
