"""Camera geometry: intrinsics from the field of view, and the head camera pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.constants import FOV_V5
from naoloc.keyframe import TORSO_HEIGHT_STANDINIT, CameraInfo, camera_in_robot


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
    assert math.atan2(z[1], z[0]) == pytest.approx(yaw, abs=1e-9)
    assert z[2] < 0  # the top camera looks 1.2 deg down
    x = t[:3, 0]  # image right
    assert math.atan2(x[1], x[0]) == pytest.approx(yaw - math.pi / 2, abs=1e-9)
    np.testing.assert_allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-12)


def test_camera_height_near_documented() -> None:
    z = camera_in_robot(0.0, 0.0)[2, 3]
    # Straight legs put the top camera at about 0.523 m; StandInit a little lower.
    assert 0.45 < z < 0.523
    assert z == pytest.approx(TORSO_HEIGHT_STANDINIT + 0.1265 + 0.06364, abs=2e-3)
