"""Random protocol in rooms the code has never been tuned to, and the pooled figures.

Each room comes from a seed (posters, textures, furniture and its size); pass seeds that
appear nowhere in the repository, or none to draw three from os.urandom. Nothing is
written into the repository: outputs go to --out (default: a folder under /tmp).

    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py -n 60 --workers 2
    MUJOCO_GL=egl .venv/bin/python tools/eval_unseen_rooms.py --seeds 123 456 789 -n 60

Prints one line per room and the pooled median / 90th percentile position error.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import Config, load_config
from naoloc.evaluation.pipeline import evaluate
from naoloc.evaluation.stats import summarize


def room_config(seed: int, backend: str = "mujoco") -> Config:
    """A room drawn from ``seed``: sides 5-8 m, 4-6 posters per wall, furniture.

    Args:
        seed: Room seed (also the world's room.seed).
        backend: "mujoco" or "fake".

    Returns:
        A config with the survey 1 m from the walls, 2 laps, 0.2 m steps.
    """
    rng = np.random.default_rng(seed)
    sx, sy = (round(float(v), 1) for v in rng.uniform(5.0, 8.0, size=2))
    return load_config(
        {
            "robot": {"backend": backend},
            "world": {
                "room": {
                    "size_m": [sx, sy],
                    "seed": int(seed),
                    "posters_per_wall": int(rng.integers(4, 7)),
                    "furniture": True,
                }
            },
            "survey": {"laps": 2, "step_m": 0.2, "wall_offset_m": 1.0},
        }
    )


def main() -> int:
    """Run the random protocol in three unseen rooms and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="room seeds")
    parser.add_argument("-n", type=int, default=60, help="test poses per room")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--backend", default="mujoco", choices=("mujoco", "fake"))
    parser.add_argument("--out", type=Path, default=None, help="output folder (not the repo)")
    args = parser.parse_args()
    seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(3)]
    out = args.out or Path(tempfile.mkdtemp(prefix="naoloc_unseen_"))
    errors: list[float] = []
    rooms: list[dict[str, Any]] = []
    t0 = time.monotonic()
    for seed in seeds:
        cfg = room_config(seed, args.backend)
        line = evaluate(cfg, "random", args.n, seed, out / f"room_{seed}", workers=args.workers)
        recs = json.loads((out / f"room_{seed}" / "estimates.json").read_text(encoding="utf-8"))
        errors += [r["error_m"] if r["error_m"] is not None else float("nan")
                   for r in recs if r["variant"] == "main"]  # fmt: skip
        room = {"seed": seed, "size_m": list(cfg.world.room.size_m), **line}
        rooms.append(room)
        print(
            f"room seed {seed} {cfg.world.room.size_m[0]:g} x {cfg.world.room.size_m[1]:g} m: "
            f"n {line['n']} median {line['median_error_m']} m p90 {line['p90_error_m']} m "
            f"max {line['max_error_m']} m heading {line['median_heading_error_deg']} deg "
            f"map {line['map_build_s']} s localize {line['localize_ms_median']} ms "
            f"wall {line['wall_s']} s",
            flush=True,
        )
    s = summarize(errors)
    pooled = {
        "rooms": len(rooms),
        "n": s.n,
        "median_error_m": round(s.median_m, 4),
        "p90_error_m": round(s.p90_m, 4),
        "max_error_m": round(s.max_m, 4),
        "within_0_3m": round(s.within_0_3m, 4),
        "wall_s": round(time.monotonic() - t0, 1),
        "out": str(out),
    }
    print(f"pooled over {len(rooms)} rooms: {json.dumps(pooled)}")
    (out / "unseen_rooms.json").write_text(json.dumps({"rooms": rooms, "pooled": pooled}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
