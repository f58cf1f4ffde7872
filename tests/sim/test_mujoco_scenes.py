"""MuJoCo backend: the NAO model and every room compile and step with no MuJoCo warning."""

from __future__ import annotations

import importlib
import importlib.util
import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

if importlib.util.find_spec("mujoco") is None:
    pytest.skip("mujoco is not installed", allow_module_level=True)

from naoloc.backends.mujoco import gl

gl.select_gl()  # before mujoco is imported: it reads MUJOCO_GL once

import naoloc  # noqa: E402
from naoloc.backends.mujoco.nao import MODEL_DIR, posture_torso_height  # noqa: E402
from naoloc.backends.mujoco.room import build_layout, survey_circuit  # noqa: E402
from naoloc.backends.mujoco.sim import Simulation  # noqa: E402
from naoloc.config import load_config  # noqa: E402
from naoloc.constants import (  # noqa: E402
    JOINT_LIMITS,
    JOINT_NAMES,
    TOP_CAMERA_IN_HEAD,
)
from naoloc.robot.keyframe import TORSO_HEIGHT_STANDINIT, camera_in_robot  # noqa: E402

mujoco: Any = importlib.import_module("mujoco")
pytestmark = pytest.mark.sim


def _sim(robot: naoloc.Robot) -> Simulation:
    assert isinstance(robot.sim, Simulation)
    return robot.sim


CONFIGS = sorted(Path(__file__).resolve().parents[2].glob("configs/*.yaml"))


def _no_warnings(data: object) -> dict[str, int]:
    return {
        mujoco.mjtWarning(i).name: int(s.number)
        for i, s in enumerate(data.warning)  # type: ignore[attr-defined]
        if s.number > 0
    }


@pytest.mark.parametrize("name", ["nao.xml", "scene.xml"])
def test_model_files_compile_and_step_without_warnings(name: str) -> None:
    model = mujoco.MjModel.from_xml_path(str(MODEL_DIR / name))
    data = mujoco.MjData(model)
    for _ in range(400):
        mujoco.mj_step(model, data)
    assert _no_warnings(data) == {}
    assert np.all(np.isfinite(data.qpos))


def test_model_has_nao_joints_limits_masses_and_cameras() -> None:
    model = mujoco.MjModel.from_xml_path(str(MODEL_DIR / "nao.xml"))
    names = [model.joint(i).name for i in range(model.njnt)]
    assert set(JOINT_NAMES) <= set(names) and len(JOINT_NAMES) == 26
    actuated = {model.actuator(i).name for i in range(model.nu)} & set(JOINT_NAMES)
    assert len(actuated) == 25 and "RHipYawPitch" not in actuated  # one motor for both
    for joint, (lo, hi, speed) in JOINT_LIMITS.items():
        assert model.joint(joint).range == pytest.approx([lo, hi], abs=1e-4)
        assert model.numeric(f"speed/{joint}").data[0] == pytest.approx(speed, rel=1e-4)
    for joint in JOINT_NAMES:
        assert model.numeric(f"speed/{joint}").data[0] > 0
    assert 5.0 < float(np.sum(model.body_mass)) < 5.4  # NAO: about 5.3 kg
    (cx, cy, cz), _ = TOP_CAMERA_IN_HEAD
    assert model.camera("CameraTop").pos == pytest.approx([cx, cy, cz], abs=1e-6)


def test_standinit_camera_height_matches_keyframe_geometry() -> None:
    assert posture_torso_height("StandInit") == pytest.approx(TORSO_HEIGHT_STANDINIT, abs=1e-6)
    with naoloc.connect({"world": {"room": {"size_m": [3.0, 3.0], "posters_per_wall": 1}},
                         "survey": {"wall_offset_m": 0.8}}) as robot:  # fmt: skip
        sim = _sim(robot)
        sim.prepare_render()
        cam = sim.data.camera("CameraTop")
        x, y, th = sim.true_pose()
        expected = camera_in_robot(0.0, 0.0)[:3, 3]
        c, s = math.cos(th), math.sin(th)
        rel = cam.xpos - np.array([x, y, 0.0])
        in_robot = np.array([c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1], rel[2]])
        assert in_robot == pytest.approx(expected, abs=1e-3)


