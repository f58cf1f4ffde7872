"""A survey that checks itself and a map that is checked, end to end on the fake backend
(issue 31): a wall in the way stops the survey in one line with its partial dataset kept;
build-map refuses that survey, and a survey steered by the wrong (far) wall, naming the
check; ``--keep-unchecked`` keeps the map, marked unchecked.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.config import load_config
from naoloc.data.dataset import DatasetWriter, partial_path_for, read_dataset
from naoloc.errors import SurveyBlocked, SurveyError
from naoloc.mapping import load_map
from naoloc.mapping.checks import map_checked

pytest.importorskip("naoloc.backends.fake")

ROOM: dict[str, Any] = {
    "robot": {"backend": "fake"},
    "world": {
        "room": {"size_m": [3.0, 3.0], "seed": 5, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
    },
    "survey": {"laps": 1, "step_m": 0.25, "wall_offset_m": 0.75, "skirting_m": 0.0},
    "map": {"neurons": 30, "epochs": 20, "vocabulary_size": 64},
}


def _cfg(tmp_path: Path, name: str = "cfg.yaml", **changes: Any) -> Path:
    data = json.loads(json.dumps(ROOM))
    for key, value in changes.items():
        data.setdefault(key, {}).update(value)
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def _last_json(out: str) -> dict[str, Any]:
    return json.loads(out.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def blocked(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """A survey whose first side runs into the wall ahead: started 1.5 m from it, the
    circuit's first side 2 m long (config), the wall on the right at the offset."""
    tmp = tmp_path_factory.mktemp("blocked")
    cfg = _cfg(tmp, world={"start_pose": [1.5, 0.75, 0.0]}, survey={"side_m": [2.0, 1.5]})
    out = tmp / "s.mcap"
    import contextlib
    import io

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["survey", "-c", str(cfg), "-o", str(out)])
    assert code == 1
    return cfg, out, err.getvalue()


def test_a_wall_in_the_way_stops_the_survey_in_one_line(blocked: tuple[Path, Path, str]) -> None:
    _, out, err = blocked
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "blocked on side 1 of lap 1 after" in lines[0]
    assert "the wall ahead is" in lines[0]
    assert not out.exists()  # never written as complete
    data = read_dataset(partial_path_for(out))
    assert not data.complete
    assert data.meta["reason"].startswith("blocked on side 1 of lap 1")
    assert len(data.keyframes) >= 1  # the steps walked are kept
    assert len(data.meta["vision"]) == len(data.keyframes)  # with what the survey measured


def test_build_map_refuses_a_survey_that_ran_into_a_wall(
    blocked: tuple[Path, Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg, out, _ = blocked
    partial = partial_path_for(out)
    if len(read_dataset(partial).keyframes) < 3:
        pytest.skip("too few frames for a map")  # pragma: no cover - the room gives 4
    code = main(["build-map", "-c", str(cfg), "-d", str(partial), "-o", str(tmp_path / "m.npz")])
    err = capsys.readouterr().err
    assert code == 1
    assert len(err.strip().splitlines()) == 1
    assert "failed its survey_complete check" in err and "blocked on side 1" in err
    assert not (tmp_path / "m.npz").exists()


def test_a_robot_beside_no_wall_is_refused_before_it_walks(tmp_path: Path) -> None:
    cfg = load_config(
        json.loads(json.dumps(ROOM))
        | {"world": {**ROOM["world"], "room": {"size_m": [6.0, 6.0], "seed": 5,
                                               "style": "posters"},
                     "start_pose": [3.0, 3.0, 0.0]}}
    )  # fmt: skip
    from naoloc import connect
    from naoloc.behaviours import survey

    with connect(cfg) as robot:
        with pytest.raises(SurveyError, match="no wall to follow"):
            survey(robot, cfg, lambda kf, lap, odo: None)
        assert robot.sim is not None
        x, y, _ = robot.sim.true_pose()
    assert math.hypot(x - 3.0, y - 3.0) < 0.01  # it did not walk


def _far_wall_survey(source: Path, target: Path) -> None:
    """``source``'s survey as a robot steering by the far wall would have recorded it: its
    side lines see the wall across the room (the issue's mirrored survey), not the one
    beside it."""
    data = read_dataset(source)
    meta = dict(data.meta)
    width = 3.0 - 0.75  # the far wall, seen from the circuit
    meta["vision"] = [
        {**v, "side": None if v["side"] is None else {**v["side"], "distance_m": width}}
        for v in meta["vision"]
    ]
    meta["start_side"] = {**meta["start_side"], "distance_m": width}
    writer = DatasetWriter(target, config=data.config, meta=meta)
    for kf, lap in zip(data.keyframes, data.laps, strict=True):
        writer.write(kf, lap=lap, odometry=kf.pose)
    writer.close(complete=True)


def test_build_map_refuses_a_survey_beside_the_wrong_wall_unless_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = _cfg(tmp_path)
    good = tmp_path / "good.mcap"
    assert main(["survey", "-c", str(cfg), "-o", str(good)]) == 0
    capsys.readouterr()
    assert main(["build-map", "-c", str(cfg), "-d", str(good), "-o", str(tmp_path / "g.npz")]) == 0
    out = capsys.readouterr().out
    summary = _last_json(out)
    assert summary["checked"] is True
    assert {c["name"] for c in summary["checks"]} >= {
        "survey_complete", "wall_poses", "coverage", "wall_fit", "loop_closure", "odometry",
        "room_size",
    }  # fmt: skip
    assert all(c["verdict"] in ("pass", "skip") for c in summary["checks"])
    assert "build-map check: coverage" in out  # printed before the result line
    assert map_checked(load_map(tmp_path / "g.npz"))

    wrong = tmp_path / "wrong.mcap"
    _far_wall_survey(good, wrong)
    code = main(["build-map", "-c", str(cfg), "-d", str(wrong), "-o", str(tmp_path / "w.npz")])
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert "failed its wall_poses check" in err or "failed its coverage check" in err
    assert not (tmp_path / "w.npz").exists()

    code = main(["build-map", "-c", str(cfg), "-d", str(wrong), "-o", str(tmp_path / "w.npz"),
                 "--keep-unchecked"])  # fmt: skip
    summary = _last_json(capsys.readouterr().out)
    assert code == 0 and summary["checked"] is False
    assert not map_checked(load_map(tmp_path / "w.npz"))
    assert load_map(tmp_path / "w.npz").meta["checked"] is False


def test_survey_blocked_is_a_motion_error() -> None:
    from naoloc.errors import MotionError

    assert issubclass(SurveyBlocked, MotionError)  # the evaluation's survey task catches it
