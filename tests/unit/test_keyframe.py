"""Camera geometry: intrinsics from the field of view, and the head camera pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.constants import FOV_V5
from naoloc.robot.keyframe import TORSO_HEIGHT_STANDINIT, CameraInfo, camera_in_robot


def test_intrinsics_from_fov() -> None:
    cam = CameraInfo(320, 240, *FOV_V5)
    k = cam.matrix()
    # A point at the image edge lies at hfov/2 from the axis.
    assert math.atan((320 - k[0, 2]) / k[0, 0]) == pytest.approx(FOV_V5[0] / 2)
    assert math.atan((240 - k[1, 2]) / k[1, 1]) == pytest.approx(FOV_V5[1] / 2)
    assert cam.scaled(640, 480).fx == pytest.approx(2 * cam.fx)


@pytest.mark.parametrize("yaw", [0.0, -math.pi / 2, math.pi / 2, 1.0])
def test_optical_axis_follows_head_yaw(yaw: float) -> None:
    t = camera_in_robot(yaw, 0.0)
    z = t[:3, 2]  # view direction in FRAME_ROBOT
    # StandInit's torso leans 0.1 rad forward, so the yaw axis is tilted: a few mrad off.
    assert math.atan2(z[1], z[0]) == pytest.approx(yaw, abs=0.005)
    assert z[2] < 0  # the top camera looks down (1.2 deg in the head, plus the lean)
    x = t[:3, 0]  # image right
    assert math.atan2(x[1], x[0]) == pytest.approx(yaw - math.pi / 2, abs=0.005)
    np.testing.assert_allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-12)


def test_camera_height_near_documented() -> None:
    t = camera_in_robot(0.0, 0.0)
    # Straight legs put the top camera at about 0.523 m; StandInit's bent, leaning legs put it
    # at about (87, 0, 504) mm, looking 6.9 deg down.
    assert t[:3, 3] == pytest.approx([0.087, 0.0, 0.504], abs=2e-3)
    assert pytest.approx(0.3204, abs=1e-4) == TORSO_HEIGHT_STANDINIT
    assert math.degrees(math.asin(-t[2, 2])) == pytest.approx(6.93, abs=0.05)
