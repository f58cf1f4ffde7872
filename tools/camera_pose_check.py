"""The camera pose from kinematics against the simulator's truth, and the walk's sway.

For each simulated backend (mujoco, fake), prints:

- StandInit, head at zero: ``ALMotion.getPosition("CameraTop", FRAME_ROBOT, True)``
  (mm, deg; the pitch wy > 0 looks down);
- the largest difference between getPosition (FRAME_ROBOT, sensors) and
  ``robot.sim.true_camera_pose`` converted to FRAME_ROBOT, over both cameras and a few
  head poses, standing still (mm and deg);
- while ``move(0.1, 0, 0)`` runs (1-3 s after the start): the true top camera's peak to
  peak sideways motion (mm) and roll (deg) in FRAME_ROBOT, and what is left 1 s after
  ``stopMove``.

Acceptance of issue 11: agreement within 5 mm and 0.5 deg; StandInit looks 2-12 deg down;
sway at least 10 mm peak to peak sideways or 1 deg of roll.

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/camera_pose_check.py [--backend mujoco fake] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import naoloc
from naoloc.constants import FRAME_ROBOT
from naoloc.robot import kinematics as kin


def _in_robot(robot: naoloc.Robot, index: int) -> np.ndarray:
    assert robot.sim is not None
    room = kin.transform_from_6d(robot.sim.true_camera_pose(index))
    return np.linalg.inv(kin.world_to_robot(robot.sim.true_pose())) @ room


def check(backend: str) -> dict[str, Any]:
    """Measure one backend; lengths in mm, angles in deg."""
    cfg = {"robot": {"backend": backend}, "world": {"room": {"furniture": False}}}
    out: dict[str, Any] = {"backend": backend}
    with naoloc.connect(cfg) as robot:
        motion = robot.motion
        robot.posture.goToPosture("StandInit", 1.0)
        p = motion.getPosition("CameraTop", FRAME_ROBOT, True)
        out["standinit_top_mm"] = [round(1000 * v, 1) for v in p[:3]]
        out["standinit_top_pitch_deg"] = round(math.degrees(p[4]), 2)
        worst_mm, worst_deg = 0.0, 0.0
        for yaw, pitch in ((0.0, 0.0), (0.9, -0.3), (-1.5, 0.1), (0.3, 0.4)):
            motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [yaw, pitch], 1.0)
            for index, name in ((0, "CameraTop"), (1, "CameraBottom")):
                got = kin.transform_from_6d(motion.getPosition(name, FRAME_ROBOT, True))
                true = _in_robot(robot, index)
                worst_mm = max(worst_mm, 1000 * float(np.abs(got[:3, 3] - true[:3, 3]).max()))
                cos = (np.trace(got[:3, :3].T @ true[:3, :3]) - 1.0) / 2.0
                worst_deg = max(worst_deg, math.degrees(math.acos(min(1.0, cos))))
        out["max_diff_mm"], out["max_diff_deg"] = round(worst_mm, 3), round(worst_deg, 4)
        motion.angleInterpolationWithSpeed(["HeadYaw", "HeadPitch"], [0.0, 0.0], 1.0)
        lateral, roll = [], []
        motion.move(0.1, 0.0, 0.0)
        try:
            for k in range(150):
                motion.getRobotVelocity()  # one 20 ms cycle
                if k >= 50:
                    local = kin.position6d(_in_robot(robot, 0))
                    lateral.append(local[1])
                    roll.append(local[3])
        finally:
            motion.stopMove()
        for _ in range(50):
            motion.getRobotVelocity()
        still = kin.position6d(_in_robot(robot, 0))
    out["sway_lateral_p2p_mm"] = round(1000 * (max(lateral) - min(lateral)), 1)
    out["sway_roll_p2p_deg"] = round(math.degrees(max(roll) - min(roll)), 2)
    out["after_stop_lateral_mm"] = round(1000 * abs(still[1]), 3)
    out["after_stop_roll_deg"] = round(math.degrees(abs(still[3])), 4)
    return out


def main() -> None:
    """Print one block per backend (and the JSON with --json)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--backend", nargs="+", default=["mujoco", "fake"])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = [check(b) for b in args.backend]
    for r in rows:
        print(f"{r['backend']}:")
        print(
            f"  StandInit top camera {r['standinit_top_mm']} mm, "
            f"pitch {r['standinit_top_pitch_deg']} deg (down)"
        )
        print(
            f"  getPosition vs true_camera_pose: max {r['max_diff_mm']} mm, {r['max_diff_deg']} deg"
        )
        print(
            f"  sway while move(0.1, 0, 0): {r['sway_lateral_p2p_mm']} mm peak to peak sideways, "
            f"{r['sway_roll_p2p_deg']} deg roll; 1 s after stopMove: "
            f"{r['after_stop_lateral_mm']} mm, {r['after_stop_roll_deg']} deg"
        )
    if args.json:
        print(json.dumps(rows))


if __name__ == "__main__":
    main()
