"""The random or anywhere protocol in rooms the code has never been tuned to, pooled.

Each room comes from a seed (posters, textures, furniture and its size); pass seeds that
appear nowhere in the repository, or none to draw three from os.urandom. Nothing is
written into the repository: outputs go to --out (default: a folder under /tmp). ``--set``
changes any config key of every room (dotted path = YAML value), e.g. dim light or one
picture per wall; ``--small`` draws rooms of 3.5-4.5 x 2.8-3.5 m like the paper's lab.

    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py -n 60 --workers 2
    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py --protocol anywhere -n 60
    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py --set world.sim.light=0.3
    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py --seeds 123 456 789 -n 60

Prints one line per room and the pooled median / 90th percentile position error and the
share of poses with no estimate (a miss, counted as infinitely wrong in the percentiles), and
the CPU time of each localization's map work (extraction, localizer, floor step; not the
pictures or the motion): median, 90th percentile and largest.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from naoloc.config import Config, load_config
from naoloc.errors import NaolocError
from naoloc.evaluation.pipeline import evaluate
from naoloc.evaluation.stats import integrity, summarize


def room_config(
    seed: int,
    backend: str = "mujoco",
    *,
    small: bool = False,
    mixed: bool = False,
    overrides: dict[str, Any] | None = None,
) -> Config:
    """A room drawn from ``seed``: sides 5-8 m (small: about 4 x 3 m), 4-6 pictures a wall.

    Args:
        seed: Room seed (also the world's room.seed).
        backend: "mujoco" or "fake".
        small: A lab-sized room with the survey 0.7 m from the walls and 3 laps (nearer, the
            robot's arm hides the floor beside it from the bottom camera).
        mixed: Any room the localization targets name: 4 x 3 to 10 x 8 m, home or office,
            light 0.3, 1 or 1.5 (a room under 4.5 m wide is surveyed 0.7 m from the walls).
        overrides: Nested config keys applied to every room.

    Returns:
        A config with the survey 1 m from the walls, 2 laps, 0.2 m steps (small: 0.7 m, 3).
    """
    rng = np.random.default_rng(seed)
    room: dict[str, Any] = {}  # what a kind of room adds (drawn before the pictures a wall)
    world: dict[str, Any] = {}
    if mixed:
        sx = round(float(rng.uniform(4.0, 10.0)), 1)
        sy = round(float(rng.uniform(3.0, min(sx, 8.0))), 1)
        small_room = min(sx, sy) < 4.5
        survey = {"laps": 3 if small_room else 2, "step_m": 0.2,
                  "wall_offset_m": 0.7 if small_room else 1.0}  # fmt: skip
        room = {"style": str(rng.choice(["home", "office"]))}
        world = {"sim": {"light": float(rng.choice([0.3, 1.0, 1.5]))}}
    elif small:
        sx, sy = round(float(rng.uniform(3.5, 4.5)), 1), round(float(rng.uniform(2.8, 3.5)), 1)
        survey = {"laps": 3, "step_m": 0.2, "wall_offset_m": 0.7}
    else:
        sx, sy = (round(float(v), 1) for v in rng.uniform(5.0, 8.0, size=2))
        survey = {"laps": 2, "step_m": 0.2, "wall_offset_m": 1.0}
    base = {
        "robot": {"backend": backend},
        "world": {
            "room": {
                "size_m": [sx, sy],
                "seed": int(seed),
                "posters_per_wall": int(rng.integers(4, 7)),
                "furniture": True,
                **room,
            },
            **world,
        },
        "survey": survey,
    }
    return load_config(_wall_on_the_right(base)).with_overrides(overrides or {})


def _wall_on_the_right(base: dict[str, Any]) -> dict[str, Any]:
    """The survey told its wall's side: the evaluation places the robot at
    ``Config.start_pose`` (offset, offset, 0), the wall y = 0 on its right. This tool
    measures localization in a surveyed room; finding the side is the survey's own figure
    (``tools/eval_survey.py``)."""
    base["survey"] = {"head_yaw_rad": -math.pi / 2, **base["survey"]}
    return base


def add_set_option(parser: argparse.ArgumentParser, help_text: str) -> None:
    """The tools' repeatable ``--set KEY=VALUE`` config override (read by :func:`parse_sets`)."""
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help=help_text)


def parse_sets(items: list[str]) -> dict[str, Any]:
    """``["a.b=1", "c=x"]`` -> ``{"a": {"b": 1}, "c": "x"}`` (values parsed as YAML)."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"--set {item!r}: expected KEY.PATH=VALUE")
        node = out
        *parents, leaf = key.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        try:
            node[leaf] = yaml.safe_load(value)
        except yaml.YAMLError as err:
            why = getattr(err, "problem", None) or str(err).splitlines()[0]
            raise SystemExit(f"--set {item!r}: VALUE is not YAML ({why})") from None
    return out


def main() -> int:
    """Run the random protocol in three unseen rooms and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="room seeds")
    parser.add_argument("-n", type=int, default=60, help="test poses per room")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--backend", default="mujoco", choices=("mujoco", "fake"))
    parser.add_argument("--out", type=Path, default=None, help="output folder (not the repo)")
    parser.add_argument("--protocol", default="random", choices=("random", "anywhere", "changed"))
    parser.add_argument("--small", action="store_true", help="lab-sized rooms (about 4 x 3 m)")
    parser.add_argument(
        "--mixed", action="store_true",
        help="rooms of every kind the targets name: 4 x 3 to 10 x 8 m, home and office, "
        "light 0.3 to 1.5 (drawn from each seed)",
    )  # fmt: skip
    add_set_option(parser, "config override for every room, e.g. world.sim.light=0.3")
    parser.add_argument(
        "--record", action="store_true",
        help="record each localization's observations (room_SEED/recordings/main_INDEX.mcap; "
        "naoloc replay re-runs one without a robot)",
    )  # fmt: skip
    parser.add_argument(
        "--pool", type=Path, nargs="+", default=None, metavar="OUT",
        help="pool earlier outputs' rooms (every room_* folder) instead of running",
    )  # fmt: skip
    args = parser.parse_args()
    overrides = parse_sets(args.set)
    t0 = time.monotonic()
    rooms: list[dict[str, Any]] = []
    failed: list[dict[str, Any]] = []  # rooms without a map (survey or map failed)
    protocol = args.protocol
    if args.pool:
        for folder in args.pool:
            saved = json.loads((folder / "unseen_rooms.json").read_text(encoding="utf-8"))
            rooms += [_filled(room, folder) for room in saved["rooms"]]
            protocol = saved["pooled"].get("protocol", protocol)
            failed += saved["pooled"].get("rooms_without_map", [])
        out = args.pool[0]
    else:
        seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(3)]
        out = args.out or Path(tempfile.mkdtemp(prefix="naoloc_unseen_"))
        for seed in seeds:
            cfg = room_config(
                seed, args.backend, small=args.small, mixed=args.mixed, overrides=overrides
            )
            try:
                room = _room(cfg, seed, args.protocol, args.n, out, args.workers, args.record)
            except NaolocError as err:  # the survey or the map failed: no localization there
                print(f"room seed {seed}: no map: {err}", flush=True)
                failed.append({"seed": seed, "error": str(err)})
                continue
            rooms.append(room)
    pooled = {
        "rooms": len(rooms),
        "rooms_without_map": failed,
        **_pool(rooms),
        # What a user gets: build-map refuses a map that fails its checks (no localization
        # there at all), so these figures count only the rooms whose map passed them.
        "checked_maps": {
            "rooms": sum(1 for r in rooms if r["map_checked"]),
            **_pool([r for r in rooms if r["map_checked"]]),
        },
        "protocol": protocol,
        "overrides": overrides,
        "wall_s": round(time.monotonic() - t0, 1),
        "out": str(out),
    }
    print(f"pooled over {len(rooms)} rooms: {json.dumps(pooled)}")
    target = out / "unseen_rooms.json" if not args.pool else Path(tempfile.mkdtemp()) / "pool.json"
    target.write_text(json.dumps({"rooms": rooms, "pooled": pooled}, indent=1))
    return 0


