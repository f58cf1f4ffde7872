"""build-map's ``origin`` check: the start's own heading to its wall against its first
steps', held to the odometry's turn error over those steps (issue 31)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from naoloc.config import MapCheckTuning
from naoloc.mapping.checks import _origin


@pytest.mark.parametrize(
    ("own_deg", "frames_deg", "verdict"),
    [
        (0.2, -0.1, "pass"),
        # room 1787548163 with its own NAO's odometry: a right map (origin 0.02 m, heading
        # 0.5 deg) whose first steps' lines, less the odometry's turn, read 3.0 deg apart
        (0.35, -2.65, "pass"),
        # room 1835541671: the start's one view read 6.7 deg off its wall
        (-6.69, 1.08, "fail"),
        (179.0, -179.0, "pass"),  # across the wrap: 2 deg apart
        (None, 0.0, "skip"),
        (0.0, None, "skip"),
    ],
)
def test_origin_check(own_deg: float | None, frames_deg: float | None, verdict: str) -> None:
    def rad(v: float | None) -> float | None:
        return None if v is None else math.radians(v)

    walled = SimpleNamespace(start_own=rad(own_deg), start_frames=rad(frames_deg))
    check = _origin(walled, MapCheckTuning())
    assert check.verdict == verdict, check.line()
