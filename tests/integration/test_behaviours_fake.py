"""Behaviours on the fake backend: survey, interruption, localize and go-home plumbing.

The map is replaced here by a double that answers from the simulator's truth (plus a known
offset), so these tests check the behaviours' geometry and control, not the map's vision;
tests/test_cli_verbs.py runs them end to end with the real map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from naoloc import connect
from naoloc.behaviours import SCAN_YAWS, frames_per_lap, go_home, localize, survey
from naoloc.behaviours.localize import PAPER_SECOND_OFFSET
from naoloc.behaviours.nearest_wall import detect_wall_by_parallax
from naoloc.config import Config, load_config
from naoloc.data.dataset import partial_path_for, read_dataset
from naoloc.data.recorder import record_survey
from naoloc.geometry import Pose2D, relative_pose
from naoloc.localization import Picture, PoseEstimate, Status
from naoloc.robot import Robot
from naoloc.robot.camera import Camera, stand
from naoloc.robot.keyframe import Keyframe

pytest.importorskip("naoloc.backends.fake")


def small_cfg(**survey: Any) -> Config:
    """A 3 x 3 m fake room; 1 lap of a 1.5 m square in 0.5 m steps (12 frames).

    Exact odometry (profile ideal): these tests are about the behaviours' plumbing; a NAO's
    drift walks this small room's survey into a wall (issue 12 keeps it off by vision).
    """
    return load_config(
        {
            "robot": {"backend": "fake"},
            "world": {
                "room": {"size_m": [3.0, 3.0], "seed": 3, "style": "posters"},
                "camera_realism": {"profile": "ideal"},
                "odometry": {"profile": "ideal"},
            },  # the pre-issue-11 world: pipeline logic, not realism
            "survey": {"laps": 1, "step_m": 0.5, "wall_offset_m": 0.75, **survey},
            "go_home": {"tolerance_m": 0.15, "max_tries": 4},
        }
    )


def _start_at(robot: Any, x: float, y: float, theta: float) -> tuple[Any, Pose2D]:
    """The simulator and the map origin (where the robot stood, room frame), the robot
    then moved to ``(x, y, theta)`` (room frame)."""
    sim = robot.sim
    assert sim is not None
    origin = Pose2D.from_list(sim.true_pose())
    sim.teleport(x, y, theta)
    return sim, origin


# The survey circuit of small_cfg in the map frame (a 1.5 m square from the origin).
_SIDE = [0.5, 1.0, 1.5]
CIRCUIT = np.array(
    [(v, 0.0, 0.0) for v in _SIDE] + [(1.5, v, 0.0) for v in _SIDE]
    + [(1.5 - v, 1.5, 0.0) for v in _SIDE] + [(0.0, 1.5 - v, 0.0) for v in _SIDE]
)  # fmt: skip


class TruthMap:
    """A map double: the survey circuit's keyframes and no landmarks (go-home's floor grid
    knows only the walked floor), and the map origin in the room frame."""

    def __init__(self, origin_room: Pose2D) -> None:
        self.meta = {"origin_room_pose": origin_room.to_list()}
        self.keyframe_poses = CIRCUIT

    def extract(self, queries: Sequence[Keyframe]) -> list[None]:
        """No features: the filter double answers from the truth."""
        return [None] * len(queries)


class TruthLocalizer:
    """A filter double: the true map-frame pose plus a fixed offset (m), with a 1 cm
    covariance, once it has taken ``needed`` pictures (before: lost).

    Records every observation it is given, as the real filter does.
    """

    def __init__(
        self, robot: Robot, vmap: TruthMap, offset: tuple[float, float] = (0.0, 0.0),
        needed: int = 1,
    ) -> None:  # fmt: skip
        self.robot, self.vmap, self.offset, self.needed = robot, vmap, offset, needed
        self.log: list[Any] = []
        self.cpu_s = 0.0
        self.filter = SimpleNamespace(walls=None, pictures=0, map_floor_m=0.0)

    def update(self, obs: Any) -> None:
        self.log.append(obs)
        if isinstance(obs, Picture):
            self.filter.pictures += 1

    def pose(self) -> PoseEstimate:
        nan = float("nan")
        if self.filter.pictures < self.needed:
            return PoseEstimate(nan, nan, nan, None, 0.0, Status.LOST, "test: not yet", "none")
        assert self.robot.sim is not None
        truth = relative_pose(
            Pose2D.from_list(self.vmap.meta["origin_room_pose"]),
            Pose2D.from_list(self.robot.sim.true_pose()),
        )
        cov = np.diag([1e-4, 1e-4, 1e-4])
        return PoseEstimate(
            truth.x + self.offset[0], truth.y + self.offset[1], truth.theta, cov, 1.0,
            Status.TRACKING,
        )  # fmt: skip


def test_survey_walks_the_rectangle_and_records_each_step() -> None:
    cfg = small_cfg(head_yaw_rad=-math.pi / 2)
    got: list[tuple[Keyframe, int]] = []
    with connect(cfg) as robot:
        start = Pose2D.from_list(robot.sim.true_pose())  # type: ignore[union-attr]
        result = survey(robot, cfg, lambda kf, lap, odo: got.append((kf, lap)))
        assert not robot.motion.moveIsActive()
    assert result.frames == len(got) == frames_per_lap((1.5, 1.5), 0.5) == 12
    assert result.laps == 1 and result.meta["direction"] == "ccw"
    assert result.meta["origin_room_pose"] == pytest.approx(start.to_list())
    assert result.meta["head_yaw"] == pytest.approx(-math.pi / 2, abs=0.02)  # the wall's side
    assert result.meta["picture_yaw"] == pytest.approx(-math.pi / 2 + 0.77, abs=1e-6)
    assert result.path_m == pytest.approx(6.0, rel=0.05)
    # Map-frame odometry poses follow the square; the truth follows it in the room frame.
    xy = np.array([[kf.pose.x, kf.pose.y] for kf, _ in got])
    want = [(0.5, 0), (1.0, 0), (1.5, 0), (1.5, 0.5), (1.5, 1.0), (1.5, 1.5)]
    assert np.allclose(xy[:6], want, atol=0.05)
    for kf, _ in got:
        assert kf.true_pose is not None
        truth_map = relative_pose(start, kf.true_pose)
        assert truth_map.distance(kf.pose) < 0.15  # odometry drift stays small
        # pictures look ahead of the wall on the right (survey.look_ahead_rad 0.77)
        assert kf.head_yaw == pytest.approx(-math.pi / 2 + 0.77, abs=0.02)
        assert kf.image.shape == (240, 320, 3)
    # The walls never get closer than the offset allows: the robot stayed inside.
    assert all(0.5 < kf.true_pose.x < 2.5 and 0.5 < kf.true_pose.y < 2.5 for kf, _ in got)  # type: ignore[union-attr]


def test_interrupted_survey_stops_the_robot_and_keeps_frames(tmp_path: Path) -> None:
    cfg = small_cfg(head_yaw_rad=-math.pi / 2)
    out = tmp_path / "s.mcap"
    count = {"n": 0}

    class Stop(KeyboardInterrupt):
        pass

    with connect(cfg) as robot:
        real_move = robot.motion.moveTo

        def move_then_maybe_stop(*args: Any, **kwargs: Any) -> bool:
            count["n"] += 1
            if count["n"] == 6:
                robot.motion.move(0.1, 0.0, 0.0)  # walking when the Ctrl-C arrives
                raise Stop()
            return bool(real_move(*args, **kwargs))

        robot.motion.moveTo = move_then_maybe_stop  # type: ignore[method-assign]
        with pytest.raises(Stop):
            record_survey(robot, cfg, out)
        assert not robot.motion.moveIsActive()
        assert robot.motion.getRobotVelocity() == pytest.approx([0.0, 0.0, 0.0])
    assert not out.exists()  # only a survey that completed all its laps becomes out
    data = read_dataset(partial_path_for(out))
    assert len(data.keyframes) == 4  # 3 steps, the turn, 2 more steps; the 6th move broke
    assert not data.complete and data.meta["reason"] == "interrupted (SIGINT)"


@pytest.mark.parametrize(
    ("start", "side", "direction"),
    [((0.75, 0.75, 0.0), "right", "ccw"), ((0.75, 2.25, 0.0), "left", "cw")],
)
def test_floor_lines_decide_the_direction_in_the_corner(
    start: tuple[float, float, float], side: str, direction: str
) -> None:
    cfg = small_cfg().with_overrides({"world": {"start_pose": list(start)}})
    with connect(cfg) as robot:
        res = survey(robot, cfg, lambda kf, lap, odo: None)
        end = robot.sim.true_pose() if robot.sim is not None else None
    assert res.wall is not None  # the paper's detector ran and was recorded
    assert res.floorline is not None and res.yaw_source == "floorline"
    assert res.floorline.side == side, res.floorline
    near = res.floorline.right_m if side == "right" else res.floorline.left_m
    assert near == pytest.approx(0.75, abs=0.03)  # the far wall (2.25 m) may be out of reach
    assert res.parallax is None  # no probe step was needed
    assert res.meta["direction"] == direction
    assert res.meta["floorline_wall"]["side"] == side
    assert res.meta["wall_follow"]["steered_steps"] == res.frames
    assert res.frames == frames_per_lap((1.5, 1.5), 0.5)
    assert end is not None and math.hypot(end[0] - start[0], end[1] - start[1]) < 0.3


@pytest.mark.parametrize(
    ("start", "side"), [((0.75, 0.75, 0.0), "right"), ((0.75, 2.25, 0.0), "left")]
)
def test_parallax_finds_the_nearer_wall(start: tuple[float, float, float], side: str) -> None:
    cfg = small_cfg().with_overrides({"world": {"start_pose": list(start)}})
    with connect(cfg) as robot:
        stand(robot)
        with Camera(robot, cfg.camera) as camera:
            res = detect_wall_by_parallax(robot, camera, 0.5)
    assert res.side == side, res
    # The nearer wall (0.75 m) shifts features about 3x more than the far one (2.25 m).
    near, far = (
        (res.right_shift_px, res.left_shift_px)
        if side == "right"
        else (res.left_shift_px, res.right_shift_px)
    )
    assert near > 2.0 * far


@pytest.mark.parametrize("strategy", ["scan", "paper"])
def test_localize_never_translates_and_reports_error(strategy: str) -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim, origin = _start_at(robot, 2.0, 1.2, 2.5)
        vmap = TruthMap(origin)
        loc = TruthLocalizer(robot, vmap, (0.3, -0.4), needed=3)
        before = Pose2D.from_list(sim.true_pose())
        if strategy == "paper":
            from naoloc.behaviours.localize import paper_queries

            with Camera(robot, cfg.camera, "t") as camera:
                queries = paper_queries(camera, 2)
            yaws = [q.head_yaw for q in queries]
            # Two looks at the nearest wall, the second a little nearer its normal.
            assert abs(yaws[1]) - abs(yaws[0]) == pytest.approx(PAPER_SECOND_OFFSET, abs=0.02)
            return
        result = localize(robot, vmap, cfg, localizer=loc)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
    assert before.distance(after) < 0.02
    # A short look: it stops once the belief is concentrated (the third picture here).
    assert result.pictures == 3 and len(loc.log) == result.pictures
    assert result.error_m == pytest.approx(0.5, abs=1e-6)
    assert result.truth is not None and result.truth.distance(relative_pose(origin, after)) < 1e-9
    summary = result.summary()
    assert summary["error_m"] == pytest.approx(0.5, abs=1e-3) and "heading_error_deg" in summary
    assert summary["status"] == "tracking" and summary["robot_s"] > 0


def test_localize_turns_in_place_while_lost() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim, origin = _start_at(robot, 1.5, 1.5, 0.0)
        loc = TruthLocalizer(robot, TruthMap(origin), needed=len(SCAN_YAWS) + 2)
        result = localize(robot, TruthMap(origin), cfg, localizer=loc)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
    assert result.extra_turns == 1 and result.pictures == len(SCAN_YAWS) + 2
    assert math.hypot(after.x - 1.5, after.y - 1.5) < 0.05
    assert abs(after.theta - math.pi / 2) < 0.1  # a quarter turn, no walk


def test_localize_gives_up_lost_after_its_turns() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        origin = Pose2D.from_list(robot.sim.true_pose())  # type: ignore[union-attr]
        loc = TruthLocalizer(robot, TruthMap(origin), needed=10**6)
        result = localize(robot, TruthMap(origin), cfg, localizer=loc, extra_turns=1)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert not result.estimate.found and result.extra_turns == 1
    assert result.summary()["x"] is None and result.summary()["reason"]


def test_the_config_sets_the_looks_turns_in_place() -> None:
    """``localize.extra_turns`` and ``localize.extra_turn_rad`` (the tuning record, not
    module constants) decide how a lost look turns."""
    cfg = small_cfg().with_overrides({"localize": {"extra_turns": 2, "extra_turn_rad": 1.0}})
    with connect(cfg) as robot:
        sim, origin = _start_at(robot, 1.5, 1.5, 0.0)
        loc = TruthLocalizer(robot, TruthMap(origin), needed=10**6)
        result = localize(robot, TruthMap(origin), cfg, localizer=loc)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
    assert not result.estimate.found and result.extra_turns == 2
    assert abs(math.remainder(after.theta - 2.0, 2 * math.pi)) < 0.1  # two turns of 1 rad


def test_the_config_bounds_go_homes_robot_time() -> None:
    """``go_home.min_time_s`` and ``go_home.time_per_m_s`` (the tuning record) bound the
    walk: with 2 s allowed, it gives up on the way and stops."""
    cfg = small_cfg().with_overrides({"go_home": {"min_time_s": 2.0, "time_per_m_s": 0.1}})
    with connect(cfg) as robot:
        _sim, origin = _start_at(robot, 2.2, 2.1, -2.0)
        vmap = TruthMap(origin)
        result = go_home(robot, vmap, cfg, localizer=TruthLocalizer(robot, vmap))  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert not result.reached and result.reason.startswith("gave up after")


def test_go_home_walks_back_to_the_origin_on_the_live_pose() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        _sim, origin = _start_at(robot, 2.2, 2.1, -2.0)
        vmap = TruthMap(origin)
        loc = TruthLocalizer(robot, vmap, (0.03, -0.03))  # a biased but honest filter
        result = go_home(robot, vmap, cfg, localizer=loc)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert result.reached and result.looks == 1  # it never stopped to look again
    assert result.error_m is not None and result.error_m < 0.2
    assert len(result.trail) > 10  # a pose at every frame while walking
    summary = result.summary()
    assert summary["tries"] == 1 and summary["reached"] is True
    # Walking continuously: little more than the time to walk the path.
    assert result.robot_s < 2.0 * result.walk_s + 10.0


@pytest.mark.parametrize("contacts", [2, 0])
def test_go_home_backs_off_a_thing_the_map_does_not_show_and_goes_around(contacts: int) -> None:
    """Something stands on the planned path that the map does not show (a chair without
    landmarks): the robot touches it and stops; it then marks the floor ahead blocked,
    steps back and plans around it, up to ``go_home.contacts`` times, after which a contact
    stops it for good (blocked)."""
    from naoloc.navigation.grid import grid_of_map

    cfg = load_config({**small_cfg().model_dump(), "go_home": {"tolerance_m": 0.15,
                                                              "contacts": contacts}})  # fmt: skip
    touches: list[tuple[float, float]] = []
    with connect(cfg) as robot:
        sim, origin = _start_at(robot, 2.2, 2.1, -2.0)
        vmap = TruthMap(origin)
        start = relative_pose(origin, Pose2D.from_list(sim.true_pose()))
        path = grid_of_map(vmap).plan(start, Pose2D())
        mid = path[len(path) // 2] if len(path) > 1 else Pose2D(start.x / 2, start.y / 2, 0.0)
        thing = origin * Pose2D(mid.x, mid.y, 0.0)  # room frame, on the way home
        free = sim.is_free

        def is_free(x: float, y: float, clearance: float) -> bool:  # the thing's contact
            if math.hypot(x - thing.x, y - thing.y) <= 0.12 + clearance:
                touches.append((x, y))
                return False
            return free(x, y, clearance)

        sim.is_free = is_free  # type: ignore[method-assign]
        loc = TruthLocalizer(robot, vmap)
        result = go_home(robot, vmap, cfg, localizer=loc)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert touches  # it did walk into the thing
    if contacts:
        assert result.reached, result.reason
        assert result.error_m is not None and result.error_m < 0.2
    else:
        assert not result.reached and result.reason.startswith("blocked")


def test_go_home_stops_and_looks_when_lost_and_gives_up() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        origin = Pose2D.from_list(robot.sim.true_pose())  # type: ignore[union-attr]
        robot.sim.teleport(1.5, 1.5, 0.0)  # type: ignore[union-attr]
        loc = TruthLocalizer(robot, TruthMap(origin), needed=10**6)  # never recognises anything
        result = go_home(robot, TruthMap(origin), cfg, localizer=loc)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert not result.reached and result.reason
    assert result.looks == cfg.go_home.max_tries
    assert result.summary()["reached"] is False


def naoloc_modulo(angle: float) -> float:
    """Angle wrapped into (-pi, pi]."""
    from naoloc.geometry import modulo2PI

    return modulo2PI(angle)
