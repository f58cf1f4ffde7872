"""Benchmark the MuJoCo backend: camera frames per second and simulated/wall time when walking.

Prints, for the same scene in the same run:
- ``getImageRemote`` frames/s at QVGA and VGA (kRGB, top camera; each call also advances
  the simulation by one 20 ms ALMotion cycle, as the backend always does);
- a raw ``mujoco.Renderer`` loop (``update_scene`` + ``render``) on the same model, camera
  and scene options, at the same sizes;
- their ratio (getImageRemote time per frame / raw time per frame);
- all of that twice, with ``world.camera_realism.profile`` ``ideal`` and ``nao``, and the
  time of the camera model alone (``naoloc/backends/simulated/camera_model.py``) per frame;
- the simulated-time / wall-time ratio while walking with the camera off (moveTo legs of a
  survey-like square: 1 m forward, a quarter turn, repeated).

Targets (issue 3): QVGA getImageRemote at most 1.3x a raw frame and at least 150 frames/s on
a 2-core CPU; walking at least 50x faster than real time.

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/bench_sim.py [-c CONFIG] [-n FRAMES] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import naoloc
from naoloc.backends.mujoco.sim import Simulation, mujoco
from naoloc.backends.mujoco.video import HIDDEN_GROUPS, MujocoVideo
from naoloc.backends.simulated.camera_model import CameraModel, Motion
from naoloc.config import load_config
from naoloc.constants import kQVGA, kRGBColorSpace, kVGA


def _time_get_image(video: MujocoVideo, resolution: int, frames: int) -> float:
    handle = video.subscribeCamera("bench", 0, resolution, kRGBColorSpace, 30)
    for _ in range(5):  # warm up: the first frame uploads textures and compiles shaders
        video.getImageRemote(handle)
    start = time.perf_counter()
    for _ in range(frames):
        video.getImageRemote(handle)
    elapsed = time.perf_counter() - start
    video.unsubscribe(handle)
    return elapsed / frames


def _time_raw(sim: Simulation, width: int, height: int, frames: int) -> float:
    renderer = mujoco.Renderer(sim.model, height, width)
    option = mujoco.MjvOption()
    for g in HIDDEN_GROUPS:
        option.geomgroup[g] = 0
    try:
        for _ in range(5):
            renderer.update_scene(sim.data, camera="CameraTop", scene_option=option)
            renderer.render()
        start = time.perf_counter()
        for _ in range(frames):
            renderer.update_scene(sim.data, camera="CameraTop", scene_option=option)
            renderer.render()
        return (time.perf_counter() - start) / frames
    finally:
        renderer.close()


def _time_model(sim: Simulation, video: MujocoVideo, width: int, height: int, frames: int) -> float:
    """Seconds per frame of the camera model alone on a rendered frame (turning camera)."""
    rgb = video.render_rgb(0, width, height).copy()
    model = CameraModel(sim.cfg.world.camera_realism, 0, 0)
    motion = Motion(omega=(0.0, 0.5, 0.0))
    hfov, vfov = sim.fov
    for i in range(5):
        model.process(rgb, time_s=i / 30, fps=30, hfov=hfov, vfov=vfov, motion=motion)
    start = time.perf_counter()
    for i in range(frames):
        model.process(rgb, time_s=(i + 5) / 30, fps=30, hfov=hfov, vfov=vfov, motion=motion)
    return (time.perf_counter() - start) / frames


def _walk_ratio(robot: naoloc.Robot, sim: Simulation, legs: int) -> tuple[float, float]:
    sim.teleport(1.0, 1.0, 0.0)
    t_sim0, t_wall0 = sim.sim_time(), time.perf_counter()
    for _ in range(legs):
        robot.motion.moveTo(1.0, 0.0, 0.0)
        robot.motion.moveTo(0.0, 0.0, math.pi / 2)
    sim_s = sim.sim_time() - t_sim0
    wall_s = time.perf_counter() - t_wall0
    return sim_s, wall_s


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-c", "--config", default="configs/sim_paper_room.yaml")
    parser.add_argument("-n", "--frames", type=int, default=200, help="frames per measurement")
    parser.add_argument("--legs", type=int, default=4, help="walk legs (1 m + quarter turn)")
    parser.add_argument("--json", action="store_true", help="print one JSON line at the end")
    args = parser.parse_args(argv)

    out: dict[str, Any] = {
        "config": args.config,
        "mujoco_gl": os.environ.get("MUJOCO_GL"),
        "cpus": os.cpu_count(),
    }
    for profile in ("ideal", "nao"):
        cfg = load_config(args.config).with_overrides(
            {"world": {"camera_realism": {"profile": profile}}}
        )
        with naoloc.connect(cfg) as robot:
            sim, video = robot.sim, robot.video
            assert isinstance(sim, Simulation) and isinstance(video, MujocoVideo)
            for name, res, (w, h) in (("qvga", kQVGA, (320, 240)), ("vga", kVGA, (640, 480))):
                ours = _time_get_image(video, res, args.frames)
                raw = _time_raw(sim, w, h, args.frames)
                model = _time_model(sim, video, w, h, args.frames)
                key = f"{profile}_{name}"
                out[f"{key}_get_image_fps"] = round(1.0 / ours, 1)
                out[f"{key}_raw_renderer_fps"] = round(1.0 / raw, 1)
                out[f"{key}_cost_ratio"] = round(ours / raw, 3)
                out[f"{key}_camera_model_ms"] = round(model * 1e3, 3)
                print(
                    f"{profile:5s} {name.upper():4s} getImageRemote {1 / ours:6.1f} frames/s "
                    f"({ours * 1e3:6.2f} ms) | raw mujoco.Renderer {1 / raw:6.1f} frames/s "
                    f"({raw * 1e3:6.2f} ms) | ratio {ours / raw:4.2f} | camera model "
                    f"{model * 1e3:5.2f} ms"
                )
            if profile == "nao":
                sim_s, wall_s = _walk_ratio(robot, sim, args.legs)
                out["walk_sim_s"] = round(sim_s, 2)
                out["walk_wall_s"] = round(wall_s, 3)
                out["walk_realtime_factor"] = round(sim_s / wall_s, 1)
                print(
                    f"walking, camera off: {sim_s:.1f} s simulated in {wall_s:.2f} s wall "
                    f"= {sim_s / wall_s:.0f}x real time"
                )
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
