"""The localization's floor step: when it replaces the estimate, and when it must not.

The floor lines and the landmark vote are replaced by stand-ins (the geometry is
``test_floorfix.py``'s, the vote ``test_mapping_localize.py``'s); what is tested is the rule
in :func:`naoloc.behaviours.localize._floor_fix`.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from collections.abc import Callable, Sequence
from types import SimpleNamespace
from typing import Any

import pytest
from yaml import safe_load

from naoloc.config import load_config
from naoloc.errors import ConfigError
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.mapping.localizer import Estimate, no_estimate
from naoloc.perception.floorline import WallLine

# The module, not the function naoloc.behaviours re-exports under the same name.
loc = importlib.import_module("naoloc.behaviours.localize")
sup = importlib.import_module("naoloc.mapping.support")
TRUTH = Pose2D(1.2, 0.7, 0.4)  # map frame = wall frame here
META = {"wall_poses": {"wall_frame": [0.0, 0.0, 0.0], "walls_m": [-1.0, 4.0, -1.0, 3.0]}}


def _patch(
    monkeypatch: pytest.MonkeyPatch,
    support: Callable[[Any, Any, Any, Sequence[Pose2D]], list[int]],
    peaks: Callable[..., list[tuple[float, int]]] | None = None,
) -> None:
    """Stand-ins for the landmarks: ``support`` votes, ``peaks`` places along an axis
    (:func:`naoloc.mapping.support.axis_peaks`'s arguments after the matches; none by
    default)."""
    monkeypatch.setattr(sup, "support_matches", lambda *_a, **_k: None)
    monkeypatch.setattr(sup, "pose_support", lambda v, f, q, poses, **_k: support(v, f, q, poses))
    monkeypatch.setattr(
        sup, "axis_peaks", lambda _m, *a, **k: [] if peaks is None else peaks(*a, **k)
    )


def _lines() -> list[WallLine]:
    dists = (4.0 - TRUTH.x, 3.0 - TRUTH.y, TRUTH.x + 1.0, TRUTH.y + 1.0)
    return [
        WallLine(d, modulo2PI(k * math.pi / 2 - TRUTH.theta), 200, 0.9, 0.005, 1.0)
        for k, d in enumerate(dists)
    ]


def _run(
    monkeypatch: pytest.MonkeyPatch, estimate: Estimate, vote: dict[str, int]
) -> tuple[Estimate, list[int]]:
    """``_floor_fix`` with exact lines; the vote gives ``vote['truth']`` to the candidate at
    the truth, ``vote['other']`` to one other place, 0 to the rest."""
    calls: list[int] = []

    def support(_vmap: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        calls.append(len(poses))
        out = []
        other_given = False
        for p in poses:
            if math.hypot(p.x - TRUTH.x, p.y - TRUTH.y) < 0.01:
                out.append(vote["truth"])
            elif not other_given:
                out.append(vote["other"])
                other_given = True
            else:
                out.append(0)
        return out

    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _lines())
    _patch(monkeypatch, support)
    vmap = SimpleNamespace(meta=META)
    return loc._floor_fix(None, vmap, None, [], [], estimate, loc.CpuMeter()), calls  # type: ignore[arg-type]


def test_a_clear_vote_replaces_a_fallback(monkeypatch: pytest.MonkeyPatch) -> None:
    guess = Estimate(2.5, 2.0, 0.1, 0.1, "verified", {"method": "keyframes"})
    est, _ = _run(monkeypatch, guess, {"truth": 60, "other": 20})
    assert est.method == "floorlines" and est.confidence == loc.FLOOR_CONFIDENCE
    assert math.hypot(est.x - TRUTH.x, est.y - TRUTH.y) < 1e-6
    assert abs(modulo2PI(est.theta - TRUTH.theta)) < 1e-6
    assert est.details["replaced"]["method"] == "keyframes"


def test_a_clear_vote_gives_a_pose_where_there_was_none(monkeypatch: pytest.MonkeyPatch) -> None:
    est, _ = _run(
        monkeypatch, no_estimate("verified", "no verified match"), {"truth": 40, "other": 5}
    )
    assert est.found and est.method == "floorlines"


@pytest.mark.parametrize(
    "vote",
    [{"truth": 60, "other": 55}, {"truth": loc.FLOOR_MIN_SUPPORT - 1, "other": 0}],
    ids=["two-places-nearly-equal", "too-little-support"],
)
def test_an_unclear_vote_changes_nothing(
    monkeypatch: pytest.MonkeyPatch, vote: dict[str, int]
) -> None:
    est, _ = _run(monkeypatch, no_estimate("verified", "no verified match"), vote)
    assert not est.found and est.method == "none"
    guess = Estimate(2.5, 2.0, 0.1, 0.1, "verified", {"method": "keyframes"})
    est, _ = _run(monkeypatch, guess, vote)
    assert est.method == "keyframes" and (est.x, est.y) == (2.5, 2.0)


def test_a_pnp_pose_the_floor_confirms_takes_the_floor_pose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pnp = Estimate(TRUTH.x + 0.12, TRUTH.y - 0.08, TRUTH.theta + 0.05, 0.8, "verified",
                   {"method": "pnp", "inliers": 40})  # fmt: skip
    est, calls = _run(monkeypatch, pnp, {"truth": 60, "other": 0})
    assert est.method == "pnp" and est.confidence == 0.8 and est.details["inliers"] == 40
    assert math.hypot(est.x - TRUTH.x, est.y - TRUTH.y) < 1e-6
    assert abs(modulo2PI(est.theta - TRUTH.theta)) < 1e-6
    assert (
        est.details["floor_confirmed"]
        and est.details["floor_refined"]["pnp"] == pnp.pose().to_list()
    )
    # One floor pose confirms it: no choice, so no vote (nor the matching it needs)
    assert calls == [] and "floor_support" not in est.details
    assert "floor_refined" not in pnp.details  # the PnP estimate itself is left as it was


def test_a_confirmed_pnp_pose_takes_the_best_supported_nearby_pose(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two floor poses near the PnP pose (a line of furniture 0.15 m in front of a wall):
    the vote picks the one the pictures support, not the one nearer the PnP pose."""
    lines = _lines()
    furniture = dataclasses.replace(lines[0], distance=lines[0].distance - 0.15)
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: [*lines, furniture])

    def support(_vmap: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        return [50 if math.hypot(p.x - TRUTH.x, p.y - TRUTH.y) < 0.01 else 30 for p in poses]

    _patch(monkeypatch, support)
    pnp = Estimate(TRUTH.x + 0.11, TRUTH.y, TRUTH.theta, 0.8, "verified", {"method": "pnp"})
    vmap = SimpleNamespace(meta=META)
    est = loc._floor_fix(None, vmap, None, [], [], pnp, loc.CpuMeter())  # type: ignore[arg-type]
    assert math.hypot(est.x - TRUTH.x, est.y - TRUTH.y) < 1e-6
    assert est.details["floor_candidates"] >= 2 and est.details["floor_support"] == 50


def test_a_pnp_pose_the_floor_contradicts_is_replaced(monkeypatch: pytest.MonkeyPatch) -> None:
    wrong = Estimate(3.0, 2.5, -1.0, 0.4, "verified", {"method": "pnp"})
    est, calls = _run(monkeypatch, wrong, {"truth": 60, "other": 10})
    assert len(calls) == 1 and est.method == "floorlines"
    assert math.hypot(est.x - TRUTH.x, est.y - TRUTH.y) < 1e-6


def _hidden_y_walls() -> list[WallLine]:
    """The x walls' lines, and a bookcase 0.5 m in front of the +y wall hiding it (the -y
    wall out of sight): y is bounded (at most TRUTH.y + 0.5) but not given."""
    xp, yp, xm, _ = _lines()
    return [xp, xm, dataclasses.replace(yp, distance=yp.distance - 0.5)]


def test_a_pnp_pose_no_line_contradicts_keeps_the_axis_the_lines_do_not_pin(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _hidden_y_walls())
    est = _vote_between(monkeypatch, kept=60, bookcase=30)
    assert est.method == "pnp" and est.confidence == 0.7 and est.details["floor_consistent"]
    assert abs(est.x - TRUTH.x) < 1e-6  # pinned by the x walls' lines
    assert est.y == pytest.approx(TRUTH.y + 0.06)  # kept: only the bookcase bounds y
    assert abs(modulo2PI(est.theta - TRUTH.theta)) < 1e-6  # the lines' heading
    assert est.details["floor_refined"]["pnp"] == PNP.pose().to_list()
    assert est.details["floor_support"] == 60 and est.details["floor_rival"] == 30


@pytest.mark.parametrize("kept", [20, 80])  # out-voted; not out-voting it 1.5 times
def test_a_consistent_pnp_pose_that_does_not_clearly_win_the_vote_goes_to_the_vote(
    monkeypatch: pytest.MonkeyPatch, kept: int
) -> None:
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _hidden_y_walls())
    calls: list[int] = []
    est = _vote_between(monkeypatch, kept=kept, bookcase=60, calls=calls)
    assert len(calls) == 1  # the candidates' votes are counted once, with the PnP pose's
    assert est.method == "floorlines" and "floor_consistent" not in est.details
    assert est.y == pytest.approx(TRUTH.y + 0.5)  # the bookcase's pose won the vote


