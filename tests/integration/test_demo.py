"""``naoloc demo`` finishes (exit 0) whatever the world does to the survey and the map.

The fake backend (ray-cast room, real NAO odometry model, real camera model), small rooms.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from naoloc.app.cli import main

BASE: dict[str, Any] = {
    "robot": {"backend": "fake"},
    "world": {"room": {"size_m": [3.0, 3.0], "seed": 5}},  # style home, honest odometry
    "survey": {"laps": 1, "step_m": 0.25, "wall_offset_m": 0.75},
    "map": {"neurons": 20, "epochs": 10, "vocabulary_size": 32},
}


def _run(tmp_path: Path, capsys: pytest.CaptureFixture[str], **changes: Any) -> dict[str, Any]:
    data = json.loads(json.dumps(BASE))
    for key, value in changes.items():
        data.setdefault(key, {}).update(value)
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(yaml.safe_dump(data))
    assert main(["demo", "-c", str(cfg), "-o", str(tmp_path / "demo")]) == 0
    out = capsys.readouterr().out
    summary: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    summary["_out"] = out
    return summary


@pytest.mark.slow
def test_demo_finishes_in_the_default_world(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Home room, a NAO's odometry: whatever the accuracy, the demo ends with its summary."""
    summary = _run(tmp_path, capsys)
    assert summary["n"] == len(summary["positions"])
    assert summary["no_estimate"] == sum(p["estimate"] is None for p in summary["positions"])
    for p in summary["positions"]:  # a miss has no made-up pose
        assert (p["estimate"] is None) == (p["error_m"] is None)


@pytest.mark.slow
def test_demo_goes_on_from_a_survey_that_stopped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The head looks left while the wall is on the right: the circuit turns into the wall."""
    summary = _run(
        tmp_path,
        capsys,
        world={"start_pose": [0.75, 0.75, 0.0], "odometry": {"profile": "ideal"}},
        survey={"head_yaw_rad": 1.5},
    )
    assert summary["survey_stopped"], summary["_out"]
    assert "demo: the survey stopped early: " in summary["_out"]
    assert summary["frames"] >= 3 and summary["map"] is not None
    assert summary["n"] >= 5
    assert summary["dataset"].endswith(".partial.mcap")


def test_demo_without_a_map_says_why_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Facing a wall 0.3 m away, the survey cannot take a step: no map, still exit 0."""
    summary = _run(
        tmp_path,
        capsys,
        world={"start_pose": [0.3, 1.5, math.pi], "odometry": {"profile": "ideal"}},
        survey={"head_yaw_rad": 1.5},
    )
    lines = [ln for ln in summary["_out"].splitlines() if ln.startswith("demo: no map: ")]
    assert len(lines) == 1, summary["_out"]
    assert summary["map"] is None and summary["n"] == 0 and summary["median_error_m"] is None
