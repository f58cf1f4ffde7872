"""Behaviours: plain functions over the robot interface (Algorithm 3 and beyond).

- :func:`nearest_wall` / :func:`detect_nearest_wall`: the paper's Fig. 10 detector.
- :func:`survey`: Algorithm 3, closed laps with a picture after each step.
- :func:`localize`: head scan (or the paper's 1-2 pictures) -> the map's estimate.
- :func:`go_home`: localize, walk to the map origin, repeat.

They use only ``robot.motion``, ``robot.video`` and ``robot.posture`` (``robot.sim`` only
to report the truth), so they run unchanged on every backend.
"""

from __future__ import annotations

from naoloc.behaviours.localize import (
    SCAN_YAWS,
    Localization,
    localize,
    paper_queries,
    truth_in_map,
)
from naoloc.behaviours.nearest_wall import (
    WallSide,
    count_halves,
    detect_nearest_wall,
    nearest_side_in_room,
    nearest_wall,
)
from naoloc.behaviours.survey import SurveyResult, Waypoint, circuit, frames_per_lap, survey
from naoloc.robot.camera import Camera, look, stand

__all__ = [
    "SCAN_YAWS",
    "Camera",
    "Localization",
    "SurveyResult",
    "WallSide",
    "Waypoint",
    "circuit",
    "count_halves",
    "detect_nearest_wall",
    "frames_per_lap",
    "localize",
    "look",
    "nearest_side_in_room",
    "nearest_wall",
    "paper_queries",
    "stand",
    "survey",
    "truth_in_map",
]
