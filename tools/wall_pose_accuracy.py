"""How far a survey's keyframe poses are from the simulator's truth: odometry vs walls.

Usage::

    naoloc survey -c paper_room -o /tmp/s.mcap
    python tools/wall_pose_accuracy.py /tmp/s.mcap [more.mcap ...]

For each dataset it prints, in the map frame (the survey start), the position error of
the keyframes' odometry poses and of the wall-referenced poses build-map uses
(``map.wall_poses``, :mod:`naoloc.wall_poses`): median, p90 and max (m), the median heading
error (rad), and the ratio of the medians. Needs a simulator's dataset (true poses and
``origin_room_pose``).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from naoloc.dataset import read_dataset
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.wall_poses import wall_poses


def _errors(poses: list[Pose2D], truth: list[Pose2D]) -> tuple[np.ndarray, np.ndarray]:
    pos = np.array([math.dist((p.x, p.y), (t.x, t.y)) for p, t in zip(poses, truth, strict=True)])
    head = np.array(
        [
            abs(math.remainder(p.theta - t.theta, 2 * math.pi))
            for p, t in zip(poses, truth, strict=True)
        ]
    )
    return pos, head


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("datasets", nargs="+")
    args = parser.parse_args(argv)
    for path in args.datasets:
        try:
            data = read_dataset(path)
        except NaolocError as err:
            print(f"wall_pose_accuracy: {err}", file=sys.stderr)
            return 2
        origin = data.meta.get("origin_room_pose")
        if origin is None or any(kf.true_pose is None for kf in data.keyframes):
            print(f"{path}: no ground truth (not a simulator's survey)", file=sys.stderr)
            return 2
        o = Pose2D(*origin)
        truth = [o.inverse() * kf.true_pose for kf in data.keyframes if kf.true_pose is not None]
        offset = float(data.config.get("survey", {}).get("wall_offset_m", 1.0))
        walled = wall_poses(data.keyframes, data.meta, offset=offset)
        rows = [("odometry", [kf.pose for kf in data.keyframes])]
        if walled is not None:
            rows.append(("walls", [kf.pose for kf in walled.keyframes]))
        medians = []
        for name, poses in rows:
            pos, head = _errors(poses, truth)
            medians.append(float(np.median(pos)))
            print(
                f"{path}: {name:8s} median {np.median(pos):.3f} m"
                f"  p90 {np.percentile(pos, 90):.3f} m  max {pos.max():.3f} m"
                f"  heading median {np.median(head):.4f} rad"
            )
        if walled is not None:
            print(
                f"{path}: {walled.summary()}; "
                f"odometry/walls median ratio {medians[0] / medians[1]:.1f}x"
            )
        else:
            print(f"{path}: no floor-line records: build-map keeps the odometry poses")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