@pytest.mark.parametrize("style", ["home", "office", "posters"])
@pytest.mark.parametrize("path", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_every_config_compiles_and_steps_without_warnings(path: Path, style: str) -> None:
    cfg = load_config(path).with_overrides(
        {"robot": {"backend": "mujoco"}, "world": {"room": {"style": style}}}
    )
    with naoloc.connect(cfg) as robot:
        sim = _sim(robot)
        robot.motion.move(0.1, 0.0, 0.3)
        for _ in range(50):
            robot.motion.getRobotPosition(False)
        robot.motion.stopMove()
        robot.motion.setAngles("Head", [1.0, -0.3], 1.0)
        robot.posture.goToPosture("Crouch", 1.0)
        robot.posture.goToPosture("StandInit", 1.0)
        assert sim.warnings() == {}
        assert np.all(np.isfinite(sim.data.qpos))
        x, y, _ = sim.true_pose()
        assert sim.is_free(x, y, 0.1)


@pytest.mark.parametrize("seed,size", [(0, (6.0, 6.0)), (5, (9.0, 4.0)), (8, (3.0, 2.5))])
def test_room_layout_posters_unique_and_furniture_clear_of_the_circuit(
    seed: int, size: tuple[float, float]
) -> None:
    cfg = load_config(
        {
            "world": {
                "room": {
                    "size_m": list(size),
                    "seed": seed,
                    "posters_per_wall": 4,
                    "style": "posters",
                }
            },
            "survey": {"wall_offset_m": 0.7},
        }
    )
    layout = build_layout(cfg)
    assert len(layout.posters) == 16
    assert {p.wall for p in layout.posters} == {"x0", "x1", "y0", "y1"}
    images = [p.image for p in layout.posters]
    for i in range(len(images)):
        for j in range(i + 1, len(images)):
            if images[i].shape == images[j].shape:
                assert not np.array_equal(images[i], images[j])
    for p in layout.posters:
        x, y, z = p.center
        assert -0.01 <= x <= size[0] + 0.01 and -0.01 <= y <= size[1] + 0.01
        assert z - p.height / 2 > 0.0 and z + p.height / 2 < layout.wall_height
    corners = survey_circuit(cfg)
    for f in layout.furniture:
        x0, y0, x1, y1 = f.rect
        assert 0 < x0 < x1 < size[0] and 0 < y0 < y1 < size[1]
        for px, py in corners:
            assert not (x0 - 0.3 < px < x1 + 0.3 and y0 - 0.3 < py < y1 + 0.3)
        assert not layout.is_free((x0 + x1) / 2, (y0 + y1) / 2, 0.01)
    assert layout.is_free(size[0] / 2, size[1] / 2, 0.3)
    again = build_layout(cfg)
    pairs = zip(layout.posters, again.posters, strict=True)
    assert all(np.array_equal(a.image, b.image) for a, b in pairs)
    assert [f.rect for f in layout.furniture] == [f.rect for f in again.furniture]


def test_posters_from_a_folder_of_photographs(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    for i in range(3):
        photo = rng.integers(0, 256, (60 + i, 80, 3), dtype=np.uint8)
        assert cv2.imwrite(str(tmp_path / f"photo_{i}.png"), photo)
    (tmp_path / "notes.txt").write_text("not an image")
    room = {"posters_per_wall": 1, "poster_dir": str(tmp_path), "style": "posters"}
    cfg = load_config({"world": {"room": room}})
    posters = build_layout(cfg).posters
    assert len(posters) == 4
    firsts = {p.image.tobytes()[:30] for p in posters[:3]}
    assert len(firsts) == 3  # each photograph used once before any repeats
    with pytest.raises(naoloc.errors.ConfigError, match="poster_dir"):
        build_layout(load_config({"world": {"room": {"poster_dir": str(tmp_path / "none")}}}))


def test_missing_headless_gl_names_the_packages(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(gl.ctypes.util, "find_library", lambda name: None)
    with pytest.raises(naoloc.errors.RenderError, match="apt-get install libegl1"):
        gl.select_gl()


def test_missing_mujoco_names_the_pip_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(__import__("sys").modules, "mujoco", None)
    with pytest.raises(naoloc.errors.DependencyNotInstalled, match=r"naoloc\[sim\]"):
        naoloc.connect({"robot": {"backend": "mujoco"}})


@pytest.mark.parametrize("style", ["home", "office"])
@pytest.mark.parametrize("path", CONFIGS[1:], ids=[p.stem for p in CONFIGS[1:]])
def test_furnished_rooms_hang_art_at_real_heights_and_repeat(path: Path, style: str) -> None:
    cfg = load_config(path).with_overrides({"world": {"room": {"style": style}}})
    layout = build_layout(cfg)
    assert len(layout.posters) >= 4 and layout.fixtures
    for p in layout.posters:
        assert 1.2 <= p.center[2] <= 1.8, p.name  # picture centres as in real rooms
        assert p.center[2] - p.height / 2 >= 0.95, p.name  # above the camera's band
    again = build_layout(cfg)  # same seed, same room
    assert [p.center for p in again.posters] == [p.center for p in layout.posters]
    assert all(
        np.array_equal(a.image, b.image) for a, b in zip(layout.posters, again.posters, strict=True)
    )
    assert [f.rect for f in again.furniture] == [f.rect for f in layout.furniture]
    other = build_layout(cfg.with_overrides({"world": {"room": {"seed": cfg.world.room.seed + 1}}}))
    assert [p.center for p in other.posters] != [p.center for p in layout.posters]
    low = [f for f in layout.fixtures if f.pos[2] + f.size[-1] <= 0.95]
    assert len(low) >= 4  # skirting, sockets, radiators: the camera's band is not empty
    for x, y in survey_circuit(cfg):
        assert layout.is_free(x, y, 0.2)


def test_posters_style_keeps_the_rooms_of_earlier_versions() -> None:
    cfg = load_config({"world": {"room": {"style": "posters", "seed": 3}}})
    layout = build_layout(cfg)
    assert layout.fixtures == () and layout.materials == {}
    assert all(0.45 <= p.center[2] <= 0.75 for p in layout.posters)
    default = build_layout(load_config({"world": {"room": {"seed": 3}}}))
    assert default.style == "home"
