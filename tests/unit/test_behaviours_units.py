"""Pure parts of the behaviours: the circuit's geometry and the nearest-wall detector."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from naoloc.behaviours import circuit, count_halves, frames_per_lap, nearest_wall
from naoloc.behaviours.localize import own_sigma
from naoloc.behaviours.track import TrackPoint, walk_route
from naoloc.geometry import Pose2D
from naoloc.localization.localizer import PoseEstimate, Status
from naoloc.robot.camera import clamp_head


def _textured(h: int, w: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 255, (h // 8, w // 8), dtype=np.uint8)
    return np.kron(small, np.ones((8, 8), dtype=np.uint8))


@pytest.mark.parametrize("side", ["left", "right"])
def test_nearest_wall_picks_the_textured_half(side: str) -> None:
    img = np.full((240, 320), 128, dtype=np.uint8)
    tex = _textured(240, 160, 0)
    if side == "left":
        img[:, :160] = tex
    else:
        img[:, 160:] = tex
    wall = nearest_wall(img)
    assert wall.side == side
    assert wall.head_yaw == pytest.approx(math.pi / 2 if side == "left" else -math.pi / 2)
    assert max(wall.left, wall.right) > 20 and min(wall.left, wall.right) < 5


def test_blank_image_goes_right_with_no_keypoints() -> None:
    assert count_halves(np.zeros((120, 160), np.uint8)) == (0, 0)
    assert nearest_wall(np.zeros((120, 160, 3), np.uint8)).side == "right"


def test_circuit_is_closed_and_counter_clockwise() -> None:
    pts = circuit((4.0, 4.0), 0.2, 2, math.pi / 2)
    pictures = [p for p in pts if p.picture]
    assert len(pictures) == 2 * 80 == 2 * frames_per_lap((4.0, 4.0), 0.2)
    # Every step is 0.2 m; the robot ends at the origin facing map +x.
    xy = np.array([[p.pose.x, p.pose.y] for p in pictures])
    steps = np.linalg.norm(np.diff(np.vstack([[0.0, 0.0], xy]), axis=0), axis=1)
    assert np.allclose(steps[steps > 1e-9], 0.2)
    assert pts[-1].pose.x == pytest.approx(0.0, abs=1e-9)
    assert pts[-1].pose.y == pytest.approx(0.0, abs=1e-9)
    assert abs(pts[-1].pose.theta) < 1e-9
    # Counter-clockwise: the square lies in y >= 0 and the corners come in order.
    assert xy[:, 1].min() > -1e-9 and xy[:, 0].min() > -1e-9
    corners = [(p.pose.x, p.pose.y) for p in pts if not p.picture][:4]
    assert np.allclose(corners, [(4, 0), (4, 4), (0, 4), (0, 0)], atol=1e-9)
    assert [p.closes_lap for p in pts if not p.picture] == [False, False, False, True] * 2
    assert [p.lap for p in pictures] == [0] * 80 + [1] * 80


def test_clockwise_rectangle_with_uneven_sides() -> None:
    pts = circuit((3.0, 1.0), 0.4, 1, -math.pi / 2)
    corners = [(p.pose.x, p.pose.y) for p in pts if not p.picture]
    assert np.allclose(corners, [(3, 0), (3, -1), (0, -1), (0, 0)], atol=1e-9)
    # 3 m in 0.4 m steps -> 8 equal steps of 0.375 m; 1 m -> 2 steps (round(2.5) = 2).
    assert frames_per_lap((3.0, 1.0), 0.4) == 2 * (8 + 2)
    assert sum(p.picture for p in pts) == 20


def test_head_clamped_to_limits_and_shell() -> None:
    assert clamp_head(3.0, 0.0)[0] < 2.0857
    assert clamp_head(-3.0, 0.0)[0] > -2.0857
    assert clamp_head(1.57, -0.6)[1] == pytest.approx(-0.338, abs=2e-3)  # the shell
    assert clamp_head(0.8, -0.672)[1] == pytest.approx(-0.527, abs=2e-3)
    assert clamp_head(0.0, -0.6)[1] == pytest.approx(-0.6)
    assert clamp_head(0.0, -0.9)[1] == pytest.approx(-0.671, abs=2e-3)


def test_nearest_side_from_the_room_layout() -> None:
    from naoloc.behaviours import nearest_side_in_room

    assert nearest_side_in_room((6.0, 6.0), (1.0, 1.0, 0.0)).side == "right"
    assert nearest_side_in_room((6.0, 6.0), (1.0, 5.0, 0.0)).side == "left"
    assert nearest_side_in_room((6.0, 6.0), (1.0, 1.0, math.pi / 2)).side == "left"
    assert nearest_side_in_room((4.0, 3.0), (3.5, 0.5, math.pi)).side == "left"


def test_truncate_route_keeps_the_first_metres() -> None:
    from naoloc.geometry import Pose2D
    from naoloc.navigation.route import truncate_route

    here = Pose2D(3.0, 4.0, 1.0)
    route = [Pose2D(3.0 * (1 - k / 6), 4.0 * (1 - k / 6)) for k in range(1, 7)]  # 5 m home
    leg = truncate_route(here, route, 2.0)
    assert math.hypot(leg[-1].x - 3.0, leg[-1].y - 4.0) == pytest.approx(2.0)
    assert leg[-1].x == pytest.approx(3.0 * 0.6) and leg[-1].y == pytest.approx(4.0 * 0.6)
    assert truncate_route(here, route, 9.0) == route
    # Along a bent route the length follows the path, not the straight line.
    bent = [Pose2D(1.0, 0.0), Pose2D(1.0, 1.0), Pose2D(0.0, 1.0)]
    cut = truncate_route(Pose2D(), bent, 1.5)
    assert (cut[-1].x, cut[-1].y) == pytest.approx((1.0, 0.5))


@pytest.mark.parametrize(
    ("here", "expect"),
    [
        ((0.0, 0.0, 0.0), "forward"),  # goal ahead: walk forward, no turn
        ((0.0, 0.0, math.pi), "turn"),  # goal behind: turn in place first
        ((0.0, 0.5, 0.0), "right"),  # goal ahead and to the right: forward, turning right
    ],
)
def test_pursuit_walks_toward_the_route(here: tuple[float, float, float], expect: str) -> None:
    from naoloc.geometry import Pose2D
    from naoloc.navigation.route import pursuit

    cmd = pursuit(Pose2D(*here), [Pose2D(2.0, 0.0)])
    if expect == "forward":
        assert cmd.x > 0 and abs(cmd.theta) < 1e-9
    elif expect == "turn":
        assert cmd.x == 0 and cmd.theta != 0
    else:
        assert cmd.x > 0 and cmd.theta < 0
    assert pursuit(Pose2D(*here), []).x == 0.0


@pytest.mark.parametrize(
    ("here", "moves", "turns"),
    [
        # Goal 0.6 m ahead along -x, to be reached facing +x: from facing it (pi), the robot
        # walks on toward it and turns (either way) at once instead of in place there.
        ((0.6, 0.0, math.pi), (1.0, 0.0), "any"),
        # Facing +x already: it steps back toward the goal and does not turn.
        ((0.6, 0.0, 0.0), (-1.0, 0.0), "none"),
        # Facing +y with the goal along -x: it steps sideways to its left and turns right,
        # toward +x.
        ((0.6, 0.0, math.pi / 2), (0.0, 1.0), "right"),
    ],
)
def test_pursuit_near_the_goal_turns_to_its_heading_while_it_walks(
    here: tuple[float, float, float], moves: tuple[float, float], turns: str
) -> None:
    from naoloc.constants import WALK_SPEED, WALK_SPEED_Y
    from naoloc.geometry import Pose2D
    from naoloc.navigation.route import pursuit

    route = [Pose2D(0.0, 0.0)]
    cmd = pursuit(Pose2D(*here), route, goal_theta=0.0, align_m=1.0)
    assert abs(cmd.x) <= WALK_SPEED + 1e-12 and abs(cmd.y) <= WALK_SPEED_Y + 1e-12
    norm = math.hypot(cmd.x, cmd.y)
    assert norm > 0.05  # it walks while it turns
    assert (cmd.x / norm, cmd.y / norm) == pytest.approx(moves, abs=1e-9)
    if turns == "none":
        assert cmd.theta == pytest.approx(0.0)
    elif turns == "right":
        assert cmd.theta < 0
    else:
        assert abs(cmd.theta) > 0.3
    # Beyond align_m, or without a goal heading, the pursuit of before: a goal behind is
    # turned to in place first.
    far = pursuit(Pose2D(*here), route, goal_theta=0.0, align_m=0.5)
    plain = pursuit(Pose2D(*here), route)
    assert far == plain
    if here[2] == 0.0:
        assert (plain.x, plain.y) == (0.0, 0.0) and plain.theta != 0.0


class _Motion:
    """ALMotion's walk calls, recorded."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def move(self, x: float, y: float, theta: float) -> None:
        self.calls.append("move")

    def stopMove(self) -> None:
        self.calls.append("stopMove")


