"""The floor-line fix: the walls the map records, the poses floor-wall lines allow."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from naoloc.geometry import Pose2D, modulo2PI
from naoloc.localization.floorfix import (
    Walls,
    candidates,
    carry_lines,
    check_pose,
    landmark_candidates,
    map_walls,
)
from naoloc.perception.floorline import WallLine

# A 5 x 4 m room in a wall frame turned 0.05 rad from the map frame.
WALLS = Walls(Pose2D(0.2, -0.1, 0.05), (-1.0, 4.0, -1.0, 3.0))


def _line(distance: float, normal: float, span: float = 1.0) -> WallLine:
    return WallLine(distance, normal, 200, 0.9, 0.005, span)


def _lines_at(pose_w: Pose2D, furniture: float | None = None) -> list[WallLine]:
    """Exact lines to the four walls from ``pose_w`` (wall frame); optionally a bookcase
    ``furniture`` m in front of the +x wall."""
    x0, x1, y0, y1 = WALLS.bounds
    out = []
    for k, dist in enumerate((x1 - pose_w.x, y1 - pose_w.y, pose_w.x - x0, pose_w.y - y0)):
        if k == 0 and furniture is not None:
            out.append(_line(dist - furniture, modulo2PI(k * math.pi / 2 - pose_w.theta)))
        out.append(_line(dist, modulo2PI(k * math.pi / 2 - pose_w.theta)))
    return out


def _near(cands: list[Pose2D], truth: Pose2D, metres: float = 0.01, rad: float = 0.01) -> bool:
    return any(
        math.hypot(c.x - truth.x, c.y - truth.y) < metres
        and abs(modulo2PI(c.theta - truth.theta)) < rad
        for c in cands
    )


@pytest.mark.parametrize("theta", [0.3, -2.0, 2.9])
def test_the_true_pose_is_among_the_candidates(theta: float) -> None:
    pose_w = Pose2D(1.2, 0.7, theta)
    truth = WALLS.frame * pose_w
    lines = _lines_at(pose_w, furniture=0.8)
    every = candidates(lines, WALLS)
    assert _near(every, truth)
    # One quarter turn: one pose. The bookcase's x coordinate would put the +x wall's own
    # line behind that wall, so only the walls' coordinates remain; both y walls agree.
    kept = candidates(lines, WALLS, heading=truth.theta + 0.3)
    assert len(kept) == 1 and _near(kept, truth)
    assert len(every) > len(kept)


def test_furniture_hiding_its_wall_leaves_both_coordinates() -> None:
    pose_w = Pose2D(1.2, 0.7, 0.3)
    truth = WALLS.frame * pose_w
    # The bookcase 0.8 m in front of the +x wall hides it: the bookcase's line or the -x
    # wall's line may be the wall's, so x has two candidates.
    lines = [ln for ln in _lines_at(pose_w, furniture=0.8) if abs(ln.distance - 2.8) > 1e-6]
    kept = candidates(lines, WALLS, heading=truth.theta)
    assert len(kept) == 2 and _near(kept, truth)
    assert sorted(round((WALLS.frame.inverse() * c).x, 6) for c in kept) == [1.2, 2.0]


def test_an_axis_no_wall_line_gives_takes_the_landmarks_places() -> None:
    """The x walls out of range, a chest 0.6 m in front of the -x wall: the lines give x
    only from the chest. The solver's place along x (the landmarks') becomes a candidate,
    searched within the walls and in front of the chest's line."""
    pose_w = Pose2D(2.1, 0.7, 0.3)
    truth = WALLS.frame * pose_w
    _xp, yp, xm, ym = _lines_at(pose_w)
    chest = _line(xm.distance - 0.6, xm.normal)
    lines = [yp, ym, chest]
    assert not _near(candidates(lines, WALLS, heading=truth.theta), truth, metres=0.3)
    asked: list[tuple[float, int, float, tuple[float, float]]] = []

    def solve(
        theta: float, axis: int, fixed: float, span: tuple[float, float]
    ) -> list[tuple[float, int]]:
        asked.append((theta, axis, fixed, span))
        places = [(2.1, 40), (-0.5, 30)] if axis == 0 else [(0.7, 50)]
        return [(c, n) for c, n in places if span[0] <= c <= span[1]]

    kept = [
        *candidates(lines, WALLS, heading=truth.theta),
        *landmark_candidates(lines, WALLS, solve, heading=truth.theta),
    ]
    assert _near(kept, truth)
    on_x = [a for a in asked if a[1] == 0]
    assert len(on_x) == 1 and on_x[0][2] == pytest.approx(0.7)  # the y walls' coordinate
    low, high = on_x[0][3]
    assert low == pytest.approx(pose_w.x - 0.6 - 0.2) and high == pytest.approx(3.9)
    # The chest's pose and the landmarks' x; the solver's y agrees with the y walls' line.
    assert len(kept) == 2
    # One y wall only: its coordinate could be another wall's in a wrong quarter turn, so
    # nothing is searched from it.
    asked.clear()
    seen = [yp, chest, _line(0.9, xm.normal)]
    one_sided = [*candidates(seen, WALLS), *landmark_candidates(seen, WALLS, solve)]
    assert not [a for a in asked if a[1] == 0]
    assert not _near(one_sided, truth, metres=0.3)


