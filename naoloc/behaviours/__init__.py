"""Behaviours: plain functions over the robot interface (Algorithm 3 and beyond).

- :func:`nearest_wall` / :func:`detect_nearest_wall`: the paper's Fig. 10 detector.
- :func:`survey`: Algorithm 3, closed laps with a picture after each step.
- :func:`localize`: look (head, maybe turns in place) until the filter tracks a pose.
- :func:`track`: the pose at every camera frame while walking.
- :func:`go_home`: walk to the map origin on the live pose.

They use only ``robot.motion``, ``robot.video`` and ``robot.posture`` (``robot.sim`` only
to report the truth), so they run unchanged on every backend.
"""

from __future__ import annotations

from naoloc.behaviours.go_home import GoHomeResult, go_home
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
from naoloc.behaviours.track import TrackResult, track
from naoloc.robot.camera import Camera, look, stand

__all__ = [
    "SCAN_YAWS",
    "Camera",
    "GoHomeResult",
    "Localization",
    "SurveyResult",
    "TrackResult",
    "WallSide",
    "Waypoint",
    "circuit",
    "count_halves",
    "detect_nearest_wall",
    "frames_per_lap",
    "go_home",
    "localize",
    "look",
    "nearest_side_in_room",
    "nearest_wall",
    "paper_queries",
    "stand",
    "survey",
    "track",
    "truth_in_map",
]
