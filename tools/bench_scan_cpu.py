"""CPU time of whole localizations in the simulator, split by stage, on one core.

Usage::

    naoloc evaluate --protocol anywhere -n 20 -o /tmp/ev913     # or tools/eval_unseen_rooms.py
    python tools/bench_scan_cpu.py /tmp/ev913 [-n 8] [--early-floor off] [--json ROWS.json]
    PYTHONPATH=/path/to/an/older/checkout python tools/bench_scan_cpu.py /tmp/ev913

Runs the localize behaviour (scan strategy, the config's floor step) at the first ``-n``
test poses of a ``naoloc evaluate`` output folder (its config.yaml, map and
estimates.json), with OpenCV on one thread, and prints per localization the pictures it
took, its estimate and the CPU milliseconds of each stage of the map's work: feature
extraction, the localizer (every call: after each sweep, and the last sweep's heading),
floor-line detection, and the floor step's votes. The stages are timed by wrapping the
functions from outside, so the same script measures any commit's code (``PYTHONPATH``):
compare two commits' figures on the same folder, and their estimates, which should agree
where only speed changed. Taking pictures, moving the head and turning are not counted.
The error against the simulator's truth is printed too (median, p90, share within 0.3 m),
so a change of behaviour (``--early-floor off``: the floor lines only after the last
sweep) is measured on the same map and poses.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from naoloc.config import load_config  # noqa: E402
from naoloc.errors import NaolocError  # noqa: E402
from naoloc.mapping import load_map  # noqa: E402
from naoloc.mapping.map import VisualMap  # noqa: E402
from naoloc.robot.registry import connect  # noqa: E402

STAGES = ("extract", "localize", "detect", "vote")


class _Timers:
    """CPU seconds per name, of calls to the functions :meth:`wrap` replaced."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def wrap(self, name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[name] = self.seconds.get(name, 0.0) + time.process_time() - t0

        return timed

    def stages_ms(self) -> dict[str, float]:
        """The stages (ms): the floor step's votes are its time less the lines' capture
        and detection (``measure``), detection counted on its own."""
        s = self.seconds
        out = {k: 1e3 * s.get(k, 0.0) for k in ("extract", "localize", "detect")}
        out["vote"] = 1e3 * (s.get("floorfix", 0.0) - s.get("measure", 0.0))
        return out


def _install(timers: _Timers) -> Any:
    """Wrap the stages' functions; returns the localize behaviour's module."""
    loc: Any = importlib.import_module("naoloc.behaviours.localize")
    follow: Any = importlib.import_module("naoloc.behaviours.wall_follow")
    VisualMap.extract = timers.wrap("extract", VisualMap.extract)  # type: ignore[method-assign]
    VisualMap.localize_features = timers.wrap(  # type: ignore[method-assign]
        "localize", VisualMap.localize_features
    )
    follow.detect_wall_lines = timers.wrap("detect", follow.detect_wall_lines)
    loc.measure_floor_lines = timers.wrap("measure", loc.measure_floor_lines)
    loc._floor_fix = timers.wrap("floorfix", loc._floor_fix)
    return loc


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outdir", type=Path, help="a naoloc evaluate output folder")
    parser.add_argument("-n", type=int, default=8, help="test poses (the first n)")
    parser.add_argument(
        "--early-floor",
        choices=("on", "off"),
        default=None,
        help="the floor lines may settle a first sweep before the scan turns (default: the "
        "code's own behaviour; not given to commits before the option existed)",
    )
    parser.add_argument("--json", type=Path, default=None, help="write the rows here too")
    args = parser.parse_args(argv)
    cv2.setNumThreads(1)
    try:
        cfg = load_config(args.outdir / "config.yaml")
        maps = sorted((args.outdir / "maps").glob("*.npz"))
        if not maps:
            raise NaolocError(f"{args.outdir / 'maps'} has no map")
        vmap = load_map(maps[0])
        records = json.loads((args.outdir / "estimates.json").read_text(encoding="utf-8"))
    except (NaolocError, OSError, ValueError) as err:
        print(f"bench_scan_cpu: {err}", file=sys.stderr)
        return 2
    poses = [r["room_pose"] for r in records if "room_pose" in r][: args.n]
    timers = _Timers()
    loc = _install(timers)
    rows: list[dict[str, float]] = []
    errors: list[float] = []  # m; inf where nothing was recognised
    kwargs: dict[str, Any] = {}
    if args.early_floor is not None:
        kwargs["early_floor"] = args.early_floor == "on"
    with connect(cfg) as robot:
        if robot.sim is None:
            print("bench_scan_cpu: the config's backend has no simulator", file=sys.stderr)
            return 2
        for pose in poses:
            robot.sim.teleport(*pose)
            timers.seconds.clear()
            result = loc.localize(robot, vmap, cfg, **kwargs)
            ms = timers.stages_ms()
            ms["total"] = sum(ms.values())
            ms["pictures"] = len(result.queries)
            rows.append(ms)
            est = result.estimate
            off = result.error_m
            errors.append(float("inf") if off is None else off)
            print(
                f"{len(result.queries):2d} pictures, estimate ({est.x:.4f}, {est.y:.4f}, "
                f"{est.theta:.4f}) {est.method}, error "
                + ("none" if off is None else f"{off:.3f} m")
                + ": "
                + " ".join(f"{k} {ms[k]:.0f}" for k in (*STAGES, "total"))
                + " ms",
                flush=True,
            )
    for key in (*STAGES, "total"):
        v = [r[key] for r in rows]
        print(f"{key}: median {np.median(v):.0f} ms, largest {np.max(v):.0f} ms")
    e = np.asarray(errors)
    # No estimate counts as the largest error (inf; percentiles of inf would give NaN).
    p90 = float(np.percentile(np.where(np.isfinite(e), e, 1e9), 90))
    p90_text = "none (no estimate)" if p90 >= 1e8 else f"{p90:.3f} m"
    print(
        f"error: median {np.median(e):.3f} m, p90 {p90_text}, "
        f"{100 * np.mean(e < 0.3):.1f} % within 0.3 m, no estimate {int(np.sum(~np.isfinite(e)))}"
        f"; one sweep (7 pictures) {sum(r['pictures'] == 7 for r in rows)} of {len(rows)}"
    )
    if args.json is not None:
        out = [
            {**r, "error_m": float(x) if np.isfinite(x) else None}
            for r, x in zip(rows, e, strict=True)
        ]
        args.json.write_text(json.dumps(out), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
