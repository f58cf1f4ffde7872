"""The paper's nearest-wall detector (Fig. 10): A-KAZE keypoints in each image half.

The image is split into a left and a right half; the side with more keypoints is taken as
the side of the nearest wall, and the head turns to it (+pi/2 left, -pi/2 right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from naoloc.behaviours.camera import DEFAULT_HEAD_PITCH, Camera, look
from naoloc.errors import FeatureError
from naoloc.robot import Robot

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
