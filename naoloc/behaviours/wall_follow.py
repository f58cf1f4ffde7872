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
from naoloc.constants import BOTTOM_CAMERA_IN_HEAD, FRAME_ROBOT
from naoloc.geometry import Pose2D, mid_transform, modulo2PI
from naoloc.perception.floorline import WallLine, detect_wall_lines, wall_line_candidates
from naoloc.perception.wall_gate import crosses_path, in_front_range, side_line_angle
from naoloc.robot import Robot
from naoloc.robot.camera import Camera, look
from naoloc.robot.lens import Lens

BOTTOM_CAMERA = 1
MAX_LATERAL_M = 0.12  # largest sideways correction per step
MAX_TURN_RAD = 0.25  # largest heading correction per step
FRONT_PITCH = -0.35  # head pitch for the front wall (the bottom camera sees 0.4 m to far ahead)
MIN_SCALE_BASELINE_M = 0.4  # front-distance change needed for one scale sample
MIN_SCALE_SIDES = 2
MAX_SCALE_SPREAD = 0.1  # relative median absolute deviation of the per-side ratios
# Where the bottom camera looks for a side wall's floor line: (|HeadYaw| rad, HeadPitch rad,
# Gaussian blur of the picture in px, 0: none). Beside the robot, head up (the shell clamps
# the pitch to about -0.33 at this yaw): the floor from about 0.5 m to 4 m. Nearer, the foot
# of the wall leaves the picture, and with the head pitched down StandInit's arm (the
# forearm held forward) hides the floor beside and ahead of the shoulder. Looking back past
# the shoulder the floor is clear from about 0.45 to 1.2 m; there the near floor fills the
# picture, and a carpet's speckle, sharp that near, widens the floor's colour model until a
# grey wall passes for floor: the blur keeps it narrow (tools/floorline_views.py).
BESIDE_VIEW = (math.pi / 2, -0.672, 0)
BEHIND_VIEW = (2.0, 0.0, 15)
BEHIND_LOW_VIEW = (2.0, 0.2, 15)  # near a corner the level view's floor is too little
HEAD_HEIGHT_M = 0.44  # the head joint above the floor, standing, m
HEADING_YAWS = (1.35, 1.7, 2.0)  # |HeadYaw| of :func:`heading_views`, rad
NEAR_OFFSET_M = 0.65  # below this offset the behind view is tried first
MIN_OFFSET_M = 0.5  # nearer, neither view sees the wall reliably (and a step's correction
#                     of MAX_LATERAL_M leaves the body too little room): the survey refuses
# The views see a wall's foot from about 0.45 m: a robot steered to 0.5 m drifts out of
# sight within a step or two (a NAO's step errs 2 cm sideways) and then walks blind. Below
# this the survey keeps this far from its walls (the circuit's sides stay as configured;
# the wall-referenced poses measure where the robot walked, not assume it).
MIN_KEEP_M = 0.6
# The front wall's line: head up for a wall 0.6-2.6 m ahead, level for one 0.5-1.0 m ahead.
FRONT_NEAR_PITCH = 0.0
FLOOR_BEYOND_M = 0.4  # floor seen this far past a line ahead: the line is no wall, m
FRONT_NEAR_M = 0.8  # a front wall expected nearer than this is looked for level first
MAX_CARRY_M = 0.8  # a side line carried by the odometry steers for this much walk, m
JUMP_M = 0.15  # a side line this far from the carried one sees something else, m
JUMP_RAD = 0.12  # or turned this much from it (a NAO's step turns it by about 0.02), rad


