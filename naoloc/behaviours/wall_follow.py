"""Keeping the survey's distance and heading to the wall from the bottom camera.

:class:`FloorEye` is a second ALVideoDevice subscription, to the bottom camera (index 1),
that measures the floor-wall line (:mod:`naoloc.perception.floorline`) with the camera pose from the
robot's own kinematics (``getTransform("CameraBottom", FRAME_ROBOT, True)``), so it works
the same on a real NAO and over the network. :func:`corrected_step` turns a measured side
wall into the next ``moveTo``: back to the survey's wall offset and parallel to the wall,
every correction bounded. :func:`metric_scale` compares the odometry with the front wall's
distances measured while walking toward it.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.config import CameraConfig
from naoloc.constants import FRAME_ROBOT
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.perception.floorline import WallLine, detect_wall_line, detect_wall_lines
from naoloc.perception.wall_gate import in_front_range, side_line_angle
from naoloc.robot import Robot
from naoloc.robot.camera import Camera
from naoloc.robot.lens import Lens

BOTTOM_CAMERA = 1
MAX_LATERAL_M = 0.12  # largest sideways correction per step
MAX_TURN_RAD = 0.25  # largest heading correction per step
FRONT_PITCH = -0.35  # head pitch for the front wall (the bottom camera sees 0.4 m to far ahead)
MIN_SCALE_BASELINE_M = 0.4  # front-distance change needed for one scale sample
MIN_SCALE_SIDES = 2
MAX_SCALE_SPREAD = 0.1  # relative median absolute deviation of the per-side ratios


class FloorEye:
    """The bottom camera, measuring floor-wall lines.

    Args:
        robot: The robot.
        like: The survey's camera config (resolution and colorspace are reused).
        name: Subscriber name.
        lens: The camera's lens, undone by the floor-line detector (None: a pinhole).
    """

    def __init__(
        self,
        robot: Robot,
        like: CameraConfig,
        name: str = "naoloc_floor",
        lens: Lens | None = None,
    ) -> None:
        self.robot = robot
        self.lens = lens
        cfg = CameraConfig(
            index=BOTTOM_CAMERA,
            resolution=like.resolution,
            colorspace=like.colorspace,
            fps=like.fps,
        )
        self.camera = Camera(robot, cfg, name)

    def measure(self, expect_normal: float, tolerance: float = 0.5) -> WallLine | None:
        """The wall line whose normal is within ``tolerance`` of ``expect_normal`` (rad).

        Args:
            expect_normal: Expected normal direction in FRAME_ROBOT, rad (``-pi/2``: right).
            tolerance: Largest accepted difference, rad.
        """
        view = self.view()
        if view is None:
            return None
        image, hfov, vfov, pose = view
        return detect_wall_line(
            image, hfov, vfov, pose, expect_normal=expect_normal, tolerance=tolerance,
            lens=self.lens,
        )  # fmt: skip

    def lines(self) -> list[WallLine]:
        """Every floor-wall line in view (up to two: a corner), FRAME_ROBOT."""
        view = self.view()
        return [] if view is None else self.detect(view)

    def detect(self, view: tuple[np.ndarray, float, float, np.ndarray]) -> list[WallLine]:
        """Every floor-wall line (up to two: a corner) in a :meth:`view`, FRAME_ROBOT."""
        image, hfov, vfov, pose = view
        return detect_wall_lines(image, hfov, vfov, pose, lens=self.lens)

    def view(self) -> tuple[np.ndarray, float, float, np.ndarray] | None:
        """A picture (BGR), its fields of view (rad) and the camera's pose in FRAME_ROBOT;
        None when the robot reports no usable camera pose."""
        frame = self.camera.frame()
        info = self.camera.info(frame)
        pose = np.asarray(
            self.robot.motion.getTransform("CameraBottom", FRAME_ROBOT, True), np.float64
        )
        if pose.size != 16 or not np.all(np.isfinite(pose)):
            return None
        return frame.bgr(), info.hfov, info.vfov, pose

    def close(self) -> None:
        """Unsubscribe (best effort)."""
        self.camera.close()


def trusted(line: WallLine | None, offset: float, side_normal: float) -> WallLine | None:
    """``line`` when it is plausible for the side wall kept at ``offset`` m in the direction
    ``side_normal`` (rad), by :func:`naoloc.perception.wall_gate.side_line_angle`, else None."""
    if line is None or side_line_angle(line.distance, line.normal, offset, side_normal) is None:
        return None
    return line


def corrected_step(
    line: WallLine | None, side_normal: float, offset: float, step: float
) -> tuple[Pose2D, bool]:
    """The next ``moveTo`` (FRAME_ROBOT) from a measured side wall.

    Args:
        line: The side wall (None: no measurement; the robot steps straight ahead).
        side_normal: Where the wall should be, rad (``-pi/2`` right, ``+pi/2`` left).
        offset: Distance to keep from the wall, m.
        step: Distance to advance along the wall, m.

    Returns:
        The relative target ``(x, y, theta)`` and whether the vision was used. The target
        ends ``offset`` from the wall (sideways correction at most :data:`MAX_LATERAL_M`)
        and parallel to it (turn at most :data:`MAX_TURN_RAD`).
    """
    line = trusted(line, offset, side_normal)
    if line is None:
        return Pose2D(step, 0.0, 0.0), False
    toward = line.distance - offset
    lateral = max(-MAX_LATERAL_M, min(MAX_LATERAL_M, toward))
    heading = modulo2PI(line.normal - side_normal)
    heading = max(-MAX_TURN_RAD, min(MAX_TURN_RAD, heading))
    nx, ny = math.cos(line.normal), math.sin(line.normal)
    x = lateral * nx + step * math.cos(heading)
    y = lateral * ny + step * math.sin(heading)
    return Pose2D(x, y, heading), True


@dataclass(frozen=True, slots=True)
class FrontSample:
    """One front-wall measurement.

    Attributes:
        side: Index of the side walked (lap * 4 + side), to pair samples of one wall.
        odometry: Odometry pose (map frame) where it was measured.
        line: The front wall's line in FRAME_ROBOT.
    """

    side: int
    odometry: Pose2D
    line: WallLine


def metric_scale(samples: list[FrontSample]) -> tuple[float | None, list[float]]:
    """Metres per odometry metre, from the front wall's distances along each side.

    On each side, the front measurements' wall distances against the odometry's
    displacement (projected on the wall's normal) fall on a line whose slope is one
    sample (least squares over all of the side's measurements within
    :data:`naoloc.perception.wall_gate.FRONT_RANGE_M`).

    Returns:
        ``(median ratio, the per-side ratios)``; the ratio is None with fewer than
        :data:`MIN_SCALE_SIDES` sides or when their median absolute deviation exceeds
        :data:`MAX_SCALE_SPREAD` of the median.
    """
    by_side: dict[int, list[FrontSample]] = {}
    for s in samples:
        if not in_front_range(s.line.distance):
            continue
        by_side.setdefault(s.side, []).append(s)
    ratios = []
    for group in by_side.values():
        first, last = group[0], group[-1]
        if first.line.distance - last.line.distance < MIN_SCALE_BASELINE_M:
            continue
        direction = first.odometry.theta + first.line.normal
        c, sn = math.cos(direction), math.sin(direction)
        odo = np.array(
            [(g.odometry.x - first.odometry.x) * c + (g.odometry.y - first.odometry.y) * sn
             for g in group]
        )  # fmt: skip
        dist = np.array([g.line.distance for g in group])
        if odo[-1] <= 0:
            continue
        slope = float(np.polyfit(odo, dist, 1)[0])  # metres of wall distance per odometry m
        if slope < 0:
            ratios.append(-slope)
    if len(ratios) < MIN_SCALE_SIDES:
        return None, ratios
    median = float(statistics.median(ratios))
    spread = statistics.median(abs(r - median) for r in ratios) / median
    if spread > MAX_SCALE_SPREAD:
        return None, ratios  # the sides disagree: a wrong line somewhere, no scale
    return median, ratios


def line_dict(line: WallLine | None) -> dict[str, Any] | None:
    """JSON-able line (or None)."""
    return None if line is None else line.to_dict()
