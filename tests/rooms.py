"""Rooms and helpers the pipeline tests share."""

from __future__ import annotations

import json
from typing import Any

import pytest

from naoloc.app.cli import main

# A 4 x 4 m room of posters on ideal odometry and camera, one lap in 0.4 m steps and a small
# map: the pipeline's logic (CLI verbs, network, recordings), not realism.
PIPELINE_ROOM: dict[str, Any] = {
    "robot": {"backend": "fake"},
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },
    "survey": {"laps": 1, "step_m": 0.4},
    "map": {"neurons": 30, "epochs": 10, "vocabulary_size": 32, "seed": 4},
}


def run_json(argv: list[str], capsys: pytest.CaptureFixture[str], ok: int = 0) -> dict[str, Any]:
    """Run the CLI in-process; assert its exit code is ``ok``; its last stdout JSON line."""
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == ok, err
    result: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    return result
