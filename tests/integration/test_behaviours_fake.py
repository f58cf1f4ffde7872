"""Behaviours on the fake backend: survey, interruption, localize and go-home plumbing.

The map is replaced here by a double that answers from the simulator's truth (plus a known
offset), so these tests check the behaviours' geometry and control, not the map's vision;
tests/test_cli_verbs.py runs them end to end with the real map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
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
from naoloc.mapping.localizer import Estimate, no_estimate
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


# The survey circuit of small_cfg in the map frame (a 1.5 m square from the origin).
_SIDE = [0.5, 1.0, 1.5]
CIRCUIT = np.array(
    [(v, 0.0, 0.0) for v in _SIDE] + [(1.5, v, 0.0) for v in _SIDE]
    + [(1.5 - v, 1.5, 0.0) for v in _SIDE] + [(0.0, 1.5 - v, 0.0) for v in _SIDE]
)  # fmt: skip


class TruthMap:
    """A map double: the estimate is the true map-frame pose plus a fixed offset (m).

    Its keyframes are the survey circuit and it has no landmarks, so go-home's floor grid
    knows only the walked floor (the rest of the room is unknown, not blocked).
    """

    def __init__(self, robot: Robot, origin_room: Pose2D, *offsets: tuple[float, float]) -> None:
        self.robot = robot
        self.meta = {"origin_room_pose": origin_room.to_list()}
        self.offsets = offsets  # used in turn, one per call
        self.calls: list[int] = []
        self.keyframe_poses = CIRCUIT

    def extract(self, queries: Sequence[Keyframe]) -> list[None]:
        """No features: the double answers from the truth (one placeholder per picture)."""
        return [None] * len(queries)

    def localize_features(
        self,
        feats: Sequence[None],
        queries: Sequence[Keyframe],
        mode: str = "verified",
        memo: object = None,
    ) -> Estimate:
        assert len(feats) == len(queries)
        return self.localize(queries, mode)

    def localize(self, queries: Sequence[Keyframe], mode: str = "verified") -> Estimate:
        offset = self.offsets[len(self.calls) % len(self.offsets)]
        self.calls.append(len(queries))
        assert self.robot.sim is not None
        truth = relative_pose(
            Pose2D.from_list(self.meta["origin_room_pose"]),
            Pose2D.from_list(self.robot.sim.true_pose()),
        )
        # A verified PnP estimate over many inliers: the filter trusts it to a few cm.
        details = {"method": "pnp", "inliers": 200}
        return Estimate(truth.x + offset[0], truth.y + offset[1], truth.theta, 1.0, mode, details)


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
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(2.0, 1.2, 2.5)
        vmap = TruthMap(robot, origin, (0.3, -0.4))
        before = Pose2D.from_list(sim.true_pose())
        loc = localize(robot, vmap, cfg, strategy=strategy)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
    assert before.distance(after) < 0.02
    assert vmap.calls == [len(SCAN_YAWS) if strategy == "scan" else 2]
    assert loc.error_m == pytest.approx(0.5, abs=1e-6)
    assert loc.truth is not None and loc.truth.distance(relative_pose(origin, after)) < 1e-9
    yaws = [q.head_yaw for q in loc.queries]
    if strategy == "scan":
        assert max(yaws) - min(yaws) > 3.5
    else:  # two looks at the nearest wall, the second a little nearer its normal
        assert abs(yaws[1]) - abs(yaws[0]) == pytest.approx(PAPER_SECOND_OFFSET, abs=0.02)
    summary = loc.summary()
    assert summary["error_m"] == pytest.approx(0.5, abs=1e-3) and "heading_error_deg" in summary
    assert 0.0 <= summary["compute_s"] <= loc.wall_s  # the double's work: next to nothing


def test_the_cpu_meter_counts_its_blocks_only() -> None:
    """compute_s: CPU inside the timed blocks; waiting (a picture, a walk) is not counted."""
    import time

    from naoloc.behaviours.localize import CpuMeter

    meter = CpuMeter()
    with meter.timed():
        t0 = time.process_time()
        while time.process_time() - t0 < 0.03:
            pass
    time.sleep(0.05)
    with pytest.raises(ValueError), meter.timed():
        raise ValueError("counted all the same")
    assert 0.03 <= meter.seconds < 0.05


def test_localize_scan_with_a_turn_in_place() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(1.5, 1.5, 0.0)
        loc = localize(robot, TruthMap(robot, origin, (0.0, 0.0)), cfg, turns=2)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
    assert len(loc.queries) == 2 * len(SCAN_YAWS)
    assert math.hypot(after.x - 1.5, after.y - 1.5) < 0.05
    assert abs(abs(after.theta) - math.pi) < 0.1


def test_go_home_walks_back_to_the_origin() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(2.2, 2.1, -2.0)
        vmap = TruthMap(robot, origin, (0.05, -0.05))  # a biased but honest localizer
        result = go_home(robot, vmap, cfg)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert result.reached
    assert 1 <= result.tries <= 2
    assert result.error_m is not None and result.error_m < 0.15
    assert result.summary()["tries"] == result.tries


def test_go_home_gives_up_after_max_tries() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(1.5, 1.5, 0.0)
        # Wedged: every walk is blocked at once, so the robot never gets home.
        robot.motion.moveTo = lambda *a, **k: False  # type: ignore[method-assign]
        vmap = TruthMap(robot, origin, (0.0, 0.0))
        result = go_home(robot, vmap, cfg)  # type: ignore[arg-type]
    assert not result.reached and result.reason
    assert result.tries <= cfg.go_home.max_tries
    assert result.blocked_at  # each blocked walk was remembered and planned around
    assert result.summary()["reached"] is False


class UnsureMap(TruthMap):
    """A truth double whose confidence follows a script (one value per call, last repeats)."""

    def __init__(self, robot: Robot, origin_room: Pose2D, confidences: Sequence[float]) -> None:
        super().__init__(robot, origin_room, (0.0, 0.0))
        self.confidences = list(confidences)

    def localize(self, queries: Sequence[Keyframe], mode: str = "verified") -> Estimate:
        est = super().localize(queries, mode)
        conf = self.confidences[min(len(self.calls), len(self.confidences)) - 1]
        if conf <= 0.0:  # recognised nothing
            return no_estimate(mode, "test: nothing recognised")
        return Estimate(est.x, est.y, est.theta, conf, mode, est.details)


@pytest.mark.parametrize(
    ("confidences", "calls", "turned"),
    [((0.3, 0.5, 0.99), [1, 2, 3], 2), ((0.2,), [1, 2, 3, 4], 3), ((0.99,), [1], 0)],
)
def test_localize_turns_in_place_until_confident(
    confidences: tuple[float, ...], calls: list[int], turned: int
) -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(1.5, 1.4, 0.3)
        vmap = UnsureMap(robot, origin, confidences)
        loc = localize(robot, vmap, cfg)  # type: ignore[arg-type]
        after = Pose2D.from_list(sim.true_pose())
        assert not robot.motion.moveIsActive()
    # sweeps so far, then (after turns) the last sweep alone for the heading
    assert vmap.calls == [len(SCAN_YAWS) * k for k in calls] + ([len(SCAN_YAWS)] if turned else [])
    assert loc.extra_turns == turned and loc.summary()["extra_turns"] == turned
    assert math.hypot(after.x - 1.5, after.y - 1.4) < 0.05  # turned, never translated
    assert abs(naoloc_modulo(after.theta - 0.3 - turned * math.pi / 2)) < 0.1
    # The estimate is for where the robot stands at the last picture.
    assert loc.truth is not None and loc.truth.distance(relative_pose(origin, after)) < 1e-9
    bodies = {round(q.pose.theta, 1) for q in loc.queries}
    assert len(bodies) == turned + 1


@pytest.mark.parametrize(
    ("outcome", "support", "alternatives", "calls", "floor_calls"),
    [
        ("floor_confirmed", 5, False, [1], 1),
        ("floor_consistent", 33, False, [1], 1),
        ("floor_consistent", 6, False, [1, 2, 3, 4], 2),
        ("floorlines", 40, False, [1], 1),
        ("undecided", 0, False, [1, 2, 3, 4], 2),
        ("floor_confirmed", 5, True, [1], 1),
    ],
    ids=[
        "confirmed-stops",
        "consistent-stops",
        "consistent-but-weak-turns",
        "vote-winner-stops",
        "undecided-turns",
        "look-alike-confirmed-stops",
    ],
)
def test_floor_lines_may_settle_the_first_sweep(
    monkeypatch: pytest.MonkeyPatch,
    outcome: str,
    support: int,
    alternatives: bool,
    calls: list[int],
    floor_calls: int,
) -> None:
    """A first sweep that is not confident goes to the floor step before the robot turns:
    when the step decides (it confirms the PnP pose, keeps it by a clear margin and enough
    support, or a floor candidate wins the vote) the scan stops there, whatever look-alike
    the pictures saw;
    when it leaves the estimate as it was, the robot turns as before and the floor step
    runs again at the end, with lines measured where the robot then stands."""
    import importlib

    module = importlib.import_module("naoloc.behaviours.localize")
    seen: list[Estimate] = []
    logs: list[Any] = []

    def floor_fix(
        _r: Any, _v: Any, _c: Any, _q: Any, _f: Any, est: Estimate, _m: Any, log: Any
    ) -> Estimate:
        seen.append(est)
        logs.append(log)
        if outcome == "undecided":
            return est
        if outcome == "floorlines":
            return Estimate(est.x, est.y, est.theta, 0.3, est.mode,
                            {**est.details, "method": "floorlines"})  # fmt: skip
        return Estimate(est.x, est.y, est.theta, est.confidence, est.mode,
                        {**est.details, outcome: True, "floor_support": support})  # fmt: skip

    monkeypatch.setattr(module, "_floor_fix", floor_fix)

    class Unsure(UnsureMap):
        def localize(self, queries: Sequence[Keyframe], mode: str = "verified") -> Estimate:
            est = super().localize(queries, mode)
            if alternatives:
                est.details["alternatives"] = [[0.0, 0.0, 0.0, 30]]
            return est

    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(1.5, 1.4, 0.3)
        vmap = Unsure(robot, origin, (0.5,))
        loc = localize(robot, vmap, cfg)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    sweeps = [len(SCAN_YAWS) * k for k in calls]
    assert vmap.calls == sweeps + ([len(SCAN_YAWS)] if len(calls) > 1 else [])
    assert loc.extra_turns == len(calls) - 1 and len(seen) == floor_calls
    if outcome == "floorlines":
        assert loc.estimate.method == "floorlines"
    elif outcome != "undecided":
        assert loc.estimate.details.get(outcome) is True  # the last floor step's word
    assert len(loc.queries) == sweeps[-1]
    # One log per localization: the lines of the first floor step reach the last one.
    assert all(log is logs[0] for log in logs) and logs[0] is not None


def test_a_first_sweep_that_recognised_nothing_goes_to_the_floor_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """No estimate from the first sweep: the floor step still runs before any turn, and a
    candidate that clearly wins its vote ends the scan there."""
    import importlib

    module = importlib.import_module("naoloc.behaviours.localize")
    seen: list[Estimate] = []

    def floor_fix(
        _r: Any, _v: Any, _c: Any, _q: Any, _f: Any, est: Estimate, _m: Any, *_: Any
    ) -> Estimate:
        seen.append(est)
        return Estimate(1.0, 2.0, 0.5, 0.3, "verified", {"method": "floorlines"})

    monkeypatch.setattr(module, "_floor_fix", floor_fix)
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        vmap = UnsureMap(robot, Pose2D.from_list(sim.true_pose()), (0.0,))
        loc = localize(robot, vmap, cfg)  # type: ignore[arg-type]
        assert not robot.motion.moveIsActive()
    assert len(seen) == 1 and not seen[0].found
    assert loc.extra_turns == 0 and len(loc.queries) == len(SCAN_YAWS)
    assert loc.estimate.method == "floorlines" and loc.estimate.found


@pytest.mark.parametrize("floor_ran", [True, False], ids=["floor-step-ran", "no-floor-step"])
def test_an_unverified_guess_the_floor_leaves_standing_is_no_estimate(
    monkeypatch: pytest.MonkeyPatch, floor_ran: bool
) -> None:
    """A keyframe-bearing guess the floor step checked but neither confirmed nor replaced
    is reported as no estimate (kept in the details); without a floor step it stays."""
    import importlib

    module = importlib.import_module("naoloc.behaviours.localize")

    def floor_fix(
        _r: Any, _v: Any, _c: Any, _q: Any, _f: Any, est: Estimate, _m: Any, *_: Any
    ) -> Estimate:
        if floor_ran:
            est.details.update(floor_lines=4, floor_candidates=2, floor_support=12)
        return est

    monkeypatch.setattr(module, "_floor_fix", floor_fix)

    class Guessing(TruthMap):
        def localize(self, queries: Sequence[Keyframe], mode: str = "verified") -> Estimate:
            est = super().localize(queries, mode)
            return Estimate(est.x + 2.0, est.y, est.theta, 0.1, mode, {"method": "keyframes"})

    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        vmap = Guessing(robot, Pose2D.from_list(sim.true_pose()), (0.0, 0.0))
        loc = localize(robot, vmap, cfg)  # type: ignore[arg-type]
    est = loc.estimate
    if floor_ran:
        assert not est.found and loc.summary()["method"] == "none"
        assert loc.summary()["x"] is None and loc.error_m is None
        assert est.details["unverified"]["method"] == "keyframes"
        assert len(est.details["unverified"]["pose"]) == 3
    else:
        assert est.found and est.method == "keyframes" and est.confidence == 0.1


def test_heading_after_turns_comes_from_the_last_sweep() -> None:
    from naoloc.behaviours.localize import _heading_from_last_sweep

    class Tail:
        def __init__(self, method: str) -> None:
            self.method = method

        def localize_features(
            self,
            feats: Sequence[None],
            queries: Sequence[Keyframe],
            mode: str = "verified",
            memo: object = None,
        ) -> Estimate:
            return Estimate(9.0, 9.0, 0.5, 0.9, mode, {"method": self.method})

    combined = Estimate(1.0, 2.0, 0.2, 0.8, "verified", {"method": "pnp"})
    got = _heading_from_last_sweep(Tail("pnp"), [], [], combined, "verified")  # type: ignore[arg-type]
    assert (got.x, got.y, got.theta) == (1.0, 2.0, 0.5)  # position kept, heading replaced
    kept = _heading_from_last_sweep(Tail("keyframes"), [], [], combined, "verified")  # type: ignore[arg-type]
    assert kept == combined  # keyframe bearings do not replace a PnP heading
    rough = Estimate(1.0, 2.0, 0.2, 0.3, "verified", {"method": "keyframes"})
    got = _heading_from_last_sweep(Tail("keyframes"), [], [], rough, "verified")  # type: ignore[arg-type]
    assert (got.x, got.y, got.theta) == (1.0, 2.0, 0.5)  # but they replace the same, combined


def naoloc_modulo(angle: float) -> float:
    """Angle wrapped into (-pi, pi]."""
    from naoloc.geometry import modulo2PI

    return modulo2PI(angle)


def test_go_home_plans_around_a_blocked_walk() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(2.2, 2.1, -2.0)
        real_move = robot.motion.moveTo
        moves: list[tuple[float, ...]] = []

        def first_walk_blocked(*args: Any, **kwargs: Any) -> bool:
            moves.append(tuple(float(a) for a in args))
            if len(moves) == 1:
                return False  # an obstacle on the way home
            return bool(real_move(*args, **kwargs))

        robot.motion.moveTo = first_walk_blocked  # type: ignore[method-assign]
        vmap = TruthMap(robot, origin, (0.0, 0.0))
        result = go_home(robot, vmap, cfg, leg_m=5.0)  # type: ignore[arg-type]
    assert result.reached and result.error_m is not None and result.error_m < 0.15
    assert result.tries >= 2 and len(result.blocked_at) == 1
    summary = result.summary()
    assert summary["reached"] and summary["path_m"] > 1.0 and summary["blocked"] == 1
    assert summary["method"] == "filter" and len(summary["covariance"]) == 3


def test_go_home_steps_when_nothing_is_recognised() -> None:
    cfg = small_cfg()
    with connect(cfg) as robot:
        sim = robot.sim
        assert sim is not None
        origin = Pose2D.from_list(sim.true_pose())
        sim.teleport(1.5, 1.5, 0.0)
        vmap = UnsureMap(robot, origin, (0.0, 0.0, 0.0, 0.0, 0.99))
        result = go_home(robot, vmap, cfg)  # type: ignore[arg-type]
    # Lost all around (4 sweeps), one step forward, then a confident estimate leads home.
    n = len(SCAN_YAWS)  # pictures per sweep
    assert vmap.calls[:5] == [n, 2 * n, 3 * n, 4 * n, n]
    assert result.reached and result.error_m is not None and result.error_m < 0.15


def test_go_home_legs_stop_short_and_stalls_are_seen() -> None:
    from naoloc.behaviours.go_home import FINAL_LEG_M, _leg_length, _stalled

    here = Pose2D(1.5, 0.0, math.pi)
    home = [Pose2D(0.0, 0.0)]
    assert _leg_length(here, home, 2.0) == pytest.approx(1.5 - FINAL_LEG_M / 2)
    assert _leg_length(Pose2D(0.5, 0.0), home, 2.0) == 2.0  # near: the whole way
    assert _leg_length(Pose2D(4.0, 0.0), home, 2.0) == 2.0  # far: a full leg
    # 0.5 m of odometry, but the fixes before and after are 5 cm apart: blocked ahead.
    bump = _stalled((Pose2D(2.0, 1.0), 0.5, 0.0), Pose2D(2.05, 1.0))
    assert bump is not None and bump.x == pytest.approx(2.05 + 0.3) and bump.y == 1.0
    assert _stalled((Pose2D(2.0, 1.0), 0.5, 0.0), Pose2D(2.45, 1.0)) is None
