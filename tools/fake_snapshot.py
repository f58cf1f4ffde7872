"""Save a PNG contact sheet of fake-backend camera frames, to check the room looks right.

Usage::

    .venv/bin/python tools/fake_snapshot.py [-c CONFIG] [--seed N] [-o fake_snapshot.png] [--bench]

Frames (QVGA, top camera unless noted), room frame poses: the four walls seen from the
room centre, a wall seen from 1 m, a corner, the view from the start pose, and the bottom
camera. Each tile is labelled with its pose. Prints the A-KAZE keypoint count per frame;
``--bench`` also prints the median wall time of getImageRemote per resolution.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import naoloc
from naoloc.constants import (
    RESOLUTION_NAMES,
    kBottomCamera,
    kQQVGA,
    kQVGA,
    kRGBColorSpace,
    kTopCamera,
    kVGA,
)
from naoloc.robot.image import frame_from_naoqi


def main(argv: list[str] | None = None) -> int:
    """Render the contact sheet; returns the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-c", "--config", help="YAML config (robot.backend is forced to fake)")
    parser.add_argument("--seed", type=int, default=None, help="world.room.seed override")
    parser.add_argument("-o", "--output", default="fake_snapshot.png", help="PNG to write")
    parser.add_argument("--bench", action="store_true", help="time frames per resolution")
    args = parser.parse_args(argv)
    cfg = naoloc.load_config(args.config)
    overrides: dict = {"robot": {"backend": "fake"}}
    if args.seed is not None:
        overrides["world"] = {"room": {"seed": args.seed}}
    cfg = cfg.with_overrides(overrides)
    sx, sy = cfg.world.room.size_m
    start = cfg.start_pose()
    views = [
        ("centre, east", (sx / 2, sy / 2, 0.0), kTopCamera),
        ("centre, north", (sx / 2, sy / 2, math.pi / 2), kTopCamera),
        ("centre, west", (sx / 2, sy / 2, math.pi), kTopCamera),
        ("centre, south", (sx / 2, sy / 2, -math.pi / 2), kTopCamera),
        ("1 m from south", (sx / 2, 1.0, -math.pi / 2), kTopCamera),
        ("corner", (sx - 1.2, sy - 1.2, math.pi / 4), kTopCamera),
        ("start pose", start, kTopCamera),
        ("bottom camera", (sx / 2, sy / 2, 0.0), kBottomCamera),
    ]
    akaze = cv2.AKAZE_create()  # type: ignore[attr-defined]
    tiles = []
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        robot.motion.wakeUp()
        robot.posture.goToPosture("StandInit", 1.0)
        for label, (x, y, theta), camera in views:
            robot.sim.teleport(x, y, theta)
            handle = robot.video.subscribeCamera("snapshot", camera, kQVGA, kRGBColorSpace, 30)
            frame = frame_from_naoqi(robot.video.getImageRemote(handle))
            robot.video.unsubscribe(handle)
            keypoints = len(akaze.detect(frame.gray()))
            print(f"{label:16s} ({x:.2f}, {y:.2f}, {theta:+.2f}): {keypoints} A-KAZE keypoints")
            tile = frame.bgr().copy()
            text = f"{label} ({x:.1f},{y:.1f},{math.degrees(theta):.0f}deg) kp={keypoints}"
            cv2.putText(tile, text, (4, 14), cv2.FONT_HERSHEY_PLAIN, 0.9, (0, 0, 0), 3)
            cv2.putText(tile, text, (4, 14), cv2.FONT_HERSHEY_PLAIN, 0.9, (255, 255, 255), 1)
            tiles.append(tile)
        if args.bench:
            _bench(robot, sx, sy)
    rows = [np.hstack(tiles[i : i + 4]) for i in range(0, len(tiles), 4)]
    sheet = np.vstack(rows)
    out = Path(args.output)
    if not cv2.imwrite(str(out), sheet):
        print(f"cannot write {out}", file=sys.stderr)
        return 1
    print(f"wrote {out} ({sheet.shape[1]}x{sheet.shape[0]})")
    return 0


def _bench(robot: naoloc.Robot, sx: float, sy: float, frames: int = 30) -> None:
    """Print the median wall time of one getImageRemote per resolution."""
    assert robot.sim is not None
    for resolution in (kQQVGA, kQVGA, kVGA):
        handle = robot.video.subscribeCamera("bench", kTopCamera, resolution, kRGBColorSpace, 30)
        times = []
        for k in range(frames):
            robot.sim.teleport(1.0 + (sx - 2.0) * k / frames, sy / 2, 0.7 * k)
            t0 = time.perf_counter()
            robot.video.getImageRemote(handle)
            times.append(time.perf_counter() - t0)
        robot.video.unsubscribe(handle)
        name = RESOLUTION_NAMES[resolution]
        print(f"getImageRemote {name}: {1e3 * float(np.median(times)):.1f} ms median")


if __name__ == "__main__":
    sys.exit(main())
