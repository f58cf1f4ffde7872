"""A map of one room used in another: does the localizer say "not the mapped room"?

Usage::

    python tools/eval_unseen_rooms.py --protocol anywhere -n 20 --seeds A B C --out DIR
    python tools/eval_wrong_room.py DIR [-n 10]

For every ordered pair of rooms in an ``eval_unseen_rooms`` folder (each room's config and
map), the robot stands at ``-n`` random free poses of room B and localizes (the standstill
look, its turns included) with room A's map. Printed: how often it said "not the mapped
room", how often it gave no pose otherwise, and how often it gave a pose, with the poses
more than 0.3 m from anything it could mean (every pose in another room is wrong). The
targets: "not the mapped room" in >= 95 % of the tries and a pose in none.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import math
import zlib
from itertools import permutations
from pathlib import Path

import numpy as np

from naoloc.behaviours.localize import localize
from naoloc.config import load_config
from naoloc.mapping import load_map
from naoloc.robot.registry import connect


def main() -> int:
    """Localize in room B with room A's map, for every pair."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=Path, help="an eval_unseen_rooms output folder")
    parser.add_argument("-n", type=int, default=10, help="tries per pair of rooms")
    parser.add_argument("--pairs", type=int, default=6, help="pairs of rooms at most")
    args = parser.parse_args()
    rooms = sorted(p for p in args.folder.glob("room_*") if (p / "config.yaml").is_file())
    if len(rooms) < 2:
        raise SystemExit(f"{args.folder}: needs two rooms or more (room_*/config.yaml)")
    counts = {"not the mapped room": 0, "lost": 0, "tracking": 0}
    posed: list[dict[str, object]] = []
    for a, b in list(permutations(rooms, 2))[: args.pairs]:
        vmap = load_map(next((a / "maps").glob("*.npz")))
        cfg = load_config(b / "config.yaml")
        rng = np.random.default_rng(zlib.crc32(f"{a.name}|{b.name}".encode()))
        with connect(cfg) as robot:
            sim = robot.sim
            assert sim is not None
            sx, sy = sim.room_size()
            for _ in range(args.n):
                for _try in range(200):
                    x, y = rng.uniform(0.4, sx - 0.4), rng.uniform(0.4, sy - 0.4)
                    if sim.is_free(float(x), float(y), 0.3):
                        break
                sim.teleport(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
                est = localize(robot, vmap, cfg).estimate
                counts[str(est.status)] += 1
                if est.found:
                    posed.append({"map": a.name, "room": b.name, "pose": [est.x, est.y],
                                  "score": est.evidence.get("picture_score"),
                                  "confidence": est.confidence})  # fmt: skip
        print(f"{a.name} map in {b.name}: {counts}", flush=True)
    total = sum(counts.values())
    summary = {
        "tries": total,
        "not_mapped_share": round(counts["not the mapped room"] / total, 3),
        "lost_share": round(counts["lost"] / total, 3),
        "posed": counts["tracking"],
        "confident_posed": sum(1 for p in posed if float(p["confidence"]) >= 0.5),  # type: ignore[arg-type]
    }
    print(f"wrong room: {json.dumps(summary)}")
    print("scores of the poses given:", sorted(p["score"] for p in posed))  # type: ignore[type-var]
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