class FloorEye:
    """The bottom camera, measuring floor-wall lines.

    Args:
        robot: The robot.
        like: The survey's camera config (resolution and colorspace are reused, and its
            ``floor_lines`` tunes the floor-line detector).
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
        self.tun = like.floor_lines  # the floor-line detector's thresholds
        self.last_pitch: float | None = None  # the pitch of measure_front's last line
        cfg = CameraConfig(
            index=BOTTOM_CAMERA,
            resolution=like.resolution,
            colorspace=like.colorspace,
            fps=like.fps,
        )
        self.camera = Camera(robot, cfg, name)

    def measure(
        self, expect_normal: float, tolerance: float = 0.5, blur: int = 0
    ) -> WallLine | None:
        """The wall line whose normal is within ``tolerance`` of ``expect_normal`` (rad).

        Args:
            expect_normal: Expected normal direction in FRAME_ROBOT, rad (``-pi/2``: right).
            tolerance: Largest accepted difference, rad.
            blur: Gaussian blur of the picture first, px (odd; 0: none).
        """
        found = self.candidates(expect_normal, tolerance, blur)
        return found[0] if found else None

    def candidates(
        self, expect_normal: float, tolerance: float = 0.5, blur: int = 0
    ) -> list[WallLine]:
        """Every line :meth:`measure` could give, the one it gives first (up to two: a
        piece of furniture's face and the wall behind it)."""
        view = self.view()
        if view is None:
            return []
        image, hfov, vfov, pose = view
        if blur > 1:
            import cv2

            image = cv2.GaussianBlur(image, (blur | 1, blur | 1), 0)
        return wall_line_candidates(
            image, hfov, vfov, pose, expect_normal=expect_normal, tolerance=tolerance,
            lens=self.lens, tun=self.tun,
        )  # fmt: skip

    def lines(self) -> list[WallLine]:
        """Every floor-wall line in view (up to two: a corner), FRAME_ROBOT."""
        view = self.view()
        return [] if view is None else self.detect(view)

    def detect(self, view: tuple[np.ndarray, float, float, np.ndarray]) -> list[WallLine]:
        """Every floor-wall line (up to two: a corner) in a :meth:`view`, FRAME_ROBOT."""
        image, hfov, vfov, pose = view
        return detect_wall_lines(image, hfov, vfov, pose, lens=self.lens, tun=self.tun)

    def view(self, still: bool = False) -> tuple[np.ndarray, float, float, np.ndarray] | None:
        """A picture (BGR), its fields of view (rad) and the camera's pose in FRAME_ROBOT;
        None when the robot reports no usable camera pose.

        Args:
            still: The head rests (after a blocking head move): the camera's pose is read
                once, before the image.
        """
        motion = self.robot.motion
        # The camera's pose read just before and after the image, halfway between (the
        # head may be moving: see Camera.keyframe).
        before = motion.getTransform("CameraBottom", FRAME_ROBOT, True)
        frame = self.camera.frame()
        after = before if still else motion.getTransform("CameraBottom", FRAME_ROBOT, True)
        info = self.camera.info(frame)
        if len(before) != 16 or len(after) != 16:
            return None
        pose = np.asarray(mid_transform(before, after), np.float64)
        if not np.all(np.isfinite(pose)):
            return None
        return frame.bgr(), info.hfov, info.vfov, pose

    def close(self) -> None:
        """Unsubscribe (best effort)."""
        self.camera.close()


def side_views(offset: float) -> list[tuple[float, float, int]]:
    """The views (|HeadYaw| rad, HeadPitch rad, blur px) that look for a side wall
    ``offset`` m away, the one that sees it best first."""
    if offset < NEAR_OFFSET_M:
        return [BEHIND_VIEW, BEHIND_LOW_VIEW, BESIDE_VIEW]
    return [BESIDE_VIEW, BEHIND_VIEW]


def look_for_line(
    robot: Robot,
    eye: FloorEye,
    normal: float,
    views: list[tuple[float, float, int]],
    accept: Any = None,
    tolerance: float = 0.5,
) -> tuple[WallLine | None, tuple[float, float, int] | None]:
    """Turn the head through ``views`` until the bottom camera sees a floor-wall line.

    A view that shows no line leaves the wall unseen, not far: the next view is tried.

    Args:
        robot: The robot (only the head moves).
        eye: The bottom camera.
        normal: The wall's expected direction in FRAME_ROBOT, rad (``-pi/2``: right).
        views: ``(|HeadYaw| rad, HeadPitch rad, blur px)``; the yaw takes the sign of
            ``normal`` (a yaw of 0 looks ahead).
        accept: Optional ``accept(line) -> bool``: a line it refuses counts as unseen.
        tolerance: Largest difference between the line's normal and ``normal``, rad.

    Returns:
        The first line seen (None: no view showed one) and the view that saw it.
    """
    side = 1.0 if normal >= 0 else -1.0
    for yaw, pitch, blur in views:
        look(robot, side * yaw, pitch)
        line = eye.measure(normal, tolerance, blur)
        if line is not None and (accept is None or accept(line)):
            return line, (yaw, pitch, blur)
    return None, None


def measure_side(robot: Robot, eye: FloorEye, side_normal: float, offset: float) -> WallLine | None:
    """The side wall's floor line, looked for beside and behind the arm (:func:`side_views`).

    Args:
        robot: The robot (only the head moves; it stays at the view that saw the line).
        eye: The bottom camera.
        side_normal: Where the wall is, rad (``-pi/2`` right, ``+pi/2`` left).
        offset: The survey's wall offset, m.

    Returns:
        The first line a view shows that :func:`trusted` keeps, else the
        first line seen at all (furniture, or a wall where it should not be), else None.
    """
    first: list[WallLine] = []

    def near(line: WallLine) -> bool:
        first.append(line)
        return trusted(line, offset, side_normal) is not None

    line, _ = look_for_line(robot, eye, side_normal, side_views(offset), near)
    return line if line is not None else (first[0] if first else None)


def heading_views(offset: float) -> list[tuple[float, float, int]]:
    """Views (|HeadYaw| rad, HeadPitch rad, blur px) whose bottom-camera picture is centred
    on the floor ``offset`` m beside the robot, ahead of, beside and behind the shoulder:
    more lines of the side wall for the survey start's heading, each seen across the whole
    picture (the side views look for the line, these measure it again)."""
    (_, _, height), tilt = BOTTOM_CAMERA_IN_HEAD
    pitch = math.atan2(HEAD_HEIGHT_M + height, max(offset, 0.3)) - tilt
    return [(yaw, pitch, 0) for yaw in HEADING_YAWS]


def measure_side_views(
    robot: Robot,
    eye: FloorEye,
    side_normal: float,
    offset: float,
    views: list[tuple[float, float, int]] | None = None,
) -> list[WallLine]:
    """The side wall's line from every view (default :func:`side_views`) that sees one
    within the side-line gate (:func:`trusted`; the survey's start: its heading is the
    map's)."""
    side = 1.0 if side_normal >= 0 else -1.0
    out = []
    for yaw, pitch, blur in side_views(offset) if views is None else views:
        look(robot, side * yaw, pitch)
        line = trusted(eye.measure(side_normal, 0.5, blur), offset, side_normal)
        if line is not None:
            out.append(line)
    return out


def median_line(lines: list[WallLine]) -> WallLine | None:
    """The line of median angle (None for none): one view's line can mix in a corner's
    other wall."""
    if not lines:
        return None
    ranked = sorted(lines, key=lambda ln: ln.normal)
    return ranked[(len(ranked) - 1) // 2]


def measure_front(
    robot: Robot, eye: FloorEye, expected: float, accept: Any = None
) -> WallLine | None:
    """The front wall's floor line (FRAME_ROBOT), looking level first when it is expected
    within :data:`FRONT_NEAR_M`, else head up first (the other pitch when unseen).

    Args:
        robot: The robot (the head turns to yaw 0).
        eye: The bottom camera.
        expected: Where the odometry expects the front wall, m.
        accept: Optional ``accept(line) -> bool``: a line it refuses counts as unseen.

    A line more than :data:`FLOOR_BEYOND_M` nearer than one across the way that the first
    pitch showed (head up: a wall out of the trusted range, say) is the floor's own seam
    and counts as unseen too.
    """
    pitches = [FRONT_PITCH, FRONT_NEAR_PITCH]
    if expected < FRONT_NEAR_M:
        pitches.reverse()
    beyond = 0.0  # the farthest line across the way an earlier pitch showed, m
    for pitch in pitches:
        look(robot, 0.0, pitch)
        found = eye.candidates(0.0, 0.4)
        line = found[0] if found else None
        seam = line is not None and line.distance < beyond - FLOOR_BEYOND_M  # floor goes on
        if line is not None and not seam and (accept is None or accept(line)):
            eye.last_pitch = pitch
            return line
        beyond = max([beyond] + [ln.distance for ln in found if crosses_path(ln)])
    eye.last_pitch = None
    return None


def carry(line: WallLine, motion: Pose2D) -> WallLine:
    """A line measured in FRAME_ROBOT, seen from where the robot is after ``motion``.

    Args:
        line: The line where it was measured (FRAME_ROBOT then).
        motion: The robot's pose now in its frame then (odometry), m and rad.

    Returns:
        The line in FRAME_ROBOT now, with ``inliers`` 0: carried, not measured.
    """
    distance = line.distance - (motion.x * math.cos(line.normal) + motion.y * math.sin(line.normal))
    normal = line.normal - motion.theta
    if distance < 0:
        distance, normal = -distance, normal + math.pi
    return WallLine(distance, modulo2PI(normal), 0, line.fraction, line.rms_m, line.span_m)


@dataclass
class SideMemory:
    """The side wall as the survey steers by it: the last line seen, carried by the
    odometry, and the depth of what stands in front of the wall.

    A wall nearer than the bottom camera's views reach (about 0.45 m) is unseen; stepping
    straight on then walks a robot turned a few degrees into the wall, blind all the way.
    The last line seen, carried by the odometry's motion since (:func:`carry`), steers for
    up to :data:`MAX_CARRY_M` of walk; after a corner the front wall's last line, turned
    with the robot, is the new side's wall. A line that jumps more than :data:`JUMP_M`
    from the carried one sees something else: furniture in front of the wall (a
    sideboard's foot), a doorway's recess, a corner's other wall. Its jump is kept as a
    level (``level``, m: how far nearer than the wall it stands), and the lines of that
    stretch steer as the wall behind them, so the robot walks past a sideboard on its
    circuit, not along its face; a line back at the wall's distance ends the stretch. A
    line turned more than :data:`JUMP_RAD` from the carried wall keeps the wall's angle,
    unless the next line is turned the same way: then the carried angle was the wrong one
    (``doubt`` holds the first such line).
    """

    side: tuple[WallLine, Pose2D] | None = None
    front: tuple[WallLine, Pose2D] | None = None
    angle_known: bool = True  # False after a corner: the odometry's turn errs 6 %
    level: float = 0.0
    doubt: tuple[WallLine, Pose2D] | None = None  # the last line that turned from the wall

    def carried(self, here: Pose2D) -> WallLine | None:
        """The wall's last line, carried to odometry pose ``here`` (None: too old)."""
        if self.side is None:
            return None
        seen, there = self.side
        motion = there.inverse() * here
        if math.hypot(motion.x, motion.y) > MAX_CARRY_M:
            return None
        if math.hypot(motion.x, motion.y) < 1e-6 and abs(motion.theta) < 1e-6:
            return seen  # measured here
        return carry(seen, motion)

    def wall_of(self, line: WallLine, here: Pose2D) -> WallLine:
        """The wall behind a measured line: the line moved by the stretch's level, a new
        level when it jumps from the carried wall (the carried wall's angle when the line
        turned from it by more than :data:`JUMP_RAD`)."""
        known = self.carried(here)
        if known is None:
            self.level, self.doubt = 0.0, None
            return line
        turned = abs(modulo2PI(line.normal - known.normal)) > JUMP_RAD and self.angle_known
        if turned and self.doubt is not None:
            # Two lines in a row turned the same way from the carried wall: the wall's angle
            # was wrong (a survey start in a corner reads the wall behind into its line).
            seen, there = self.doubt
            again = carry(seen, there.inverse() * here)
            turned = abs(modulo2PI(line.normal - again.normal)) > JUMP_RAD
        self.doubt = (line, here) if turned else None
        normal = known.normal if turned else line.normal
        if abs(line.distance - known.distance) <= JUMP_M:
            self.level = 0.0  # the wall itself
            return _moved(line, 0.0, normal)
        if abs(line.distance + self.level - known.distance) > JUMP_M:
            self.level = known.distance - line.distance  # a new stretch begins
        return _moved(line, self.level, normal)

    def seen_side(self, line: WallLine | None, here: Pose2D) -> WallLine | None:
        """A side line measured (or not) at odometry pose ``here`` (map frame).

        Returns:
            The wall it shows (None: no measured line).
        """
        if line is None or line.inliers == 0:
            return None
        wall = self.wall_of(line, here)
        self.side, self.angle_known = (wall, here), True
        return wall

    def start(self, line: WallLine | None, here: Pose2D, offset: float) -> WallLine | None:
        """The survey start's side line: the robot was set ``offset`` m from its wall, so a
        line more than :data:`JUMP_M` nearer sees furniture in front of the wall (a
        sideboard beside the start), whose depth is the first stretch's level.

        Returns:
            The wall it shows (None: no line).
        """
        if line is None or line.inliers == 0:
            return None
        self.level = offset - line.distance if offset - line.distance > JUMP_M else 0.0
        wall = _moved(line, self.level, line.normal)
        self.side, self.angle_known = (wall, here), True
        return wall

    def seen_front(self, line: WallLine | None, here: Pose2D) -> None:
        """A front line measured (or not) at odometry pose ``here``."""
        if line is not None:
            self.front = (line, here)

    def turned(self) -> None:
        """A corner: the front wall becomes the side wall; the old side is behind."""
        self.side, self.front, self.angle_known, self.level = self.front, None, False, 0.0
        self.doubt = None

    def steer(self, here: Pose2D) -> WallLine | None:
        """The wall to steer by at ``here``: the last one seen or carried (None: none)."""
        return self.carried(here)


def _moved(line: WallLine, by: float, normal: float) -> WallLine:
    return WallLine(line.distance + by, normal, line.inliers, line.fraction, line.rms_m,
                    line.span_m)  # fmt: skip


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
    """JSON-able line (or None), with where its inliers end along it (``ends_m``)."""
    if line is None:
        return None
    out: dict[str, Any] = line.to_dict()
    if line.ends_m is not None:
        out["ends_m"] = [round(e, 3) for e in line.ends_m]
    return out
