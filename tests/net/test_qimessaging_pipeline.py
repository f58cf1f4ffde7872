"""survey -> build-map -> localize over naoloc's QiMessaging equals the in-process result.

Both with ``naoloc serve --transport qimessaging`` and, where the qi package is
installed, a qimessaging client against ``naoloc serve --transport libqi``.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
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
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },  # the pre-issue-11 world: not about realism
    "survey": {"laps": 1, "step_m": 0.4},
    "map": {"neurons": 30, "epochs": 10, "vocabulary_size": 32, "seed": 4},
}
AT = ["1.4", "2.2", "0.6"]  # room frame
SERVERS = [
    "qimessaging",
    pytest.param(
        "libqi",
        marks=pytest.mark.skipif(
            importlib.util.find_spec("qi") is None, reason="qi not installed: no libqi server"
        ),
    ),
]


def _run(verb: list[str]) -> dict[str, Any]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(verb)
    assert code == 0, err.getvalue()
    result: dict[str, Any] = json.loads(out.getvalue().strip().splitlines()[-1])
    return result


def _pipeline(robot: dict[str, Any], tmp: Path, name: str) -> tuple[Path, dict[str, Any]]:
    cfg = tmp / f"{name}.yaml"
    cfg.write_text(yaml.safe_dump({**ROOM, "robot": robot}), encoding="utf-8")
    data, map_path = tmp / f"{name}.mcap", tmp / f"{name}.npz"
    _run(["survey", "-c", str(cfg), "-o", str(data)])
    _run(["build-map", "-c", str(cfg), "-d", str(data), "-o", str(map_path)])
    found = _run(["localize", "-c", str(cfg), "-m", str(map_path), "--at", *AT])
    return map_path, found


@pytest.fixture(scope="module")
def in_process(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """The in-process result, computed once for every server transport."""
    return _pipeline({"backend": "fake"}, tmp_path_factory.mktemp("local"), "local")


@pytest.mark.parametrize("server_transport", SERVERS)
def test_qimessaging_pipeline_matches_in_process(
    server_transport: str, tmp_path: Path, in_process: tuple[Path, dict[str, Any]]
) -> None:
    local_map, local = in_process
    # The server's clock at 50 x real time, as in test_naoqi_pipeline: at 1.0 the survey's
    # walking and head moves take over two minutes of waiting.
    with served({**ROOM, "robot": {"backend": "fake"}}, server_transport, speed=50.0) as server:
        robot = server.client_config(sim_service=True)["robot"]
        robot["transport"] = "qimessaging"
        net_map, net = _pipeline(robot, tmp_path, "net")
    a, b = load_map(local_map), load_map(net_map)
    assert a.images == b.images > 0
    np.testing.assert_array_equal(a.keyframe_poses, b.keyframe_poses)
    np.testing.assert_array_equal(a.keyframe_heads, b.keyframe_heads)
    np.testing.assert_array_equal(a.histograms, b.histograms)
    np.testing.assert_array_equal(a.neuron_poses, b.neuron_poses)
    # As in test_naoqi_pipeline: the served robot persists between commands, so the
    # localization's odometry noise differs from a fresh in-process robot by millimetres.
    assert abs(local["x"] - net["x"]) < 0.01 and abs(local["y"] - net["y"]) < 0.01
    assert abs(local["theta"] - net["theta"]) < np.radians(0.5)