PNP = Estimate(TRUTH.x + 0.04, TRUTH.y + 0.06, TRUTH.theta + 0.03, 0.7, "verified",
               {"method": "pnp", "inliers": 30})  # fmt: skip


def _vote_between(
    monkeypatch: pytest.MonkeyPatch, kept: int, bookcase: int, calls: list[int] | None = None
) -> Estimate:
    """``_floor_fix`` of :data:`PNP` with a vote giving ``kept`` to the pose at the truth's
    x and the PnP pose's y, ``bookcase`` to the one at the bookcase's y, 0 elsewhere."""

    def support(_vmap: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        if calls is not None:
            calls.append(len(poses))

        def one(p: Pose2D) -> int:
            if abs(p.x - TRUTH.x) > 0.01:
                return 0
            return kept if abs(p.y - PNP.y) < 0.01 else bookcase if abs(p.y - 1.2) < 0.01 else 0

        return [one(p) for p in poses]

    _patch(monkeypatch, support)
    vmap = SimpleNamespace(meta=META)
    return loc._floor_fix(None, vmap, None, [], [], PNP, loc.CpuMeter())  # type: ignore[arg-type]


@pytest.mark.parametrize("truth_vote", [loc.FLOOR_SWEPT_MIN_SUPPORT + 10, 40])
def test_the_landmarks_give_the_axis_no_wall_line_gave(
    monkeypatch: pytest.MonkeyPatch, truth_vote: int
) -> None:
    """y has only the bookcase's line: the landmarks' place along y (the truth's) is a
    candidate, and wins the vote if it is clearly and well supported."""
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _hidden_y_walls())
    asked: list[tuple[int, float]] = []

    def peaks(_frame: Any, _theta: float, axis: int, fixed: float, span: Any) -> list[Any]:
        asked.append((axis, fixed))
        return [(TRUTH.y, 45)] if axis == 1 and span[0] <= TRUTH.y <= span[1] else []

    def support(_v: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        return [truth_vote if p.distance(TRUTH) < 0.01 else 10 for p in poses]

    _patch(monkeypatch, support, peaks)
    vmap = SimpleNamespace(meta=META)
    none = no_estimate("verified", "no verified match")
    est = loc._floor_fix(None, vmap, None, [], [], none, loc.CpuMeter())  # type: ignore[arg-type]
    assert (1, pytest.approx(TRUTH.x)) in asked  # along y, at the x walls' x
    assert est.details["floor_swept"] >= 1
    if truth_vote >= loc.FLOOR_SWEPT_MIN_SUPPORT:
        assert est.method == "floorlines" and est.details["floor_axis_from"] == "landmarks"
        assert est.pose().distance(TRUTH) < 1e-6
    else:  # too little support for a place only the landmarks give: no estimate
        assert not est.found


def test_only_the_lines_confirm_a_pnp_pose(monkeypatch: pytest.MonkeyPatch) -> None:
    """A landmarks' place next to the PnP pose does not confirm it (on a look-alike print
    both fit the same landmarks): the PnP pose is only checked against the lines."""
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _hidden_y_walls())

    def support(_v: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        return [100 if p.distance(TRUTH) < 0.1 else 10 for p in poses]

    _patch(monkeypatch, support, lambda _fr, _th, axis, _fx, _sp: [(TRUTH.y, 90)] * axis)
    vmap = SimpleNamespace(meta=META)
    est = loc._floor_fix(None, vmap, None, [], [], PNP, loc.CpuMeter())  # type: ignore[arg-type]
    assert est.details["floor_swept"] >= 1
    assert "floor_confirmed" not in est.details and est.details["floor_consistent"]
    assert est.y == pytest.approx(PNP.y)  # its own y: the lines do not pin it


def test_a_pnp_pose_behind_a_seen_line_is_contradicted(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: _hidden_y_walls())
    _patch(monkeypatch, lambda _v, _f, _q, poses: [0] * len(poses))
    # 0.4 m beyond the bookcase's bound (and from its candidate): the bookcase's line would
    # lie behind the +y wall.
    pnp = Estimate(TRUTH.x, TRUTH.y + 0.9, TRUTH.theta, 0.7, "verified", {"method": "pnp"})
    vmap = SimpleNamespace(meta=META)
    est = loc._floor_fix(None, vmap, None, [], [], pnp, loc.CpuMeter())  # type: ignore[arg-type]
    assert "floor_consistent" not in est.details and "floor_refined" not in est.details
    assert (est.x, est.y) == (pnp.x, pnp.y)  # no clear vote: left as it was


def test_a_map_without_walls_is_left_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(loc, "measure_floor_lines", lambda *_: pytest.fail("measured"))
    guess = Estimate(2.5, 2.0, 0.1, 0.1, "verified", {"method": "keyframes"})
    vmap = SimpleNamespace(meta={})
    assert loc._floor_fix(None, vmap, None, [], [], guess, loc.CpuMeter()) is guess  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("off", "off"),
        ("false", "off"),
        ("on", "always"),
        ("unsure", "unsure"),
        ("always", "always"),
    ],
)
def test_floor_lines_reads_yaml_words(text: str, value: str) -> None:
    cfg = load_config({"localize": {"floor_lines": safe_load(f"x: {text}")["x"]}})
    assert cfg.localize.floor_lines == value


