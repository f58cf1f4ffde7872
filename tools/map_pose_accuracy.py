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
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_unseen_rooms import add_set_option, parse_sets
from wall_pose_accuracy import pose_errors, sim_survey

from naoloc.config import load_config
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.mapping import build_map
from naoloc.mapping.from_survey import survey_keyframes


def _line(name: str, poses: Sequence[Pose2D], truth: list[Pose2D]) -> str:
    pos, head = pose_errors(list(poses), truth)
    return (
        f"{name} median {np.median(pos):.3f} m  p90 {np.percentile(pos, 90):.3f} m  "
        f"heading median {np.median(head):.4f} rad"
    )


def main() -> int:
    """Build each survey's map and print its pose errors."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("datasets", type=Path, nargs="+", help="simulator survey .mcap files")
    add_set_option(parser, "config override, e.g. map.tuning.bundle.wall_prior_sigma=null")
    args = parser.parse_args()
    overrides = parse_sets(args.set)
    for path in args.datasets:
        try:
            data, truth = sim_survey(path)
        except NaolocError as err:
            print(f"map_pose_accuracy: {err}", file=sys.stderr)
            return 2
        cfg = load_config(data.config if isinstance(data.config, dict) else None)
        cfg = cfg.with_overrides(overrides)
        keyframes, facts = survey_keyframes(data, cfg.map, cfg.survey.wall_offset_m)
        vmap = build_map(keyframes, cfg.map, meta={**dict(data.meta), **facts})
        source = "walls" if facts.get("wall_poses") is not None else "odometry"
        print(f"{path}: {_line(f'{source:8s}', [k.pose for k in keyframes], truth)}")
        refined = [Pose2D(*p) for p in vmap.refined_poses]
        print(f"{path}: {_line('map     ', refined, truth)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
