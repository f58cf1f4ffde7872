"""Never a made-up pose: nothing recognised gives null pose fields, method none, exit 3."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from naoloc.app.cli import main
from naoloc.evaluation.protocols import PROTOCOL_BANDS, distance_to_walls, sample_protocol_poses
from naoloc.evaluation.stats import group_rows
from naoloc.localization import Localizer, Status

pytest.importorskip("naoloc.backends.fake")

ROOM = {"size_m": [3.0, 3.0], "seed": 5, "style": "posters"}
BASE = {
    "robot": {"backend": "fake"},
    # Exact odometry: a drifting survey walks into the wall of this small room; this test is
    # about what localize says when it recognises nothing.
    "world_odometry": {"profile": "ideal"},
    "survey": {"laps": 1, "step_m": 0.25, "wall_offset_m": 0.75},
    "map": {"neurons": 40, "epochs": 30, "vocabulary_size": 64},
}


def _cfg(path: Path, room: dict[str, object]) -> Path:
    data = {k: v for k, v in BASE.items() if k != "world_odometry"}
    data["world"] = {
        "room": room,
        "odometry": BASE["world_odometry"],
        "camera_realism": {"profile": "ideal"},  # the subject is the answer, not the camera
    }
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture(scope="module")
def textured_map(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("noest")
    cfg = _cfg(tmp / "a.yaml", ROOM)
    assert main(["survey", "-c", str(cfg), "-o", str(tmp / "s.mcap")]) == 0
    assert (
        main(["build-map", "-c", str(cfg), "-d", str(tmp / "s.mcap"), "-o", str(tmp / "m.npz")])
        == 0
    )
    return tmp / "m.npz"


@pytest.mark.slow
def test_blank_walls_exit_3_with_null_pose(
    textured_map: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    blank = _cfg(tmp_path / "blank.yaml", {**ROOM, "posters_per_wall": 0, "furniture": False})
    capsys.readouterr()
    code = main(
        ["localize", "-c", str(blank), "-m", str(textured_map), "--at", "1.0", "1.2", "0.5"]
    )
    out, err = capsys.readouterr()
    assert code == 3, err
    line = json.loads(out.strip().splitlines()[-1])
    assert line["x"] is None and line["y"] is None and line["theta"] is None
    assert line["confidence"] == 0 and line["method"] == "none"
    assert "error_m" not in line  # no estimate is never scored as one
    assert len(err.strip().splitlines()) == 1 and "no estimate" in err


def test_recognised_pose_exits_0_with_method(
    textured_map: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = _cfg(tmp_path / "a.yaml", ROOM)
    capsys.readouterr()
    assert (
        main(["localize", "-c", str(cfg), "-m", str(textured_map), "--at", "1.0", "1.2", "0.5"])
        == 0
    )
    line = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert line["method"] == "filter" and line["status"] == "tracking"
    assert line["error_m"] < 0.3


def test_no_observation_has_no_pose(textured_map: Path) -> None:
    from naoloc.mapping import load_map

    est = Localizer(load_map(textured_map)).pose()
    assert not est.found and est.method == "none" and est.confidence == 0.0
    assert est.status is Status.LOST and est.reason
    assert all(math.isnan(v) for v in (est.x, est.y, est.theta))


def test_misses_are_null_in_summary_rows() -> None:
    nan = float("nan")
    rows = group_rows(
        [
            {"group": 0, "truth": [1, 1, 0], "estimate": [1.1, 1, 0], "error_m": 0.1},
            {"group": 0, "truth": [1, 1, 0], "estimate": [nan, nan, nan], "error_m": nan},
        ]
    )
    assert rows[0]["estimates"] == [[1.1, 1.0], None]
    assert rows[0]["errors_m"] == [0.1, None] and rows[0]["mean_error_m"] is None
    json.dumps(rows, allow_nan=False)  # strict JSON


def test_anywhere_protocol_covers_the_interior() -> None:
    size = (6.0, 5.0)
    poses = sample_protocol_poses("anywhere", 400, 3, size, lambda x, y, c: True)
    d = np.array([distance_to_walls(p.room_pose[0], p.room_pose[1], size) for p in poses])
    lo = PROTOCOL_BANDS["anywhere"][0][0]
    assert d.min() >= lo and d.max() > 1.9  # the middle of the room is drawn too
    assert sample_protocol_poses("anywhere", 400, 3, size, lambda x, y, c: True) == poses
    random = sample_protocol_poses("random", 400, 3, size, lambda x, y, c: True)
    dr = np.array([distance_to_walls(p.room_pose[0], p.room_pose[1], size) for p in random])
    assert dr.max() <= 1.4


def test_anywhere_respects_furniture() -> None:
    def free(x: float, y: float, clearance: float) -> bool:
        return math.hypot(x - 3.0, y - 3.0) > 0.5 + clearance

    poses = sample_protocol_poses("anywhere", 200, 1, (6.0, 6.0), free)
    assert all(math.hypot(p.room_pose[0] - 3, p.room_pose[1] - 3) > 0.8 for p in poses)
