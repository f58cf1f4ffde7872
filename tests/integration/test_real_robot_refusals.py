"""Issue 33, item 1: verbs refuse a real robot's unsafe config before they connect."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from naoloc.app.cli import main

# A closed loopback port: a verb that tried to connect would fail with "cannot connect".
NAO = {"robot": {"backend": "naoqi", "url": "tcp://127.0.0.1:9", "timeout_s": 0.5}}


def _write(tmp: Path, cfg: dict[str, object]) -> Path:
    path = tmp / "nao.yaml"
    path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
    return path


def test_demo_refuses_a_real_robot_before_connecting(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "demo"
    code = main(["demo", "-c", str(_write(tmp_path, NAO)), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and "needs a simulated robot" in err and "connect" not in err
    assert not out.exists()


def test_survey_refuses_a_real_robot_without_its_rectangle(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "s.mcap"
    code = main(["survey", "-c", str(_write(tmp_path, NAO)), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and "survey.side_m is not set" in err
    assert not list(tmp_path.glob("s*"))


def test_the_shipped_nao_config_is_safe() -> None:
    from naoloc.behaviours.wall_follow import MIN_OFFSET_M
    from naoloc.config import load_config

    cfg = load_config("nao")
    assert cfg.robot.backend == "naoqi" and not cfg.robot.sim_service
    assert cfg.survey.wall_offset_m >= 0.65 > MIN_OFFSET_M
    assert cfg.survey.side_m is not None and cfg.robot.move_timeout_s <= 60