def test_floor_lines_refuses_other_words() -> None:
    with pytest.raises(ConfigError, match="floor_lines"):
        load_config({"localize": {"floor_lines": "sometimes"}})


def test_another_map_gets_the_floor_step_from_the_lines_already_measured(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An evaluation re-scores a scan's pictures with other maps (features, neurons, drift
    levels): each gets the floor step with the lines the localization measured there,
    carried from before a turn in place, without the robot; a keyframe guess the vote
    cannot settle is no estimate, as in a localization; no lines, no step."""

    def support(_vmap: Any, _f: Any, _q: Any, poses: Sequence[Pose2D]) -> list[int]:
        return [60 if math.hypot(p.x - TRUTH.x, p.y - TRUTH.y) < 0.01 else 0 for p in poses]

    _patch(monkeypatch, support)
    vmap = SimpleNamespace(meta=META)
    cfg = load_config({"localize": {"floor_lines": "unsure"}})
    guess = Estimate(2.5, 2.0, 0.1, 0.1, "verified", {"method": "keyframes"})
    # Half the lines measured before a quarter turn in place (odometry: +pi/2), half after.
    lines = _lines()
    before = [dataclasses.replace(ln, normal=modulo2PI(ln.normal + math.pi / 2))
              for ln in lines[:2]]  # fmt: skip
    turned = Pose2D(0.0, 0.0, math.pi / 2)
    log = loc.FloorLog([(Pose2D(0.0, 0.0, 0.0), before), (turned, lines[2:])])
    est = loc.floor_step_again(vmap, cfg, [], [], guess, log)  # type: ignore[arg-type]
    assert est.method == "floorlines" and est.details["floor_carried"] == 2
    assert math.hypot(est.x - TRUTH.x, est.y - TRUTH.y) < 1e-6
    _patch(monkeypatch, lambda *_a: [10] * len(_a[3]))  # an even vote: nothing settles
    none = loc.floor_step_again(vmap, cfg, [], [], guess, log)  # type: ignore[arg-type]
    assert not none.found and none.details["unverified"]["method"] == "keyframes"
    assert loc.floor_step_again(vmap, cfg, [], [], guess, None) is guess  # type: ignore[arg-type]
    sure = Estimate(TRUTH.x, TRUTH.y, TRUTH.theta, 0.95, "verified", {"method": "pnp"})
    assert loc.floor_step_again(vmap, cfg, [], [], sure, log) is sure  # type: ignore[arg-type]