def test_lines_that_contradict_each_other_bound_nothing() -> None:
    pose_w = Pose2D(1.2, 0.7, 0.3)
    truth = WALLS.frame * pose_w
    lines = _lines_at(pose_w)
    # The -x wall's line misread 0.5 m too far (2.7 m, beyond that wall), with the +x
    # wall's own line: no x coordinate keeps both lines in front of their walls, so one of
    # them is not where the floor ends and neither bounds x: both coordinates stay.
    x_minus = modulo2PI(math.pi - pose_w.theta)
    bad = [*(ln for ln in lines if ln.normal != x_minus), _line(2.7, x_minus)]
    kept = candidates(bad, WALLS, heading=truth.theta)
    assert len(kept) == 2 and _near(kept, truth)
    checked = check_pose(bad, WALLS, truth, 0.3, 0.15)
    assert checked is not None and _near([checked[0]], truth, metres=1e-6, rad=1e-6)


def test_a_lone_line_read_past_its_wall_does_not_veto_the_wall_many_lines_see() -> None:
    pose_w = Pose2D(0.5, 2.5, 0.3)  # 0.5 m from the +y wall
    truth = WALLS.frame * pose_w
    lines = _lines_at(pose_w)
    y_plus = modulo2PI(math.pi / 2 - pose_w.theta)
    # The +y wall seen by three more pictures, and once 0.3 m too far (beyond the wall):
    # that line alone would bound y below the truth; three lines agree on the wall.
    past = [_line(0.5, y_plus), _line(0.5, y_plus), _line(0.8, y_plus)]
    kept = candidates([*lines, *past], WALLS, heading=truth.theta)
    assert _near(kept, truth)
    checked = check_pose([*lines, *past], WALLS, truth, 0.3, 0.15)
    assert checked is not None and _near([checked[0]], truth, metres=1e-6, rad=1e-6)
    # With only as many lines on the wall as past it (two to one), the lone line wins:
    # the wall's coordinate goes, as before.
    fewer = [*(ln for ln in lines if ln.normal != y_plus), _line(0.5, y_plus), _line(0.8, y_plus)]
    assert not _near(candidates(fewer, WALLS, heading=truth.theta), truth)


def test_noisy_lines_still_give_the_pose_within_centimetres() -> None:
    rng = np.random.default_rng(3)
    pose_w = Pose2D(2.5, 1.9, 1.0)
    truth = WALLS.frame * pose_w
    lines = [
        _line(ln.distance + rng.normal(0, 0.02), ln.normal + rng.normal(0, 0.02))
        for ln in _lines_at(pose_w)
    ]
    assert _near(candidates(lines, WALLS, heading=truth.theta), truth, metres=0.05, rad=0.03)


def test_too_few_or_short_lines_give_nothing() -> None:
    assert candidates([_line(1.0, 0.2)], WALLS) == []
    assert candidates([_line(1.0, 0.2, 0.1), _line(2.0, 1.77, 0.1)], WALLS) == []
    # two lines on one axis only: the other coordinate is unknown
    assert candidates([_line(1.0, 0.2), _line(2.0, 0.2 + math.pi)], WALLS) == []


def test_map_walls_come_from_the_wall_poses_meta() -> None:
    meta = {"wall_poses": {"wall_frame": [0.2, -0.1, 0.05], "walls_m": [-1.0, 4.0, -1.0, 3.0]}}
    walls = map_walls(SimpleNamespace(meta=meta))  # type: ignore[arg-type]
    assert walls == WALLS and walls.coords == (4.0, 3.0, 1.0, 1.0)
    for bad in (
        {},
        {"wall_poses": None},
        {"wall_poses": {"wall_frame": [0, 0, 0]}},
        {"wall_poses": {"wall_frame": [0, 0], "walls_m": [-1, 4, -1, 3]}},
        {"wall_poses": {"wall_frame": [0, 0, 0], "walls_m": [4, -1, -1, 3]}},
        {"wall_poses": {"wall_frame": [0, 0, "x"], "walls_m": [-1, 4, -1, 3]}},
        {"wall_poses": {"wall_frame": [0, float("nan"), 0], "walls_m": [-1, 4, -1, 3]}},
        {"wall_poses": {"wall_frame": [0, 0, True], "walls_m": [-1, 4, -1, 3]}},
    ):
        assert map_walls(SimpleNamespace(meta=bad)) is None  # type: ignore[arg-type]


