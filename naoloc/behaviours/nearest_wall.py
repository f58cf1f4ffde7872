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
