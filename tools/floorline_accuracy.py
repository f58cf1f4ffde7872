"""How far the floor-wall line detector reads from the truth, in rendered unseen rooms.

Usage::

    MUJOCO_GL=egl python tools/floorline_accuracy.py [--seeds 101 202 303 404] [--views 36]
        [--set world.sim.light=0.3] [--compare REV] [--front 2.2 3.6]
        [--side 0.45 0.65 2.0 0.0 15]

For each room (``tools/eval_unseen_rooms.py``'s rooms: home style, furniture, the default
honest camera) the robot is put at random poses facing a stretch of wall with no furniture
in front of it (a 1.6 m wide strip): two thirds of the views as the survey measures a side
wall (head turned to the wall on the right, 0.7-1.4 m away), one third as it measures the
front wall before a corner (0.9-2.2 m ahead; ``--front`` sets the range, e.g. the
farther walls a localization's scans see). The bottom camera's image goes to
:func:`naoloc.perception.floorline.detect_wall_line` and the distance it reads is compared with the
true one. Prints, per kind and per room: lines found, median and p90 of |error| (m), the
share off by more than 0.1 m, and the median signed error. ``--compare REV`` scores the
detector of git revision ``REV`` on the same images in the same process (the baseline).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import subprocess
import sys
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any

import cv2
import numpy as np

import naoloc
from naoloc.behaviours.wall_follow import FRONT_PITCH, FloorEye
from naoloc.config import FloorLineTuning
from naoloc.constants import FRAME_ROBOT
from naoloc.errors import RobotError
from naoloc.robot.camera import lens_of, look, stand

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tools")]

from eval_unseen_rooms import add_set_option, parse_sets, room_config  # noqa: E402


def _clear(rects: list[tuple[float, ...]], x: float, y: float, normal: float, d: float) -> bool:
    """No furniture in the 1.6 m wide strip from (x, y) to the wall ``d`` m along ``normal``."""
    c, s = math.cos(normal), math.sin(normal)
    for t in np.linspace(0.0, d, 12):
        for u in np.linspace(-0.8, 0.8, 9):
            px, py = x + c * t - s * u, y + s * t + c * u
            for x0, y0, x1, y1 in rects:
                if x0 - 0.05 <= px <= x1 + 0.05 and y0 - 0.05 <= py <= y1 + 0.05:
                    return False
    return True


def views(
    seed: int,
    n: int,
    overrides: dict[str, Any],
    front: tuple[float, float] = (0.9, 2.2),
    side: tuple[float, float, float, float, int] = (0.7, 1.4, math.pi / 2, -0.672, 0),
) -> list[dict[str, Any]]:
    """``n`` bottom-camera views of bare wall in room ``seed`` with their true distances
    (front walls ``front`` m ahead; side walls ``side[:2]`` m away, seen at |HeadYaw|
    ``side[2]``, HeadPitch ``side[3]``, blurred ``side[4]`` px as the survey does)."""
    from naoloc.backends.mujoco.interior import plan_walls
    from naoloc.backends.mujoco.room import build_layout

    cfg = room_config(seed, overrides=overrides)
    sx, sy = cfg.world.room.size_m
    rects = [f.rect for f in build_layout(cfg).furniture] + [o[2] for o in plan_walls(cfg).objects]
    rng = np.random.default_rng(seed)
    out: list[dict[str, Any]] = []
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        stand(robot)
        eye = FloorEye(robot, cfg.camera, lens=lens_of(cfg))
        try:
            for _ in range(20 * n):
                if len(out) >= n:
                    break
                beside = len(out) % 3 != 0
                d = float(rng.uniform(*side[:2]) if beside else rng.uniform(*front))
                wall = int(rng.integers(0, 4))
                a = float(rng.uniform(0.8, (sx if wall % 2 == 0 else sy) - 0.8))
                x, y, normal = [(a, d, -math.pi / 2), (sx - d, a, 0.0),
                                (a, sy - d, math.pi / 2), (d, a, math.pi)][wall]  # fmt: skip
                if not (0.4 < x < sx - 0.4 and 0.4 < y < sy - 0.4):
                    continue
                if not _clear(rects, x, y, normal, d):
                    continue
                try:
                    robot.sim.teleport(x, y, normal + math.pi / 2 if beside else normal)
                except RobotError:
                    continue  # the robot would overlap something
                expect = -math.pi / 2 if beside else 0.0
                look(robot, -side[2] if beside else 0.0, side[3] if beside else FRONT_PITCH)
                frame = eye.camera.frame()
                info = eye.camera.info(frame)
                pose = np.asarray(robot.motion.getTransform("CameraBottom", FRAME_ROBOT, True))
                image = frame.bgr()
                if beside and side[4] > 1:  # the survey's blur of that view
                    image = cv2.GaussianBlur(image, (side[4] | 1, side[4] | 1), 0)
                out.append({"image": image, "pose": pose, "hfov": info.hfov,
                            "vfov": info.vfov, "truth": d, "expect": expect,
                            "kind": "side" if beside else "front", "seed": seed})  # fmt: skip
        finally:
            eye.close()
    return out


def _module_at(rev: str) -> ModuleType:
    """``naoloc/perception/floorline.py`` as it was at git revision ``rev``."""
    src = subprocess.run(["git", "show", f"{rev}:naoloc/perception/floorline.py"], cwd=ROOT,
                         check=True, capture_output=True, text=True).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp(prefix="floorline_")) / "floorline_old.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("floorline_old", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["floorline_old"] = mod  # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


def score(
    name: str,
    detector: ModuleType,
    data: list[dict[str, Any]],
    lens: Any,
    tun: FloorLineTuning | None = None,
) -> None:
    """Print the errors of ``detector`` on ``data`` (``tun``: its thresholds, the config's
    ``camera.floor_lines``; None: the detector's defaults, as a revision before them has)."""
    rows: dict[tuple[str, int | str], list[float]] = {}
    extra: dict[str, Any] = {} if tun is None else {"tun": tun}
    for v in data:
        line = detector.detect_wall_line(v["image"], v["hfov"], v["vfov"], v["pose"],
                                         expect_normal=v["expect"], lens=lens,
                                         **extra)  # fmt: skip
        err = math.nan if line is None else line.distance - v["truth"]
        rows.setdefault((v["kind"], "all"), []).append(err)
        rows.setdefault((v["kind"], v["seed"]), []).append(err)
    print(f"{name}:")
    for (kind, room), errs in sorted(rows.items(), key=lambda kv: (kv[0][0], str(kv[0][1]))):
        e = np.array(errs)
        ok = e[np.isfinite(e)]
        if ok.size == 0:
            print(f"  {kind:5s} room {room}: found 0 of {e.size}")
            continue
        a = np.abs(ok)
        print(f"  {kind:5s} room {room}: found {ok.size} of {e.size}, |error| median "
              f"{np.median(a):.3f} m p90 {np.percentile(a, 90):.3f} m, > 0.1 m "
              f"{np.mean(a > 0.1) * 100:.0f} %, median {np.median(ok):+.3f} m")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[101, 202, 303, 404])
    parser.add_argument("--views", type=int, default=36, help="views per room")
    add_set_option(parser, "config override of the rendered rooms, e.g. world.sim.light=0.3")
    parser.add_argument("--compare", metavar="REV", help="also score this git revision's detector")
    parser.add_argument("--front", type=float, nargs=2, default=(0.9, 2.2), metavar=("MIN", "MAX"),
                        help="the front walls' distances, m (default 0.9 2.2)")  # fmt: skip
    parser.add_argument("--side", type=float, nargs=5, default=(0.7, 1.4, math.pi / 2, -0.672, 0),
                        metavar=("MIN", "MAX", "YAW", "PITCH", "BLUR"),
                        help="the side walls' distances (m) and the view (|HeadYaw|, HeadPitch "
                        "rad, blur px; default 0.7 1.4 1.5708 -0.672 0: the survey's beside "
                        "view; 0.45 0.65 2.0 0.0 15: its behind view)")  # fmt: skip
    args = parser.parse_args(argv)
    overrides = parse_sets(args.set)
    side = (*args.side[:4], int(args.side[4]))
    data = [v for seed in args.seeds for v in views(seed, args.views, overrides, args.front, side)]
    cfg = room_config(args.seeds[0], overrides=overrides)
    lens = lens_of(cfg)
    from naoloc.perception import floorline

    score("this tree", floorline, data, lens, cfg.camera.floor_lines)
    if args.compare:
        score(f"revision {args.compare}", _module_at(args.compare), data, lens)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
