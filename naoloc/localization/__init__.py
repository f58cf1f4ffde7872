"""Localization: where the robot is in a map, from recorded observations (robot-free).

::

    from naoloc.localization import Localizer, Picture, LineScan

    loc = Localizer(vmap, cfg.localize.filter)
    loc.update(Picture(keyframe))
    est = loc.pose()          # PoseEstimate: pose, covariance, status

- :mod:`~naoloc.localization.observations`: the typed observations (pictures, floor lines,
  odometry), each with the robot's odometry;
- :mod:`~naoloc.localization.pictures` and :mod:`~naoloc.localization.walls`: the sensor
  models (landmark reprojection with place retrieval; floor-wall lines against the walls);
- :mod:`~naoloc.localization.hypothesis`: one Gaussian hypothesis (an EKF with the motion
  model);
- :mod:`~naoloc.localization.filter`: the belief, a few hypotheses ranked by evidence,
  with proposals from PnP, pooled matches and the lines
  (:mod:`~naoloc.localization.line_poses`);
- :mod:`~naoloc.localization.localizer`: ``Localizer``, ``PoseEstimate``, ``replay``;
- :mod:`~naoloc.localization.paper`: the paper's Algorithm 5 and the nearest-image baseline.
"""

from __future__ import annotations

from naoloc.localization.localizer import Localizer, PoseEstimate, Status, replay
from naoloc.localization.observations import (
    LineScan,
    Observation,
    Odometry,
    Picture,
    Relocalize,
)

__all__ = [
    "LineScan",
    "Localizer",
    "Observation",
    "Odometry",
    "Picture",
    "PoseEstimate",
    "Relocalize",
    "Status",
    "replay",
]
