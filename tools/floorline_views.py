"""Which head poses let the bottom camera see a side wall's floor line, by wall distance.

The robot (MuJoCo, default honest world) is put at distances 0.4-1.3 m from a side wall
of rooms drawn from seeds (home and office, dim and bright light), at several places
along it, and for each view (|HeadYaw|, HeadPitch) the floor line on that side is
measured. Prints, per view and distance, the share of places where a line within 5 cm of
the truth was seen (``ok``) and where a line was seen more than 5 cm off (``wrong``).
This chose :data:`naoloc.behaviours.wall_follow.BESIDE_VIEW` and ``BEHIND_VIEW`` (yaw, pitch
and the blur of the picture, px).

    MUJOCO_GL=egl .venv/bin/python tools/floorline_views.py [--seeds 1 2 3]
"""

from __future__ import annotations

import argparse
import math
import os

import naoloc
from naoloc.behaviours.wall_follow import FloorEye
from naoloc.config import load_config
from naoloc.errors import RobotError
from naoloc.robot.camera import lens_of, look, stand

# (|HeadYaw| rad, HeadPitch rad, blur px)
VIEWS = [(math.pi / 2, -0.672, 0), (math.pi / 2, 0.2, 0), (2.0, 0.0, 0), (2.0, 0.2, 0),
         (2.0, 0.0, 15), (2.0, 0.1, 15), (2.0, 0.2, 15), (2.0, 0.3, 15)]  # fmt: skip
DISTANCES = [0.4, 0.45, 0.5, 0.55, 0.6, 0.7, 0.8, 1.0, 1.2, 1.3]
TOLERANCE_M = 0.05


def main() -> int:
    """Measure every view at every distance in every room; print the shares."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=None)
    args = parser.parse_args()
    seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(4)]
    counts: dict[tuple[int, float], list[int]] = {}
    for i, seed in enumerate(seeds):
        style, light = ("home", "office")[i % 2], (0.3, 1.0)[(i // 2) % 2]
        cfg = load_config({
            "robot": {"backend": "mujoco"},
            "world": {"room": {"size_m": [5.0, 4.0], "seed": seed, "style": style},
                      "sim": {"light": light}},
            "survey": {"wall_offset_m": 0.5},
        })  # fmt: skip
        with naoloc.connect(cfg) as robot:
            assert robot.sim is not None
            stand(robot)
            eye = FloorEye(robot, cfg.camera, lens=lens_of(cfg))
            for d in DISTANCES:
                for x in (1.4, 2.5, 3.6):
                    try:
                        robot.sim.teleport(x, d, 0.0)
                    except RobotError:
                        continue  # furniture there
                    for v, (yaw, pitch, blur) in enumerate(VIEWS):
                        look(robot, -yaw, pitch)
                        line = eye.measure(-math.pi / 2, blur=blur)
                        row = counts.setdefault((v, d), [0, 0, 0])
                        row[0] += 1
                        if line is not None and abs(line.distance - d) <= TOLERANCE_M:
                            row[1] += 1
                        elif line is not None:
                            row[2] += 1
            eye.close()
        print(f"room {seed} ({style}, light {light}) done", flush=True)
    print(
        "view (|yaw|, pitch, blur) " + " ".join(f"{d:>8.2f}" for d in DISTANCES) + "  (ok/wrong %)"
    )
    for v, (yaw, pitch, blur) in enumerate(VIEWS):
        cells = []
        for d in DISTANCES:
            n, ok, wrong = counts.get((v, d), [0, 0, 0])
            cells.append(f"{100 * ok // max(1, n):>4}/{100 * wrong // max(1, n):<3}")
        print(f"({yaw:.2f}, {pitch:+.2f}, {blur:2})      " + " ".join(cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
