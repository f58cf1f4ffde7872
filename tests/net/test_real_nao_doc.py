"""Issue 33, item 1: docs/real-nao.md walked end to end against ``naoloc serve`` as the NAO.

The served robot has no NaolocSim for the client (no ``robot.sim_service``), as a real
NAO; ``serve --trace`` records every call the client makes. A refusing ``demo`` makes no
call at all, ``check`` no motion call, ``check --nod`` moves the head alone; then the
guide's survey -> build-map -> localize runs with the shipped configs/nao.yaml (address,
rectangle and laps edited as the guide says).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.backends.naoqi.testing import served

pytestmark = pytest.mark.net

ROOT = Path(__file__).resolve().parents[2]
ROOM: dict[str, Any] = {
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },
    "survey": {"wall_offset_m": 0.7},  # the robot placed as the guide says
}
# Calls that read and never move anything (stopMove ends a motion: allowed anywhere).
READS = {
    "ALMotion.getRobotPosition", "ALMotion.getAngles", "ALMotion.getTransform",
    "ALMotion.robotIsWakeUp", "ALMotion.stopMove", "ALRobotPosture.getPosture",
    "ALVideoDevice.subscribeCamera", "ALVideoDevice.getImageRemote",
    "ALVideoDevice.unsubscribe", "ALVideoDevice.getHorizontalFOV",
    "ALVideoDevice.getVerticalFOV", "ALBattery.getBatteryCharge", "NaolocWatchdog.ping",
}  # fmt: skip
NOD = {"ALMotion.setStiffnesses", "ALMotion.angleInterpolationWithSpeed"}


def _calls(trace: Path, since: int) -> list[str]:
    lines = trace.read_text(encoding="utf-8").splitlines()[since:]
    return [line.split(" ", 1)[1] for line in lines]


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def _nao_config(url: str, transport: str, path: Path) -> Path:
    """configs/nao.yaml as the guide has the owner edit it: address, rectangle, laps."""
    cfg = yaml.safe_load((ROOT / "configs" / "nao.yaml").read_text(encoding="utf-8"))
    cfg["robot"].update(url=url, transport=transport)
    cfg["survey"].update(laps=1, step_m=0.4, side_m=[2.4, 2.4])
    cfg["map"].update(neurons=30, epochs=10, vocabulary_size=32)
    path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
    return path


@pytest.mark.slow
def test_the_real_nao_guide_against_a_served_robot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = tmp_path / "calls.txt"
    served_cfg = {**ROOM, "robot": {"backend": "fake"}}
    with served(served_cfg, "zmq", speed=50.0, args=["--trace", str(trace)]) as server:
        cfg = _nao_config(server.url, "zmq", tmp_path / "nao.yaml")

        code, out, err = _run(["demo", "-c", str(cfg), "-o", str(tmp_path / "demo")], capsys)
        assert code == 1 and "needs a simulated robot" in err, err
        assert _calls(trace, 0) == []  # refused before connecting: not one call
        assert not (tmp_path / "demo").exists()

        code, out, err = _run(["check", "-c", str(cfg)], capsys)
        assert code == 0, err
        found = json.loads(out.strip().splitlines()[-1])
        assert found["ok"] and found["missing"] == []
        assert found["battery"]["charge_percent"] == 100
        assert found["camera"]["width"] == 320 and found["camera"]["lens"]["fx"] == 278.5
        calls = _calls(trace, 0)
        assert "ALVideoDevice.getImageRemote" in calls and "ALBattery.getBatteryCharge" in calls
        assert set(calls) <= READS, sorted(set(calls) - READS)
        seen = len(trace.read_text(encoding="utf-8").splitlines())

        code, out, err = _run(["check", "-c", str(cfg), "--nod"], capsys)
        assert code == 0, err
        assert json.loads(out.strip().splitlines()[-1])["nod"]["moved_rad"] > 0.1
        nod = _calls(trace, seen)
        assert set(nod) <= READS | NOD and set(nod) >= NOD

        data, vmap = tmp_path / "survey.mcap", tmp_path / "map.npz"
        code, out, err = _run(["survey", "-c", str(cfg), "-o", str(data)], capsys)
        assert code == 0, err
        code, out, err = _run(
            ["build-map", "-c", str(cfg), "-d", str(data), "-o", str(vmap)], capsys
        )
        assert code == 0, err
        code, out, err = _run(["localize", "-c", str(cfg), "-m", str(vmap)], capsys)
        assert code in (0, 3), err  # 3: nothing recognised, still one JSON line
        assert "x" in json.loads(out.strip().splitlines()[-1])


def test_check_says_what_is_missing_on_a_real_robot_config(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = tmp_path / "calls.txt"
    with served(
        {**ROOM, "robot": {"backend": "fake"}}, "zmq", args=["--trace", str(trace)]
    ) as server:
        cfg = yaml.safe_load((ROOT / "configs" / "nao.yaml").read_text(encoding="utf-8"))
        cfg["robot"].update(url=server.url, transport="zmq")
        cfg["survey"]["side_m"] = None  # a real robot must be given its rectangle
        path = tmp_path / "nao.yaml"
        path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
        code, out, err = _run(["check", "-c", str(path)], capsys)
    assert code == 4, err
    found = json.loads(out.strip().splitlines()[-1])
    assert not found["ok"] and any("survey.side_m" in m for m in found["missing"])
    assert "check: missing" in out and "survey.side_m" in err
    assert set(_calls(trace, 0)) <= READS


def test_every_command_in_the_guide_parses() -> None:
    from naoloc.app.cli import build_parser

    text = (ROOT / "docs" / "real-nao.md").read_text(encoding="utf-8")
    lines = [ln.split("#")[0].strip() for ln in text.splitlines() if ln.startswith("naoloc ")]
    assert len(lines) >= 6
    parser = build_parser()
    for line in lines:
        parser.parse_args(line.rstrip("&").split()[1:])  # exits 2 on a stale flag
