"""Re-score every recorded localization of evaluation outputs with the filter at hand.

Usage::

    python tools/eval_unseen_rooms.py --protocol anywhere --record --seeds ... --out OUT
    python tools/replay_eval.py OUT [OUT ...] [--workers 2] [--json DEST] [--set KEY=VALUE ...]

Each ``OUT`` is an output folder of ``tools/eval_unseen_rooms.py --record``. Every recorded
localization (``room_SEED/recordings/main_INDEX.mcap``) of a room whose map passed its
checks is replayed through a new filter over that room's map (``naoloc.localization.
localizer.replay``: the same pictures and lines, in order) and scored against the truth the
evaluation recorded. Printed: the replays, how many gave a pose, how many fell outside their
reported 99 % ellipse (position), the confident wrong ones (more than 0.3 m off at confidence
0.5 or more), and the error's median, p90 and p99.

Each recording's own filter tuning is used, as recorded, with ``--set KEY=VALUE`` overriding
``localize.filter`` keys (a YAML value, as the other tools' ``--set``: recordings made before
a default changed hold the old value). Keys that the filter at hand does not know (a newer
recording replayed by older code) are dropped, so two versions of the filter can be compared
on the same observations. A replay cannot take the pictures a live look would have added
while unsure: where a new filter wants more evidence than the old one did, the replay says
"no estimate" and a live run looks longer.
"""

from __future__ import annotations

import argparse
import glob
import json
import math
import sys
from functools import partial
from multiprocessing import Pool
from pathlib import Path
from typing import Any

import numpy as np
from eval_unseen_rooms import add_set_option, parse_sets

CHI2_2DOF_99 = -2.0 * math.log(0.01)  # 9.21: a position outside its 99 % ellipse
WRONG_M = 0.3  # the "confident wrong": this far off ...
CONFIDENT = 0.5  # ... at this confidence or more


def jobs(outs: list[Path]) -> list[tuple[str, int, list[float]]]:
    """(room folder, pose index, truth) of every recorded localization in checked maps."""
    out: list[tuple[str, int, list[float]]] = []
    for folder in outs:
        summary = json.loads((folder / "unseen_rooms.json").read_text(encoding="utf-8"))
        checked = {r["seed"] for r in summary["rooms"] if r.get("map_checked")}
        for room in sorted(glob.glob(str(folder / "room_*"))):
            if int(room.rsplit("_", 1)[-1]) not in checked:
                continue
            estimates = json.loads(Path(room, "estimates.json").read_text(encoding="utf-8"))
            for e in estimates:
                path = Path(room, "recordings", f"main_{e['index']:03d}.mcap")
                if e.get("variant") == "main" and path.is_file():
                    out.append((room, int(e["index"]), list(e["truth"])))
    return out


def recorded_tuning(config: dict[str, Any], overrides: dict[str, Any] | None = None) -> Any:
    """The filter tuning (``FilterTuning``) a recording's config holds, ``overrides`` set
    and the keys the filter at hand does not know dropped (a newer recording replayed by
    older code). ``config`` is changed in place."""
    from naoloc.config import FilterTuning, load_config

    tuning = config.setdefault("localize", {}).setdefault("filter", {})
    for key in [k for k in tuning if k not in FilterTuning.model_fields]:
        del tuning[key]
    tuning.update(overrides or {})
    return load_config(config).localize.filter


def replay_one(
    job: tuple[str, int, list[float]], overrides: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Replay one recorded localization (``overrides``: ``localize.filter`` keys set); its
    status, error (m), squared Mahalanobis distance and confidence (none without a pose)."""
    from naoloc.data.recording import read_recording
    from naoloc.localization.localizer import replay
    from naoloc.mapping.map import load_map

    room, index, truth = job
    rec = read_recording(Path(room, "recordings", f"main_{index:03d}.mcap"))
    tuning = recorded_tuning(rec.config, overrides)
    vmap = load_map(next(Path(room, "maps").glob("*.npz")))
    pose = replay(vmap, rec.observations, tuning, seed=rec.seed).pose()
    row: dict[str, Any] = {"room": Path(room).name, "index": index, "status": str(pose.status)}
    if pose.found and pose.covariance is not None:
        err = np.array([pose.x - truth[0], pose.y - truth[1]])
        cov = np.asarray(pose.covariance)[:2, :2]
        row.update(
            error_m=float(np.linalg.norm(err)),
            mahalanobis2=float(err @ np.linalg.solve(cov, err)),
            confidence=float(pose.confidence),
        )
    return row


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The figures of a set of replays (see the module's docstring)."""
    posed = [r for r in rows if "error_m" in r]
    errors = np.array([r["error_m"] for r in posed])
    outside = [r for r in posed if r["mahalanobis2"] > CHI2_2DOF_99]
    wrong = [r for r in posed if r["error_m"] > WRONG_M and r["confidence"] >= CONFIDENT]
    figures: dict[str, Any] = {
        "replays": len(rows),
        "posed": len(posed),
        "no_estimate": len(rows) - len(posed),
        "outside_99": len(outside),
        "outside_99_share": round(len(outside) / len(posed), 4) if posed else None,
        "confident_wrong": len(wrong),
    }
    for name, q in (("median_m", 50), ("p90_m", 90), ("p99_m", 99)):
        figures[name] = round(float(np.percentile(errors, q)), 4) if posed else None
    return figures


def main() -> int:
    """Replay and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("outs", type=Path, nargs="+", help="eval_unseen_rooms --record outputs")
    parser.add_argument("--workers", type=int, default=2, help="processes (one core each)")
    parser.add_argument("--json", type=Path, help="write every replay's row here")
    add_set_option(parser, "override a localize.filter key of every recording (VALUE: YAML)")
    args = parser.parse_args()
    overrides = parse_sets(args.set)
    for folder in args.outs:
        if not (folder / "unseen_rooms.json").is_file():
            raise SystemExit(f"{folder}: not an eval_unseen_rooms output (no unseen_rooms.json)")
    todo = jobs(args.outs)
    if not todo:
        raise SystemExit("no recorded localizations (run eval_unseen_rooms.py with --record)")
    with Pool(max(1, args.workers)) as pool:
        rows = pool.map(partial(replay_one, overrides=overrides), todo, chunksize=4)
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1), encoding="utf-8")
    print(json.dumps(summarize(rows)))
    for r in rows:
        if "error_m" in r and r["mahalanobis2"] > CHI2_2DOF_99:
            print(f"  outside: {r['room']} {r['index']}: {r['error_m']:.3f} m", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