def _room(
    cfg: Config, seed: int, protocol: str, n: int, out: Path, workers: int, record: bool = False
) -> dict[str, Any]:
    """One room: survey, map, localize; its records and figures (printed on one line);
    ``record``: each localization's observations kept (``room_SEED/recordings``)."""
    from naoloc.mapping import load_map
    from naoloc.mapping.checks import map_checked

    folder = out / f"room_{seed}"
    line = evaluate(cfg, protocol, n, seed, folder, workers=workers, record=record)
    recs = json.loads((folder / "estimates.json").read_text(encoding="utf-8"))
    main = [r for r in recs if r["variant"] == "main"]
    full = json.loads(Path(line["summary"]).read_text(encoding="utf-8"))
    line.update({k: full[k] for k in ("compute_ms_median", "compute_ms_max")})
    maps = sorted((folder / "maps").glob("*.npz"))
    checked = bool(maps) and map_checked(load_map(maps[0])) is True
    room = {"seed": seed, "size_m": list(cfg.world.room.size_m),
            "style": cfg.world.room.style, "light": cfg.world.sim.light,
            "map_checked": checked, "records": main,
            "integrity": integrity(main), **line}  # fmt: skip
    print(
        f"room seed {seed} {cfg.world.room.size_m[0]:g} x {cfg.world.room.size_m[1]:g} m "
        f"{cfg.world.room.style} light {cfg.world.sim.light:g}"
        f"{'' if checked else ' (map fails its checks: build-map would refuse it)'}: "
        f"n {line['n']} median {line['median_error_m']} m p90 {line['p90_error_m']} m "
        f"max {line['max_error_m']} m heading {line['median_heading_error_deg']} deg "
        f"no estimate {line['no_estimate']} "
        f"map {line['map_build_s']} s localize {line['localize_ms_median']} ms "
        f"(compute median {line['compute_ms_median']} max {line['compute_ms_max']} ms) "
        f"wall {line['wall_s']} s",
        flush=True,
    )
    return room


