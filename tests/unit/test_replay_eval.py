"""tools/replay_eval.py: which recorded localizations it replays, and its figures (a table
of synthetic replays)."""

from __future__ import annotations

import json
from pathlib import Path
from types import ModuleType

import pytest

from tests.tools import load_tool

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "replay_eval.py"
pytestmark = pytest.mark.skipif(not TOOL.is_file(), reason="needs the checkout's tools/")


def _tool() -> ModuleType:
    return load_tool("replay_eval")


def test_only_recorded_localizations_in_checked_maps_are_replayed(tmp_path: Path) -> None:
    """A refused map's room, a pose without a recording and another variant are left out."""
    rooms = [{"seed": 1, "map_checked": True}, {"seed": 2, "map_checked": False}]
    (tmp_path / "unseen_rooms.json").write_text(json.dumps({"rooms": rooms}), encoding="utf-8")
    for seed in (1, 2):
        room = tmp_path / f"room_{seed}"
        (room / "recordings").mkdir(parents=True)
        estimates = [
            {"variant": "main", "index": 0, "truth": [1.0, 2.0, 0.5]},
            {"variant": "main", "index": 1, "truth": [0.0, 0.0, 0.0]},
            {"variant": "paper", "index": 0, "truth": [1.0, 2.0, 0.5]},
        ]
        (room / "estimates.json").write_text(json.dumps(estimates), encoding="utf-8")
        (room / "recordings" / "main_000.mcap").write_bytes(b"")
    assert _tool().jobs([tmp_path]) == [(str(tmp_path / "room_1"), 0, [1.0, 2.0, 0.5])]


def test_the_figures_of_a_set_of_replays() -> None:
    """Outside the 99 % ellipse: a squared Mahalanobis distance over 9.21 (2 degrees of
    freedom); confident wrong: more than 0.3 m off at confidence 0.5 or more."""
    rows = [
        {"status": "tracking", "error_m": 0.01, "mahalanobis2": 1.0, "confidence": 0.99},
        {"status": "tracking", "error_m": 0.02, "mahalanobis2": 9.3, "confidence": 0.99},
        {"status": "tracking", "error_m": 0.40, "mahalanobis2": 50.0, "confidence": 0.7},
        {"status": "tracking", "error_m": 0.35, "mahalanobis2": 4.0, "confidence": 0.4},
        {"status": "lost"},
    ]
    figures = _tool().summarize(rows)
    assert figures["replays"] == 5 and figures["posed"] == 4 and figures["no_estimate"] == 1
    assert figures["outside_99"] == 2 and figures["outside_99_share"] == 0.5
    assert figures["confident_wrong"] == 1
    assert figures["median_m"] == pytest.approx(0.185)
    assert _tool().summarize([{"status": "lost"}])["median_m"] is None
