"""Sensor odometry of the fake robot: the true motion plus a seeded drift model.

``getRobotPosition(True)`` integrates every cycle's true body motion after corrupting it
with the drift of :class:`naoloc.config.OdometryConfig`:

- scale error: translations are read ``(1 + scale_error)`` times too long;
- heading bias: ``heading_bias_rad_per_m`` radians of heading per metre walked;
- position random walk: Gaussian noise of ``random_walk_m_per_sqrt_m * sqrt(ds)`` m on x
  and y for a translation ``ds``;
- heading random walk: ``heading_random_walk_rad_per_sqrt_rad * sqrt(|dtheta|)`` rad.

With every term zero the sensor odometry equals the commanded odometry exactly.
"""

from __future__ import annotations

import math

import numpy as np

from naoloc.config import OdometryConfig
from naoloc.geometry import Pose2D


class DriftingOdometry:
    """Integrates body-frame motion increments into a drifting FRAME_WORLD pose.

    Args:
        cfg: The drift model and its seed.
    """

    def __init__(self, cfg: OdometryConfig) -> None:
        self._cfg = cfg
        self._rng = np.random.default_rng(cfg.seed)
        self.pose = Pose2D()

    def add(self, step: Pose2D) -> None:
        """Integrate one true body-frame increment (FRAME_ROBOT at the start of the step).

        Args:
            step: Increment ``(dx, dy, dtheta)`` in metres and radians.
        """
        cfg = self._cfg
        ds = math.hypot(step.x, step.y)
        dth = abs(step.theta)
        if ds == 0.0 and dth == 0.0:
            return
        noise = self._rng.standard_normal(3)  # always three draws: same stream for any model
        scale = 1.0 + cfg.scale_error
        sd_pos = cfg.random_walk_m_per_sqrt_m * math.sqrt(ds)
        sd_th = cfg.heading_random_walk_rad_per_sqrt_rad * math.sqrt(dth)
        read = Pose2D(
            step.x * scale + sd_pos * float(noise[0]),
            step.y * scale + sd_pos * float(noise[1]),
            step.theta + cfg.heading_bias_rad_per_m * ds + sd_th * float(noise[2]),
        )
        self.pose = self.pose * read
