"""MuJoCo backend: camera geometry, features on the posters, time stamps, realism, extras."""

from __future__ import annotations

import importlib.util
import math
from typing import Any

import numpy as np
import pytest

if importlib.util.find_spec("mujoco") is None:
    pytest.skip("mujoco is not installed", allow_module_level=True)

import cv2

import naoloc
from naoloc.backends.mujoco.room import wall_point
from naoloc.backends.mujoco.sim import Simulation
from naoloc.backends.mujoco.video import MujocoVideo
from naoloc.constants import FOV_V5, FOV_V6, kQVGA, kRGBColorSpace, kVGA, kYuvColorSpace
from naoloc.robot.image import frame_from_naoqi
from naoloc.robot.keyframe import CameraInfo, camera_in_robot

pytestmark = pytest.mark.sim
SMALL = {
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 2, "posters_per_wall": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},  # exact rendered pixels
    }
}


def _parts(robot: naoloc.Robot) -> tuple[Simulation, MujocoVideo]:
    assert isinstance(robot.sim, Simulation) and isinstance(robot.video, MujocoVideo)
    return robot.sim, robot.video


def _marker_pixel(video: MujocoVideo, sim: Simulation, p_room: np.ndarray, w: int, h: int) -> Any:
    """Centroid (u, v) of the marker in an image, pixel-centre convention (+0.5)."""
    sim.hide_marker()
    without = video.render_rgb(0, w, h).astype(np.int16)
    sim.set_marker(*p_room)
    diff = np.abs(video.render_rgb(0, w, h).astype(np.int16) - without).sum(axis=2)
    sim.hide_marker()
    ys, xs = np.nonzero(diff > 60)
    assert xs.size > 0, "marker not visible"
    weights = diff[ys, xs].astype(np.float64)
    return np.average(xs, weights=weights) + 0.5, np.average(ys, weights=weights) + 0.5


@pytest.mark.parametrize("model", ["v5", "v6"])
def test_marker_projects_where_the_keyframe_geometry_says(model: str) -> None:
    cfg = {**SMALL, "world": {**SMALL["world"], "model": model}}
    with naoloc.connect(cfg) as robot:
        sim, video = _parts(robot)
        fov = FOV_V6 if model == "v6" else FOV_V5
        assert video.getHorizontalFOV(0) == pytest.approx(fov[0])
        assert video.getVerticalFOV(0) == pytest.approx(fov[1])
        sim.teleport(2.0, 1.8, 0.4)
        robot.motion.angleInterpolationWithSpeed("Head", [0.35, 0.15], 1.0)
        yaw, pitch = robot.motion.getAngles("Head", True)
        x, y, th = sim.true_pose()
        robot_in_room = np.array(
            [[math.cos(th), -math.sin(th), 0, x], [math.sin(th), math.cos(th), 0, y],
             [0, 0, 1, 0], [0, 0, 0, 1.0]]
        )  # fmt: skip
        cam_in_room = robot_in_room @ camera_in_robot(yaw, pitch)
        for w, h in ((640, 480), (320, 240)):
            info = CameraInfo(w, h, fov[0], fov[1])
            for p_cam in ((0.0, 0.0, 1.5), (0.35, -0.2, 1.2), (-0.5, -0.1, 2.0), (0.4, 0.1, 1.0)):
                p_room = (cam_in_room @ np.array([*p_cam, 1.0]))[:3]
                expected = info.matrix() @ np.array(p_cam)
                u, v = _marker_pixel(video, sim, p_room, w, h)
                assert u == pytest.approx(expected[0] / expected[2], abs=2.0), (w, p_cam)
                assert v == pytest.approx(expected[1] / expected[2], abs=2.0), (w, p_cam)


ROOMS = [
    "configs/sim_paper_room.yaml",
    "configs/sim_lab_room.yaml",
    {"world": {"room": {"size_m": [7.0, 5.0], "seed": 41, "posters_per_wall": 6}}},
    {"world": {"room": {"size_m": [3.0, 3.0], "seed": 77, "posters_per_wall": 2}},
     "survey": {"wall_offset_m": 0.7}},
]  # fmt: skip


