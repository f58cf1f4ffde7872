"""A map of one room used in another: does the localizer say "not the mapped room"?

Usage::

    python tools/eval_unseen_rooms.py --protocol anywhere -n 20 --seeds A B C --out DIR
    python tools/eval_wrong_room.py DIR [-n 10] [--record REC]
    python tools/eval_wrong_room.py --replay REC


For every ordered pair of rooms in an ``eval_unseen_rooms`` folder (each room's config and
map), the robot stands at ``-n`` random free poses of room B and localizes (the standstill
look, its turns included) with room A's map. Printed: how often it said "not the mapped
room", how often it gave no pose otherwise, and how often it gave a pose, with the poses
more than 0.3 m from anything it could mean (every pose in another room is wrong). The
targets: "not the mapped room" in >= 95 % of the tries and a pose in none.

``--record REC`` writes each try's observations to ``REC/MAP_in_ROOM_K.mcap`` (the filter's
every picture and floor line, as ``naoloc localize --record`` does); ``--replay REC`` re-scores
those recordings with the code and tuning at hand (each recording's own filter tuning, as
recorded, keys older code does not know dropped, unless ``--tuning-now``), so two versions of
the filter are compared on the very same observations rather than on two live runs.
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
from replay_eval import recorded_tuning

from naoloc.behaviours.localize import localize
from naoloc.config import FilterTuning, load_config
from naoloc.data.recording import read_recording, recorded_localizer
from naoloc.localization.localizer import replay
from naoloc.mapping import load_map
from naoloc.robot.registry import connect

Counts = dict[str, int]


def _summary(counts: Counts, posed: list[dict[str, object]]) -> None:
    """Print the tries' verdicts and the poses given."""
    total = max(1, sum(counts.values()))
    summary = {
        "tries": sum(counts.values()),
        "not_mapped_share": round(counts["not the mapped room"] / total, 3),
        "lost_share": round(counts["lost"] / total, 3),
        "posed": counts["tracking"],
        "confident_posed": sum(1 for p in posed if float(p["confidence"]) >= 0.5),  # type: ignore[arg-type]
    }
    print(f"wrong room: {json.dumps(summary)}")
    print("scores of the poses given:", sorted(p["score"] for p in posed))  # type: ignore[type-var]
    for p in posed:
        print(f"  posed: {p['map']} map in {p['room']}: {p.get('name', '')}")


def _replay(folder: Path, tuning_now: bool) -> int:
    """Re-score every recorded try in ``folder`` with the filter at hand."""
    paths = sorted(folder.glob("*_in_*.mcap"))
    if not paths:
        raise SystemExit(f"{folder}: no recorded tries (*_in_*.mcap)")
    counts: Counts = {"not the mapped room": 0, "lost": 0, "tracking": 0}
    posed: list[dict[str, object]] = []
    maps: dict[str, object] = {}
    for path in paths:
        rec = read_recording(path)
        map_path = str(rec.meta["map"])
        if map_path not in maps:
            maps[map_path] = load_map(map_path)
        tuning = FilterTuning() if tuning_now else recorded_tuning(rec.config)
        est = replay(maps[map_path], rec.observations, tuning, seed=rec.seed).pose()  # type: ignore[arg-type]
        counts[str(est.status)] += 1
        name, room = path.stem.split("_in_")
        room = room.rsplit("_", 1)[0]
        if est.found:
            posed.append({"map": name, "room": room, "name": path.name,
                          "score": est.evidence.get("picture_score"),
                          "confidence": est.confidence})  # fmt: skip
    _summary(counts, posed)
    return 0


def main() -> int:
    """Localize in room B with room A's map, for every pair."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=Path, nargs="?", help="an eval_unseen_rooms output folder")
    parser.add_argument("-n", type=int, default=10, help="tries per pair of rooms")
    parser.add_argument("--pairs", type=int, default=6, help="pairs of rooms at most")
    parser.add_argument(
        "--cyclic", action="store_true",
        help="pair each room's map with the next room (many maps), not the first map with all",
    )  # fmt: skip
    parser.add_argument("--record", type=Path, help="write each try's observations here")
    parser.add_argument("--replay", type=Path, help="re-score the tries recorded here")
    parser.add_argument(
        "--tuning-now", action="store_true",
        help="replay with today's default filter tuning, not the recorded one",
    )  # fmt: skip
    args = parser.parse_args()
    if args.replay is not None:
        return _replay(args.replay, args.tuning_now)
    if args.folder is None:
        parser.error("give an eval_unseen_rooms output folder, or --replay REC")
    rooms = sorted(
        p
        for p in args.folder.glob("room_*")
        if (p / "config.yaml").is_file() and any((p / "maps").glob("*.npz"))
    )
    if len(rooms) < 2:
        raise SystemExit(f"{args.folder}: needs two rooms or more with a map (room_*/maps/*.npz)")
    counts: Counts = {"not the mapped room": 0, "lost": 0, "tracking": 0}
    posed: list[dict[str, object]] = []
    if args.cyclic:
        pairs = [(rooms[i], rooms[(i + 1) % len(rooms)]) for i in range(len(rooms))]
    else:
        pairs = list(permutations(rooms, 2))
    for a, b in pairs[: args.pairs]:
        map_path = next((a / "maps").glob("*.npz"))
        vmap = load_map(map_path)
        cfg = load_config(b / "config.yaml")
        rng = np.random.default_rng(zlib.crc32(f"{a.name}|{b.name}".encode()))
        with connect(cfg) as robot:
            sim = robot.sim
            assert sim is not None
            sx, sy = sim.room_size()
            for k in range(args.n):
                for _try in range(200):
                    x, y = rng.uniform(0.4, sx - 0.4), rng.uniform(0.4, sy - 0.4)
                    if sim.is_free(float(x), float(y), 0.3):
                        break
                sim.teleport(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
                name = f"{a.name}_in_{b.name}_{k}.mcap"
                if args.record is not None:
                    args.record.mkdir(parents=True, exist_ok=True)
                    with recorded_localizer(
                        args.record / name, cfg, "localize", map_path.resolve(), vmap
                    ) as loc:
                        est = localize(robot, vmap, cfg, localizer=loc).estimate
                else:
                    est = localize(robot, vmap, cfg).estimate
                counts[str(est.status)] += 1
                if est.found:
                    posed.append({"map": a.name, "room": b.name, "pose": [est.x, est.y],
                                  "name": name, "score": est.evidence.get("picture_score"),
                                  "confidence": est.confidence})  # fmt: skip
        print(f"{a.name} map in {b.name}: {counts}", flush=True)
    _summary(counts, posed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
