"""Which side the nearest wall is on: the paper's detector (Fig. 10) and a robust one.

- :func:`nearest_wall` is the paper's: one forward image is split into a left and a right
  half; the side with more A-KAZE keypoints is taken as the nearest wall. Its cue is weak
  (a nearer wall shows less of itself), so naoloc records it but does not steer by it.
- :func:`detect_wall_by_floorline` is what the survey steers by first: the bottom camera's
  floor-wall line to the left and right (no texture needed, blank walls included).
- :func:`detect_wall_by_parallax` is the fallback when neither wall's foot is in reach:
  the robot looks left and right, steps forward, and looks again; features on a wall at
  distance d shift by about ``f * step / d`` pixels, so the side whose features move more
  is the nearer wall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from naoloc.behaviours.wall_follow import FloorEye, look_for_line, side_views
from naoloc.errors import FeatureError, MotionError
from naoloc.perception.floorline import WallLine
from naoloc.perception.wall_gate import SIDE_MIN_M, SIDE_OFFSET_ERROR_M
from naoloc.robot import Robot
from naoloc.robot.camera import DEFAULT_HEAD_PITCH, Camera, look

Side = Literal["left", "right"]


@dataclass(frozen=True, slots=True)
class WallSide:
    """Result of the nearest-wall detector.

    Attributes:
        side: "left" or "right" of the robot.
        head_yaw: HeadYaw that faces that wall, rad (+pi/2 left, -pi/2 right).
        left: A-KAZE keypoints in the left image half.
        right: A-KAZE keypoints in the right image half.
    """

    side: Side
    head_yaw: float
    left: int
    right: int


def count_halves(gray: np.ndarray) -> tuple[int, int]:
    """A-KAZE keypoints in the left and right halves of a grey image.

    Args:
        gray: ``(h, w)`` uint8 image (a 3-channel BGR image is converted).

    Returns:
        ``(left, right)`` keypoint counts.

    Raises:
        FeatureError: OpenCV failed on the image.
    """
    import cv2

    img = np.asarray(gray)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    try:
        keypoints = cv2.AKAZE_create().detect(img, None)  # type: ignore[attr-defined]
    except cv2.error as err:
        raise FeatureError(f"A-KAZE failed on a {img.shape} image: {err.msg}") from None
    half = img.shape[1] / 2.0
    left = sum(1 for kp in keypoints if kp.pt[0] < half)
    return left, len(keypoints) - left


def nearest_wall(image: np.ndarray) -> WallSide:
    """The side of the nearest wall from one forward image (ties go right).

    Args:
        image: Grey ``(h, w)`` or BGR ``(h, w, 3)`` uint8 image taken looking ahead.
    """
    left, right = count_halves(image)
    if left > right:
        return WallSide("left", math.pi / 2, left, right)
    return WallSide("right", -math.pi / 2, left, right)


def detect_nearest_wall(
    robot: Robot, camera: Camera, pitch: float = DEFAULT_HEAD_PITCH
) -> WallSide:
    """Look straight ahead, take a picture, and run :func:`nearest_wall` on it.

    Args:
        robot: The robot (head is moved; the body is not).
        camera: The camera subscription to use.
        pitch: Head pitch for the picture, rad.
    """
    look(robot, 0.0, pitch)
    return nearest_wall(camera.frame().gray())


@dataclass(frozen=True, slots=True)
class ParallaxWall:
    """Result of the parallax detector.

    Attributes:
        side: "left" or "right" of the robot.
        head_yaw: HeadYaw that faces that wall, rad (+pi/2 left, -pi/2 right).
        left_shift_px: Median horizontal feature shift on the left side (NaN: too few matches).
        right_shift_px: The same on the right side.
        left_matches: Matched features on the left side.
        right_matches: Matched features on the right side.
    """

    side: Side
    head_yaw: float
    left_shift_px: float
    right_shift_px: float
    left_matches: int
    right_matches: int


MIN_PARALLAX_MATCHES = 8


MAX_ROLL_SLOPE = 0.15  # |dy/dx| a sideways view's motion may have (camera roll up to 8.5 deg)


def feature_shift(before: np.ndarray, after: np.ndarray) -> tuple[float, int]:
    """Median horizontal shift (px) of A-KAZE features matched between two grey images.

    Args:
        before: ``(h, w)`` uint8 image.
        after: ``(h, w)`` uint8 image of the same view after the camera moved.

    Returns:
        ``(median |dx| in pixels, matches)``; the shift is NaN with fewer than
        :data:`MIN_PARALLAX_MATCHES` matches.
    """
    import cv2

    akaze = cv2.AKAZE_create()  # type: ignore[attr-defined]
    kp1, d1 = akaze.detectAndCompute(before, None)
    kp2, d2 = akaze.detectAndCompute(after, None)
    if d1 is None or d2 is None or len(kp1) < 2 or len(kp2) < 2:
        return float("nan"), 0
    pairs = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(d1, d2, k=2)
    good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < 0.75 * p[1].distance]
    # A sideways wall seen while walking forward moves along the image's horizontal, tilted
    # by the camera's roll: StandInit's 0.1 rad forward lean is a 0.1 rad roll seen sideways.
    shifts = []
    for m in good:
        dx = kp2[m.trainIdx].pt[0] - kp1[m.queryIdx].pt[0]
        dy = kp2[m.trainIdx].pt[1] - kp1[m.queryIdx].pt[1]
        if abs(dy) < 0.05 * before.shape[0] + MAX_ROLL_SLOPE * abs(dx):
            shifts.append(abs(dx))
    if len(shifts) < MIN_PARALLAX_MATCHES:
        return float("nan"), len(shifts)
    return float(np.median(shifts)), len(shifts)


def detect_wall_by_parallax(
    robot: Robot, camera: Camera, step_m: float, pitch: float = DEFAULT_HEAD_PITCH
) -> ParallaxWall:
    """Find the nearer side wall by motion parallax, returning to the start pose.

    The robot takes a picture to its left and right, walks ``step_m`` forward, takes both
    again, and walks back. The side whose features shift more is nearer. When one side has
    too few matches (a blank or very distant view), the side with matches is taken; when
    neither has, the paper's keypoint count on a forward image decides.

    Args:
        robot: The robot, standing where the survey will start.
        camera: The camera subscription to use.
        step_m: How far to step forward, m (the survey step is a good choice).
        pitch: Head pitch for the pictures, rad.

    Returns:
        The detected side with the measured shifts.

    Raises:
        MotionError: The probe step failed (the caller stops the robot).
    """
    yaws = {"left": math.pi / 2, "right": -math.pi / 2}
    before = {}
    for name, yaw in yaws.items():
        look(robot, yaw, pitch)
        before[name] = camera.frame().gray()
    if not robot.motion.moveTo(step_m, 0.0, 0.0):
        raise MotionError(f"the nearest-wall probe could not step {step_m:.2f} m forward")
    shifts: dict[str, tuple[float, int]] = {}
    for name in ("left", "right"):
        look(robot, yaws[name], pitch)
        shifts[name] = feature_shift(before[name], camera.frame().gray())
    if not robot.motion.moveTo(-step_m, 0.0, 0.0):
        raise MotionError(f"the nearest-wall probe could not step {step_m:.2f} m back")
    (ls, lm), (rs, rm) = shifts["left"], shifts["right"]
    if math.isnan(ls) and math.isnan(rs):
        side: Side = detect_nearest_wall(robot, camera, pitch).side
    elif math.isnan(ls):
        side = "right"
    elif math.isnan(rs):
        side = "left"
    else:
        side = "left" if ls > rs else "right"
    return ParallaxWall(side, yaws[side], ls, rs, lm, rm)


@dataclass(frozen=True, slots=True)
class FloorLineWall:
    """Result of the floor-wall line detector (bottom camera, works on blank walls).

    Attributes:
        side: "left" or "right" of the robot, or None when neither wall's foot was seen
            (both walls beyond the bottom camera's reach, or floor and walls alike).
        head_yaw: HeadYaw that faces that wall, rad (0.0 when ``side`` is None).
        left_m: Distance to the left wall's line, m (None: not seen).
        right_m: The same on the right.
    """

    side: Side | None
    head_yaw: float
    left_m: float | None
    right_m: float | None


def _not_the_arm(line: WallLine) -> bool:
    """A line nearer than :data:`naoloc.perception.wall_gate.SIDE_MIN_M` is the robot's own
    arm's edge: no view sees a wall's foot that near."""
    return line.distance >= SIDE_MIN_M


def decide_side(
    left: float | None, right: float | None, offset: float | None = None
) -> Side | None:
    """The side wall to follow from the floor lines actually seen (distances in m).

    A side that shows no line is unseen, not far: it never makes the other side the
    chosen one by itself. Without ``offset``: both seen, the nearer (the paper's nearest
    wall); one seen, that side. With the survey's ``offset`` (the robot was set that far
    from the wall it should follow): both seen, the one nearer the offset (a piece of
    furniture beside the robot reads nearer than the wall; the config says which distance
    is the wall's); and the chosen line must be no farther than
    :data:`naoloc.perception.wall_gate.SIDE_OFFSET_ERROR_M` beyond it (a lone line farther
    away says nothing about the unseen side, and a wall far from the offset cannot be
    followed). Else None.

    Args:
        left: Distance to the left wall's line, m (None: unseen).
        right: The same on the right.
        offset: The survey's wall offset, m (None: any lone line decides).
    """
    seen: Side
    if offset is None:
        nearer_left = left is not None and (right is None or left < right)
    else:
        nearer_left = left is not None and (
            right is None or abs(left - offset) < abs(right - offset)
        )
    if nearer_left:
        assert left is not None
        seen, distance = "left", left
    elif right is not None:
        seen, distance = "right", right
    else:
        return None
    if offset is not None and distance > offset + SIDE_OFFSET_ERROR_M:
        return None
    return seen


def detect_wall_by_floorline(
    robot: Robot, eye: FloorEye, pitch: float = DEFAULT_HEAD_PITCH, offset: float | None = None
) -> FloorLineWall:
    """Look left and right with the bottom camera; the floor-wall line nearer the robot
    (or, given ``offset``, nearer the offset: :func:`decide_side`) wins.

    Needs no texture on the walls and no step. The robot's body does not move.

    Args:
        robot: The robot (the head is moved).
        eye: The bottom camera (:class:`naoloc.behaviours.wall_follow.FloorEye`).
        pitch: Head pitch for the pictures, rad (without ``offset``).
        offset: The survey's wall offset, m. Given, each side is looked at beside and
            behind the arm (:func:`naoloc.behaviours.wall_follow.side_views`) until a line
            shows, and :func:`decide_side` decides on the lines seen; None: one look per
            side at ``pitch``, and the nearer line seen decides.
    """
    yaws = {"left": math.pi / 2, "right": -math.pi / 2}
    seen: dict[str, float | None] = {}
    for name, yaw in yaws.items():
        if offset is None:
            look(robot, yaw, pitch)
            line = eye.measure(yaw)
        else:
            line, _ = look_for_line(robot, eye, yaw, side_views(offset), _not_the_arm)
        seen[name] = None if line is None else line.distance
    left, right = seen["left"], seen["right"]
    side = decide_side(left, right, offset)
    return FloorLineWall(side, 0.0 if side is None else yaws[side], left, right)


def nearest_side_in_room(size: tuple[float, float], start: tuple[float, float, float]) -> WallSide:
    """The side (left or right of the robot) whose wall is nearer, from the room's layout.

    For a simulated room the config knows what the paper asks the operator to arrange
    (the robot in a corner, parallel to a wall). The detector's image cue is weak (a
    nearer wall shows less of itself), so the survey command uses this on simulators.

    Args:
        size: Room inner size ``(x, y)``, m.
        start: Robot pose ``(x, y, theta)`` in the room frame (m, rad).

    Returns:
        The side, with keypoint counts of 0 (no image was used).
    """

    def distance(heading: float) -> float:
        x, y, _ = start
        c, s = math.cos(heading), math.sin(heading)
        hits = []
        if c > 1e-9:
            hits.append((size[0] - x) / c)
        if c < -1e-9:
            hits.append(-x / c)
        if s > 1e-9:
            hits.append((size[1] - y) / s)
        if s < -1e-9:
            hits.append(-y / s)
        return min(hits)

    theta = start[2]
    if distance(theta + math.pi / 2) < distance(theta - math.pi / 2):
        return WallSide("left", math.pi / 2, 0, 0)
    return WallSide("right", -math.pi / 2, 0, 0)