class _Sim:
    """A simulator whose clock advances 0.1 s a reading and whose body touches something
    from the ``touch_at``-th contact check on."""

    def __init__(self, touch_at: int) -> None:
        self.t = 0.0
        self.checks = 0
        self.touch_at = touch_at

    def sim_time(self) -> float:
        self.t += 0.1
        return self.t

    def true_pose(self) -> tuple[float, float, float]:
        return (1.0, 1.0, 0.0)

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        self.checks += 1
        return self.checks < self.touch_at


class _Robot:
    def __init__(self, touch_at: int) -> None:
        self.motion = _Motion()
        self.sim = _Sim(touch_at)


class _Tracking:
    """A tracker whose belief is at the origin, tracking."""

    reached_m = 0.15  # go_home.reached_m

    def step(self) -> TrackPoint:
        est = PoseEstimate(0.0, 0.0, 0.0, np.eye(3) * 1e-4, 1.0, Status.TRACKING)
        return TrackPoint(0.0, est, None, 0.0)

    def tick(self) -> TrackPoint:
        return self.step()


@pytest.mark.parametrize(("touch_at", "why"), [(5, "blocked"), (10**6, "time")])
def test_a_walk_that_touches_something_stops(touch_at: int, why: str) -> None:
    """The body touching a wall or furniture (the simulator's contacts, a NAO's bumpers)
    stops the walk at once; it is stopped on the way out."""
    robot = _Robot(touch_at)
    route = [Pose2D(2.0, 0.0, 0.0), Pose2D(3.0, 0.0, 0.0)]
    _points, got = walk_route(robot, _Tracking(), route, max_s=3.0, ticks=0)  # type: ignore[arg-type]
    assert got == why
    assert robot.motion.calls[-1] == "stopMove"
    if why == "blocked":
        assert robot.sim.checks == touch_at  # no step after the contact


