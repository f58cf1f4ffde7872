"""go-home from random starts in rooms the code has never been tuned to.

For each room (a seed drawn from os.urandom unless given) it surveys and builds a map with
the ``naoloc`` command line, then runs ``naoloc go-home --at X Y THETA`` from N starts drawn
uniformly over the free floor at least 0.3 m from walls and furniture (the ``anywhere``
protocol's poses), two at a time. Nothing is written into the repository.

    MUJOCO_GL=egl .venv/bin/python tools/eval_go_home.py -n 20
    MUJOCO_GL=egl .venv/bin/python tools/eval_go_home.py -n 20 --set world.sim.light=0.3

Prints one line per start, then per room: starts within 0.3 m and 0.1 m of home, the
median true error, the median ratio of robot time to the time the planned path takes at a
NAO's 0.1 m/s, path length and wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_unseen_rooms import add_set_option, parse_sets, room_config

from naoloc.evaluation.protocols import sample_protocol_poses


def _naoloc(*args: str) -> dict[str, Any]:
    """Run one naoloc verb; its last stdout line as a dict (``failed`` on a non-zero exit)."""
    out = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", *args], capture_output=True, text=True, check=False
    )
    lines = out.stdout.strip().splitlines()
    try:
        result: dict[str, Any] = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        result = {}
    if out.returncode != 0:
        result["failed"] = (out.stderr.strip().splitlines() or ["?"])[-1]
    return result


def _starts(cfg_path: Path, n: int, seed: int) -> list[tuple[float, float, float]]:
    from naoloc.config import load_config
    from naoloc.robot.registry import connect

    cfg = load_config(cfg_path)
    with connect(cfg) as robot:
        assert robot.sim is not None
        poses = sample_protocol_poses("anywhere", n, seed, cfg.world.room.size_m, robot.sim.is_free)
    return [p.room_pose for p in poses]


def main() -> int:
    """Survey, map and go home from N starts per room; print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="room seeds")
    parser.add_argument("-n", type=int, default=20, help="starts per room")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--small", action="store_true", help="lab-sized rooms (about 4 x 3 m)")
    parser.add_argument("--out", type=Path, default=None, help="output folder (not the repo)")
    add_set_option(parser, "config override for every room, e.g. world.sim.light=0.3")
    args = parser.parse_args()
    seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(2)]
    out = args.out or Path(tempfile.mkdtemp(prefix="naoloc_gohome_"))
    overrides = parse_sets(args.set)
    report: list[dict[str, Any]] = []
    for seed in seeds:
        t0 = time.monotonic()
        room = out / f"room_{seed}"
        room.mkdir(parents=True, exist_ok=True)
        cfg = room_config(seed, small=args.small, overrides=overrides)
        cfg_path = room / "config.yaml"
        cfg_path.write_text(yaml.safe_dump(cfg.to_dict(), sort_keys=False), encoding="utf-8")
        survey = _naoloc("survey", "-c", str(cfg_path), "-o", str(room / "s.mcap"))
        built = _naoloc("build-map", "-c", str(cfg_path), "-d", str(room / "s.mcap"),
                        "-o", str(room / "m.npz"))  # fmt: skip
        if "failed" in survey or "failed" in built:
            print(f"room {seed}: survey/map failed: {survey.get('failed') or built.get('failed')}")
            report.append({"seed": seed, "failed": survey.get("failed") or built.get("failed")})
            continue
        starts = _starts(cfg_path, args.n, seed)

        def home(start: tuple[float, float, float], cfg_path: Path = cfg_path,
                 room: Path = room) -> dict[str, Any]:  # fmt: skip
            at = [f"{v:.4f}" for v in start]
            return _naoloc("go-home", "-c", str(cfg_path), "-m", str(room / "m.npz"), "--at", *at)

        with ThreadPoolExecutor(max(1, args.workers)) as pool:
            results = list(pool.map(home, starts))
        errors = []
        for start, res in zip(starts, results, strict=True):
            err = res.get("error_m", float("nan"))
            errors.append(err if err is not None else float("nan"))
            print(f"  start {[round(v, 2) for v in start]}: reached {res.get('reached')} "
                  f"error {err} m looks {res.get('tries')} path {res.get('path_m')} m "
                  f"robot {res.get('robot_s')} s (walk {res.get('walk_s')} s) "
                  f"{'' if res.get('reached') else res.get('reason', '')} "
                  f"{res.get('failed', '')}", flush=True)  # fmt: skip
        e = np.array(errors, dtype=float)
        ok = int(np.sum(np.nan_to_num(e, nan=np.inf) <= 0.3))
        close = int(np.sum(np.nan_to_num(e, nan=np.inf) <= 0.1))
        ratios = [r["robot_s"] / r["walk_s"] for r in results
                  if r.get("walk_s") and r.get("robot_s") is not None]  # fmt: skip
        row = {
            "seed": seed,
            "size_m": list(cfg.world.room.size_m),
            "starts": len(starts),
            "within_0_3m": ok,
            "within_0_1m": close,
            "time_ratio_median": round(float(np.median(ratios)), 2) if ratios else None,
            "median_error_m": round(float(np.median(np.nan_to_num(e, nan=np.inf))), 4),
            "reached": int(sum(1 for r in results if r.get("reached"))),
            "median_path_m": round(float(np.median([r.get("path_m", 0.0) for r in results])), 2),
            "wall_s": round(time.monotonic() - t0, 1),
            "runs": [{"start": list(st), **r} for st, r in zip(starts, results, strict=True)],
        }
        report.append(row)
        print(f"room {seed}: {json.dumps({k: v for k, v in row.items() if k != 'runs'})}",
              flush=True)  # fmt: skip
    (out / "go_home.json").write_text(json.dumps(report, indent=1), encoding="utf-8")
    print(f"outputs in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
