"""How near the paper's mode can come at the Table 3 positions: the best neuron pose there.

Usage::

    naoloc evaluate -c paper_room --protocol paper --workers 2 -o /tmp/pp
    python tools/paper_mode_floor.py /tmp/pp/surveys/base.mcap /tmp/pp/maps/akaze-300.npz

The paper's mode answers with the mean pose of the training images a neuron won (map
poses). A query at a Table 3 position, facing the protocol's heading, can only match
pictures of the walls it sees: those the survey took facing within 45 deg of that heading.
For each position this prints the nearest such picture (by its true place) and how far its
map pose is from the position, and the nearest map pose of any such picture: an error the
paper's mode cannot go below unless a neuron averages several pictures around the
position. Beside it, the paper's own mean error and twice it (issue 12, item 8).
Needs a simulator's survey (true poses) and a map built from it.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from wall_pose_accuracy import sim_survey

from naoloc.errors import NaolocError
from naoloc.evaluation.protocols import PAPER_POSITIONS
from naoloc.mapping import load_map

SAME_VIEW_RAD = math.radians(45.0)  # a picture facing this near the query's heading


def main(argv: list[str] | None = None) -> int:
    """Print, per Table 3 position, the nearest same-view picture and map pose."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("survey", help="the simulator survey (.mcap) the map was built from")
    parser.add_argument("map", help="its map (.npz)")
    args = parser.parse_args(argv)
    try:
        _, truth = sim_survey(args.survey)
        vmap = load_map(args.map)
    except NaolocError as err:
        print(f"paper_mode_floor: {err}", file=sys.stderr)
        return 2
    n = vmap.wall_images
    if n != len(truth):
        print(f"paper_mode_floor: the map has {n} wall pictures, the survey {len(truth)}",
              file=sys.stderr)  # fmt: skip
        return 2
    poses = np.asarray(vmap.refined_poses[:n], dtype=float)
    for pos in PAPER_POSITIONS:
        same = [
            i
            for i, t in enumerate(truth)
            if abs(math.remainder(t.theta - pos.heading, 2 * math.pi)) < SAME_VIEW_RAD
        ]
        if not same:
            print(f"position {pos.number}: no picture faces heading {pos.heading:.2f} rad")
            continue
        true_off = [math.hypot(truth[i].x - pos.x, truth[i].y - pos.y) for i in same]
        map_off = [math.hypot(poses[i, 0] - pos.x, poses[i, 1] - pos.y) for i in same]
        j = int(np.argmin(true_off))
        paper = pos.paper_mean_error_m()
        print(
            f"position {pos.number} ({pos.x:.1f}, {pos.y:.1f}), heading {pos.heading:.2f} rad: "
            f"nearest same-view picture #{same[j]} {true_off[j]:.3f} m away (its map pose "
            f"{map_off[j]:.3f} m); nearest map pose {min(map_off):.3f} m; "
            f"paper {paper:.3f} m, twice that {2 * paper:.3f} m"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
