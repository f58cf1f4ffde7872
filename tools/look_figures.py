"""Where to point the head: A-KAZE keypoints per frame by head yaw, pitch, resolution, threshold.

The MuJoCo robot stands ``--distance`` m from each wall at a few places along it, turned so
that the head yaw looks straight at the wall (yaw 0: facing it; 1.57: the survey's sideways
look; 0.8: obliquely), the head pitched up as asked (clamped to NAOqi's head anti-collision
limits, so at yaw 1.57 nothing above about -0.33 rad is reachable; the pitch actually
reached is printed). Per setting it prints the median and minimum A-KAZE keypoints per frame
for several detector thresholds (OpenCV's default 0.001 and lower) on the same frames.

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/look_figures.py [--styles home,office] [--json]
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
from naoloc.constants import kQVGA, kVGA, kYuvColorSpace
from naoloc.robot.image import frame_from_naoqi

FACING = {"y0": -math.pi / 2, "x1": 0.0, "y1": math.pi / 2, "x0": math.pi}
THRESHOLDS = (0.001, 0.0003, 0.0001)


def measure(
    cfg: naoloc.Config, yaw: float, pitch: float, resolution: int, distance: float
) -> dict[str, Any]:
    """Keypoints per frame over the views of one head setting, for each threshold."""
    detectors = [cv2.AKAZE_create(threshold=t) for t in THRESHOLDS]  # type: ignore[attr-defined]
    counts: list[list[int]] = [[] for _ in THRESHOLDS]
    with naoloc.connect(cfg) as robot:
        sim: Any = robot.sim
        robot.motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [yaw, pitch], 1.0)
        reached = [float(a) for a in robot.motion.getAngles(["HeadYaw", "HeadPitch"], True)]
        handle = robot.video.subscribeCamera("look", 0, resolution, kYuvColorSpace, 30)
        sx, sy = sim.room_size()
        for wall in ("y0", "x1", "y1", "x0"):
            length = sx if wall in ("y0", "y1") else sy
            for frac in (0.35, 0.65):
                x, y = wall_point(wall, frac * length, distance, (sx, sy))
                if not sim.is_free(x, y, 0.2):
                    continue
                sim.teleport(x, y, FACING[wall] - yaw)
                robot.video.getImageRemote(handle)  # auto exposure settles over frames
                gray = frame_from_naoqi(robot.video.getImageRemote(handle)).gray()
                for k, det in enumerate(detectors):
                    counts[k].append(len(det.detect(gray)))
        robot.video.unsubscribe(handle)
    return {
        "views": len(counts[0]),
        "pitch_reached": round(reached[1], 3),
        "median": [float(np.median(c)) for c in counts],
        "min": [float(np.min(c)) for c in counts],
    }


def main(argv: list[str] | None = None) -> int:
    """Print the table (and one JSON line with --json)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-c", "--config", default="configs/sim_paper_room.yaml")
    parser.add_argument("--styles", default="home,office", help="comma-separated")
    parser.add_argument("--yaws", default="0,0.8,1.57", help="head yaws, rad")
    parser.add_argument("--pitches", default="0,-0.2,-0.4,-0.55,-0.67", help="head pitches, rad")
    parser.add_argument("--resolutions", default="1,2", help="NAOqi ids: 1 QVGA, 2 VGA")
    parser.add_argument("--distance", type=float, default=1.0, help="from the wall, m")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    ths = " ".join(f"{'med@' + format(t, 'g'):>10s}" for t in THRESHOLDS)
    print(f"{'style':7s} {'yaw':>5s} {'pitch':>6s} {'reached':>7s} {'res':>4s} {'views':>5s} {ths}")
    for style in args.styles.split(","):
        cfg = load_config(args.config).with_overrides({"world": {"room": {"style": style}}})
        for yaw in (float(v) for v in args.yaws.split(",")):
            for pitch in (float(v) for v in args.pitches.split(",")):
                for res in (int(v) for v in args.resolutions.split(",")):
                    r = measure(cfg, yaw, pitch, res, args.distance)
                    rows.append({"style": style, "yaw": yaw, "pitch": pitch, "res": res, **r})
                    name = {kQVGA: "QVGA", kVGA: "VGA"}.get(res, str(res))
                    meds = " ".join(f"{m:10.0f}" for m in r["median"])
                    print(
                        f"{style:7s} {yaw:5.2f} {pitch:6.2f} {r['pitch_reached']:7.3f} "
                        f"{name:>4s} {r['views']:5d} {meds}",
                        flush=True,
                    )
    if args.json:
        print(json.dumps({"config": args.config, "distance": args.distance, "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
