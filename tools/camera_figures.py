"""What the camera sees in each room style: A-KAZE keypoints, brightness and noise per frame.

For every room style (home, office, posters), light (1.0 and 0.3 = ``world.sim.light``) and
camera profile (ideal, nao), the MuJoCo robot stands 1 m from each wall at a few places
along it, facing it with the head level (HeadPitch 0, the camera's band is 0.07-0.95 m) and,
tilted up 0.35 and 0.6 rad (toward the art at 1.2-1.8 m); it prints per setting the
median and minimum A-KAZE keypoints per QVGA frame, the mean luma, and the noise std
(from two frames of the same still view).

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/camera_figures.py [-c CONFIG] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import cv2
import numpy as np

import naoloc
from naoloc.backends.mujoco.room import wall_point
from naoloc.config import load_config
from naoloc.constants import kQVGA, kYuvColorSpace
from naoloc.robot.image import frame_from_naoqi

FACING = {"y0": -math.pi / 2, "x1": 0.0, "y1": math.pi / 2, "x0": math.pi}


def measure(cfg: naoloc.Config, pitch: float) -> dict[str, float]:
    """Keypoints, luma and noise over the views of one setting."""
    akaze = cv2.AKAZE_create()  # type: ignore[attr-defined]
    counts, lumas, noises = [], [], []
    with naoloc.connect(cfg) as robot:
        sim: Any = robot.sim
        robot.motion.angleInterpolationWithSpeed("HeadPitch", pitch, 1.0)
        handle = robot.video.subscribeCamera("figures", 0, kQVGA, kYuvColorSpace, 30)
        sx, sy = sim.room_size()
        for wall in ("y0", "x1", "y1", "x0"):
            length = sx if wall in ("y0", "y1") else sy
            for frac in (0.3, 0.5, 0.7):
                x, y = wall_point(wall, frac * length, 1.0, (sx, sy))
                if not sim.is_free(x, y, 0.2):
                    continue
                sim.teleport(x, y, FACING[wall])
                a = frame_from_naoqi(robot.video.getImageRemote(handle)).gray()
                b = frame_from_naoqi(robot.video.getImageRemote(handle)).gray()
                counts.append(len(akaze.detect(a)))
                lumas.append(float(a.mean()))
                diff = a.astype(np.float64) - b.astype(np.float64)
                noises.append(float(diff.std() / math.sqrt(2)))
        robot.video.unsubscribe(handle)
    return {
        "views": len(counts),
        "keypoints_median": float(np.median(counts)),
        "keypoints_min": float(np.min(counts)),
        "luma_mean": round(float(np.mean(lumas)), 1),
        "noise_std": round(float(np.median(noises)), 2),
    }


def main(argv: list[str] | None = None) -> int:
    """Print the table (and one JSON line with --json)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-c", "--config", default="configs/sim_paper_room.yaml")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--styles", default="home,office,posters", help="comma-separated")
    args = parser.parse_args(argv)
    rows = []
    print(f"{'style':8s} {'light':>5s} {'camera':6s} {'head':7s} {'views':>5s} "
          f"{'kp med':>6s} {'kp min':>6s} {'luma':>6s} {'noise':>6s}")  # fmt: skip
    for style in args.styles.split(","):
        for light in (1.0, 0.3):
            for profile in ("ideal", "nao"):
                for head, pitch in (("level", 0.0), ("up-0.35", -0.35), ("up-0.6", -0.6)):
                    cfg = load_config(args.config).with_overrides(
                        {"world": {"room": {"style": style}, "sim": {"light": light},
                                   "camera_realism": {"profile": profile}}}
                    )  # fmt: skip
                    r = measure(cfg, pitch)
                    rows.append({"style": style, "light": light, "camera": profile,
                                 "head": head, **r})  # fmt: skip
                    print(
                        f"{style:8s} {light:5.1f} {profile:6s} {head:7s} {r['views']:5d} "
                        f"{r['keypoints_median']:6.0f} {r['keypoints_min']:6.0f} "
                        f"{r['luma_mean']:6.1f} {r['noise_std']:6.2f}"
                    )
    if args.json:
        print(json.dumps({"config": args.config, "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
