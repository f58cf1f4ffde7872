"""How far a built map's keyframe poses are from the simulator's truth, against the walls'.

Usage::

    python tools/map_pose_accuracy.py SURVEY.mcap [more.mcap ...] [--set KEY=VALUE ...]

For each simulator dataset it builds the map in memory the way ``naoloc build-map`` does
(the dataset's own config, then the ``--set`` overrides), and prints in the map frame (the
survey start) the position error of the wall-referenced poses build-map starts from
(``map.wall_poses``) and of the map's final, bundle-adjusted poses: median and p90 (m) and
the median heading error (rad). Nothing is written.

    python tools/map_pose_accuracy.py S.mcap --set map.tuning.bundle.wall_prior_sigma=null

builds the map as before the wall-pose prior (the adjustment free to bend the poses).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_unseen_rooms import parse_sets

from naoloc.commands.build_map import survey_keyframes
from naoloc.config import load_config
from naoloc.dataset import read_dataset
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.mapping import build_map


def _errors(poses: np.ndarray, truth: list[Pose2D]) -> tuple[np.ndarray, np.ndarray]:
    pairs = list(zip(poses, truth, strict=True))
    pos = np.array([math.hypot(p[0] - t.x, p[1] - t.y) for p, t in pairs])
    head = np.array([abs(math.remainder(p[2] - t.theta, 2 * math.pi)) for p, t in pairs])
    return pos, head


def _line(name: str, pos: np.ndarray, head: np.ndarray) -> str:
    return (
        f"{name} median {np.median(pos):.3f} m  p90 {np.percentile(pos, 90):.3f} m  "
        f"heading median {np.median(head):.4f} rad"
    )


def main() -> int:
    """Build each survey's map and print its pose errors."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("datasets", type=Path, nargs="+", help="simulator survey .mcap files")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="config override, e.g. map.tuning.bundle.wall_prior_sigma=null",
    )  # fmt: skip
    args = parser.parse_args()
    overrides = parse_sets(args.set)
    for path in args.datasets:
        try:
            data = read_dataset(path)
        except NaolocError as err:
            print(f"map_pose_accuracy: {err}", file=sys.stderr)
            return 2
        origin = data.meta.get("origin_room_pose")
        if origin is None or any(kf.true_pose is None for kf in data.keyframes):
            print(f"map_pose_accuracy: {path}: not a simulator dataset", file=sys.stderr)
            return 2
        cfg = load_config(data.config if isinstance(data.config, dict) else None)
        cfg = cfg.with_overrides(overrides)
        keyframes, facts = survey_keyframes(data, cfg.map, cfg.survey.wall_offset_m)
        start = np.array([[k.pose.x, k.pose.y, k.pose.theta] for k in keyframes])
        vmap = build_map(keyframes, cfg.map, meta={**dict(data.meta), **facts})
        o = Pose2D.from_list(origin)
        truth = [relative_pose(o, kf.true_pose) for kf in data.keyframes if kf.true_pose]
        source = "walls" if facts.get("wall_poses") is not None else "odometry"
        print(f"{path}: {_line(f'{source:8s}', *_errors(start, truth))}")
        print(f"{path}: {_line('map     ', *_errors(vmap.refined_poses, truth))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