def test_a_look_settles_on_the_beliefs_own_spread_not_the_maps_floor() -> None:
    """The filter adds the map's own error to every covariance; a look that waited for the
    whole std to fall below ``localize.settle_sigma_m`` would never stop early on a map whose
    floor is above it. The settle test takes the floor off."""

    def estimate(std_m: float) -> PoseEstimate:
        cov = np.diag([std_m**2, (0.5 * std_m) ** 2, 1e-4])
        return PoseEstimate(0.0, 0.0, 0.0, cov, 1.0, Status.TRACKING)

    assert own_sigma(estimate(0.05), 0.04) == pytest.approx(0.03)
    assert own_sigma(estimate(0.04), 0.04) == pytest.approx(0.0)
    assert own_sigma(estimate(0.03), 0.04) == 0.0  # never negative
    assert own_sigma(estimate(0.05), 0.0) == pytest.approx(0.05)


@pytest.mark.parametrize(
    ("head_yaw", "first", "travel"),
    [
        (-2.0, -2.0, 4.0),  # the last sweep ended on the right: up from there
        (2.0, 2.0, 4.0),  # ... on the left: down from there
        (0.3, 2.0, 5.7),  # nearer the left end
        (0.0, -2.0, 6.0),  # in the middle: one end, then the other
    ],
)
def test_a_final_approach_sweep_starts_where_the_head_is(
    head_yaw: float, first: float, travel: float
) -> None:
    from naoloc.behaviours.go_home import next_sweep
    from naoloc.behaviours.localize import SCAN_YAWS

    order = next_sweep(SCAN_YAWS, head_yaw)
    assert sorted(order) == sorted(SCAN_YAWS) and order[0] == first
    path = [head_yaw, *order]
    assert sum(abs(b - a) for a, b in itertools.pairwise(path)) == pytest.approx(travel)
