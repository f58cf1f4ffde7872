"""survey -> build-map -> localize through `naoloc serve` gives what it gives in-process."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from naoloc.app.cli import main
from naoloc.backends.naoqi.testing import served
from naoloc.mapping import load_map

pytestmark = pytest.mark.net

ROOM: dict[str, Any] = {
    # Exact odometry: about the network; a NAO's drift walks this room's survey off course.
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },  # the pre-issue-11 world: pipeline logic, not realism
    # The nearest wall is found by parallax through the network too.
    "survey": {"laps": 1, "step_m": 0.4},
    "map": {"neurons": 30, "epochs": 10, "vocabulary_size": 32, "seed": 4},
}
AT = ["1.4", "2.2", "0.6"]  # room frame


def _run(verb: list[str], capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    code = main(verb)
    out, err = capsys.readouterr()
    assert code == 0, err
    result: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    return result


def _pipeline(
    robot: dict[str, Any], tmp: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> tuple[Path, dict[str, Any]]:
    cfg = tmp / f"{name}.yaml"
    cfg.write_text(yaml.safe_dump({**ROOM, "robot": robot}), encoding="utf-8")
    data, map_path = tmp / f"{name}.mcap", tmp / f"{name}.npz"
    _run(["survey", "-c", str(cfg), "-o", str(data)], capsys)
    _run(["build-map", "-c", str(cfg), "-d", str(data), "-o", str(map_path)], capsys)
    found = _run(["localize", "-c", str(cfg), "-m", str(map_path), "--at", *AT], capsys)
    return map_path, found


def test_network_pipeline_matches_in_process(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    local_map, local = _pipeline({"backend": "fake"}, tmp_path, "local", capsys)
    # The server's clock at 50 x real time: the survey's walking would take minutes at 1.0.
    with served({**ROOM, "robot": {"backend": "fake"}}, "zmq", speed=50.0) as server:
        robot = server.client_config(sim_service=True)["robot"]
        net_map, net = _pipeline(robot, tmp_path, "net", capsys)
    a, b = load_map(local_map), load_map(net_map)
    assert a.images == b.images > 0
    np.testing.assert_array_equal(a.keyframe_poses, b.keyframe_poses)
    np.testing.assert_array_equal(a.keyframe_heads, b.keyframe_heads)
    np.testing.assert_array_equal(a.histograms, b.histograms)
    np.testing.assert_array_equal(a.neuron_poses, b.neuron_poses)
    assert a.distinct_poses == b.distinct_poses
    # The same map, bit for bit. Localization runs on a robot that differs in one way: the
    # served robot persists between commands (it already walked the survey, so its odometry
    # noise generator has moved on), while in-process each command starts a fresh robot.
    # The turn-in-place odometry between queries differs by that noise: millimetres.
    assert abs(local["x"] - net["x"]) < 0.01 and abs(local["y"] - net["y"]) < 0.01
    assert abs(local["theta"] - net["theta"]) < np.radians(0.5)
    assert abs(local["error_m"] - net["error_m"]) < 0.01
