"""tools/eval_tracking.py's figures: the pose rate over the robot time tracked, and when a
carried robot counts as recovered (a table of synthetic tracks)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from tests.tools import load_tool

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "eval_tracking.py"
pytestmark = pytest.mark.skipif(not TOOL.is_file(), reason="needs the checkout's tools/")


def _tool() -> ModuleType:
    return load_tool("eval_tracking")


def _track(t0: float, n: int, dt: float, error: float | None, conf: float = 1.0) -> list:
    return [
        {"t": t0 + i * dt, "found": error is not None, "error_m": error, "cpu_s": 0.02,
         "confidence": conf if error is not None else 0.0, "frame": i % 3 == 0}
        for i in range(n)
    ]  # fmt: skip


def test_the_pose_rate_counts_the_robot_time_of_each_walk() -> None:
    """Two walks of 10 poses a second, the second's clock starting again at 0 (another
    room) or 30 s later (a look between): 10 Hz both, not the clocks' span."""
    tool = _tool()
    one = _track(100.0, 101, 0.1, 0.02)
    for t0 in (0.0, 140.0):
        figures = tool._figures(one + _track(t0, 101, 0.1, 0.02))
        assert figures["rate_hz"] == pytest.approx(10.1, abs=0.05)


@pytest.mark.parametrize(
    ("track", "recovered", "wrong"),
    [
        # Tracked within 0.45 m from 1 s after the carry (at 10 s) for 10 s and more.
        ([*_track(10.0, 10, 0.1, None), *_track(11.0, 120, 0.1, 0.05)], 1.0, 0),
        # Five confident poses 2 m off first: recovered later, the five counted.
        ([*_track(10.0, 5, 0.1, 2.0), *_track(10.5, 120, 0.1, 0.05)], 0.5, 5),
        # Unsure poses 2 m off (confidence 0.2) are not confident wrong ones.
        ([*_track(10.0, 5, 0.1, 2.0, 0.2), *_track(10.5, 120, 0.1, 0.05)], 0.5, 0),
        # Never 10 s in a row: not recovered.
        (
            [
                *_track(10.0, 60, 0.1, 0.05),
                *_track(16.0, 5, 0.1, None),
                *_track(16.5, 60, 0.1, 0.05),
            ],
            None,
            0,
        ),
    ],
)
def test_a_carried_walk_recovers_after_ten_seconds_tracked(
    track: list[dict[str, Any]], recovered: float | None, wrong: int
) -> None:
    got, confident_wrong = _tool().recovery(track, 10.0)
    assert confident_wrong == wrong
    if recovered is None:
        assert got is None
    else:
        assert got == pytest.approx(recovered, abs=1e-6)