def test_check_pose_pins_the_axes_the_walls_give_and_refuses_contradicted_poses() -> None:
    pose_w = Pose2D(1.2, 0.7, 0.3)
    truth = WALLS.frame * pose_w
    lines = _lines_at(pose_w)
    guess = WALLS.frame * Pose2D(1.25, 0.64, 0.33)
    checked = check_pose(lines, WALLS, guess, 0.3, 0.15)
    assert checked is not None and checked[1] == 2  # both axes from walls' lines
    assert _near([checked[0]], truth, metres=1e-6, rad=1e-6)
    # farther than `metres` from every line's coordinate (but within BEHIND_WALL_M of
    # them): kept, not snapped
    off = check_pose(lines, WALLS, WALLS.frame * Pose2D(1.1, 0.7, 0.3), 0.05, 0.15)
    assert off is not None and off[1] == 1
    assert (WALLS.frame.inverse() * off[0]).x == pytest.approx(1.1)
    # every wall seen: a pose 0.5 m off puts the +x wall's line behind that wall
    assert check_pose(lines, WALLS, WALLS.frame * Pose2D(1.7, 0.7, 0.3), 0.3, 0.15) is None
    # heading 0.3 rad off the lines' heading
    assert check_pose(lines, WALLS, WALLS.frame * Pose2D(1.2, 0.7, 0.6), 0.3, 0.15) is None
    assert check_pose(lines[:1], WALLS, truth, 0.3, 0.15) is None  # one line: nothing to check


def test_a_near_wall_fixes_a_coordinate_from_one_side() -> None:
    """0.4 m from the -y wall, the x walls unseen but a chest 0.6 m in front of the -x wall:
    x comes only from the chest. The near wall's line is its wall's (furniture stands
    farther out), so the landmarks' place along x is searched from its y; a far one-sided
    line (1.5 m) starts no search."""
    pose_w = Pose2D(2.1, -0.6, 0.3)
    truth = WALLS.frame * pose_w
    _xp, _yp, xm, ym = _lines_at(pose_w)
    chest = _line(xm.distance - 0.6, xm.normal)
    asked: list[tuple[int, float]] = []

    def solve(
        theta: float, axis: int, fixed: float, span: tuple[float, float]
    ) -> list[tuple[float, int]]:
        asked.append((axis, fixed))
        return [(2.1, 40)] if axis == 0 and span[0] <= 2.1 <= span[1] else []

    lines = [ym, chest, _line(ym.distance, ym.normal)]
    assert not _near(candidates(lines, WALLS, heading=truth.theta), truth, metres=0.3)
    kept = landmark_candidates(lines, WALLS, solve, heading=truth.theta)
    assert _near(kept, truth)
    assert (0, pytest.approx(-0.6)) in asked
    asked.clear()
    far = Pose2D(2.1, 0.5, 0.3)  # 1.5 m from the -y wall
    _xp, _yp, xm, ym = _lines_at(far)
    far_lines = [ym, _line(xm.distance - 0.6, xm.normal), _line(ym.distance, ym.normal)]
    landmark_candidates(far_lines, WALLS, solve, heading=(WALLS.frame * far).theta)
    assert not [a for a in asked if a[0] == 0]


def _same_lines(a: list[WallLine], b: list[WallLine]) -> bool:
    key = sorted((round(ln.distance, 6), round(modulo2PI(ln.normal), 6)) for ln in a)
    return key == sorted((round(ln.distance, 6), round(modulo2PI(ln.normal), 6)) for ln in b)


def test_lines_carried_across_a_turn_are_the_lines_now_despite_the_odometrys_turn_error() -> None:
    """Room 377961639, pose 0: the first sweep's lines saw the wall 1 m to one side, which
    after three quarter turns was behind the robot, so the vote had only the bookcase in
    front of it and chose a pose 0.45 m off. Carried across the turn (odometry 6 % short
    in angle, 3 cm of drift in place), the earlier lines are the lines the robot would
    see now, to a micrometre."""
    before = Pose2D(1.2, 0.7, 0.3)
    true_move = Pose2D(0.03, -0.02, 3 * math.pi / 2)  # in the frame of ``before``
    after = before * true_move
    odometry = Pose2D(true_move.x, true_move.y, true_move.theta * 0.94)
    earlier = _lines_at(before)
    every = _lines_at(after)
    now = [every[0], every[2]]  # the x walls seen now, the y walls in the blind spot
    carried = carry_lines(earlier, odometry, now)
    assert _same_lines(carried, every)
    truth = WALLS.frame * after
    assert candidates(now, WALLS) == []  # no y coordinate
    assert _near(candidates([*now, *carried], WALLS), truth)


def test_lines_are_not_carried_without_a_heading_now_or_past_the_largest_turn_error() -> None:
    before = Pose2D(1.2, 0.7, 0.3)
    earlier = _lines_at(before)
    moved = Pose2D(0.0, 0.0, math.pi / 2)
    after = before * moved
    assert carry_lines(earlier, moved, _lines_at(after)[:1]) == []  # one line: no heading
    # The odometry 0.5 rad off: the lines now cannot say which way to correct.
    off = Pose2D(0.0, 0.0, math.pi / 2 + 0.5)
    assert carry_lines(earlier, off, _lines_at(after)) == []