@pytest.mark.parametrize("room", ROOMS, ids=["paper", "lab", "seed41", "seed77"])
def test_akaze_finds_100_keypoints_on_a_poster_wall_from_one_metre(room: Any) -> None:
    akaze = cv2.AKAZE_create()  # type: ignore[attr-defined]
    posters = {"world": {"room": {"style": "posters"}}}  # posters in the camera's band
    cfg = naoloc.config.load_config(room).with_overrides(posters)
    with naoloc.connect(cfg) as robot:
        sim, video = _parts(robot)
        handle = video.subscribeCamera("akaze", 0, kQVGA, kYuvColorSpace, 30)
        # Level the view: StandInit's torso leans 0.1 rad forward (the camera looks 6.9 deg down).
        robot.motion.angleInterpolationWithSpeed("HeadPitch", -0.1, 1.0)
        counts = []
        for poster in sim.layout.posters[:: max(1, len(sim.layout.posters) // 4)]:
            along = poster.center[1] if poster.wall in ("x0", "x1") else poster.center[0]
            x, y = wall_point(poster.wall, along, 1.0, sim.room_size())
            heading = {"y0": -math.pi / 2, "x1": 0.0, "y1": math.pi / 2, "x0": math.pi}
            sim.teleport(x, y, heading[poster.wall])
            gray = frame_from_naoqi(video.getImageRemote(handle)).gray()
            counts.append(len(akaze.detect(gray)))
        assert min(counts) >= 100, counts


def test_time_stamps_colorspaces_and_bottom_camera() -> None:
    with naoloc.connect(SMALL) as robot:
        sim, video = _parts(robot)
        rgb = video.subscribeCamera("t", 0, kQVGA, kRGBColorSpace, 30)
        first = frame_from_naoqi(video.getImageRemote(rgb))
        second = frame_from_naoqi(video.getImageRemote(rgb))
        assert second.stamp - first.stamp == pytest.approx(0.02, abs=1e-6)
        assert second.stamp == pytest.approx(sim.sim_time(), abs=1e-6)
        assert np.array_equal(first.pixels, second.pixels)  # nothing moved, no noise
        gray = frame_from_naoqi(video.getImageRemote(video.subscribeCamera("g", 0, 1, 0, 30)))
        assert (
            np.abs(gray.gray().astype(int) - cv2.cvtColor(first.pixels, cv2.COLOR_RGB2GRAY)).max()
            <= 1
        )
        bottom = frame_from_naoqi(video.getImageRemote(video.subscribeCamera("b", 1, kVGA, 13, 5)))
        assert bottom.camera == 1 and bottom.width == 640 and float(bottom.gray().std()) > 5
        assert not np.array_equal(cv2.resize(bottom.bgr(), (320, 240))[..., ::-1], first.pixels)
        with pytest.raises(naoloc.errors.RobotError):
            video.subscribeCamera("big", 0, 4, kRGBColorSpace, 30)  # k16VGA


def test_realism_is_seeded_and_changes_the_image() -> None:
    frames = []
    realism = {
        "profile": "ideal",
        **{"noise_std": 8.0, "blur_px": 1.0, "exposure": 1.3, "jpeg_quality": 60, "seed": 5},
    }
    degraded: dict[str, Any] = {**SMALL, "world": {**SMALL["world"], "camera_realism": realism}}
    for cfg in (SMALL, degraded, degraded):
        with naoloc.connect(cfg) as robot:
            _, video = _parts(robot)
            handle = video.subscribeCamera("r", 0, kQVGA, kRGBColorSpace, 30)
            frames.append(frame_from_naoqi(video.getImageRemote(handle)).pixels.copy())
    clean, noisy, again = frames
    assert np.array_equal(noisy, again)
    assert np.abs(noisy.astype(int) - clean.astype(int)).mean() > 5
    assert noisy.mean() > clean.mean()  # exposure 1.3


def test_lights_and_posters_can_change_after_creation() -> None:
    with naoloc.connect(SMALL) as robot:
        sim, video = _parts(robot)
        poster = next(p for p in sim.layout.posters if p.wall == "x1")
        sim.teleport(3.0, poster.center[1], 0.0)
        base = video.render_rgb(0, 320, 240).copy()
        sim.set_light_scale(0.4)
        assert video.render_rgb(0, 320, 240).mean() < 0.7 * base.mean()
        sim.set_light_scale(1.0)
        assert np.array_equal(video.render_rgb(0, 320, 240), base)
        assert poster.name in sim.poster_names()
        sim.remove_poster(poster.name)
        removed = video.render_rgb(0, 320, 240).copy()
        assert removed.std() < base.std()
        sim.restore_poster(poster.name)
        assert np.array_equal(video.render_rgb(0, 320, 240), base)
        sim.move_poster(poster.name, 0.3)
        moved = video.render_rgb(0, 320, 240)
        assert not np.array_equal(moved, base) and not np.array_equal(moved, removed)
        with pytest.raises(naoloc.errors.RobotError):
            sim.remove_poster("no_such_poster")
    dim = {**SMALL, "world": {**SMALL["world"], "sim": {"light": 0.5}}}
    with naoloc.connect(dim) as robot:  # world.sim.light applies from the start
        sim, video = _parts(robot)
        sim.teleport(3.0, poster.center[1], 0.0)
        assert video.render_rgb(0, 320, 240).mean() < 0.8 * base.mean()