def _filled(room: dict[str, Any], out: Path) -> dict[str, Any]:
    """A room of an earlier output with its records and map check (older outputs lack them)."""
    from naoloc.mapping import load_map
    from naoloc.mapping.checks import map_checked

    folder = out / f"room_{room['seed']}"
    if "records" not in room:
        recs = json.loads((folder / "estimates.json").read_text(encoding="utf-8"))
        room["records"] = [r for r in recs if r["variant"] == "main"]
    if "map_checked" not in room:
        maps = sorted((folder / "maps").glob("*.npz"))
        room["map_checked"] = bool(maps) and map_checked(load_map(maps[0])) is True
    return room


def _pool(rooms: list[dict[str, Any]]) -> dict[str, Any]:
    """The rooms' localizations pooled: accuracy, integrity, compute and robot time."""
    every = [r for room in rooms for r in room["records"]]
    errors = [r["error_m"] if r["error_m"] is not None else float("nan") for r in every]
    compute = [r["compute_ms"] for r in every]
    robot_s = [r["robot_s"] for r in every if r.get("robot_s") is not None]
    if not every:
        return {"n": 0}
    s = summarize(errors)

    def pct(values: list[float], qs: tuple[tuple[str, int], ...]) -> dict[str, Any]:
        return {k: round(float(np.percentile(values, q)), 2) if values else None for k, q in qs}

    return {
        "n": s.n,
        "median_error_m": round(s.median_m, 4),
        "p90_error_m": round(s.p90_m, 4),
        "within_0_3m": round(s.within_0_3m, 4),
        "no_estimate": int(sum(1 for e in errors if not np.isfinite(e))),
        "compute_ms": pct(compute, (("median", 50), ("p90", 90), ("max", 100))),
        "integrity": integrity(every),
        "robot_s": pct(robot_s, (("median", 50), ("p90", 90))),
    }


if __name__ == "__main__":
    raise SystemExit(main())
