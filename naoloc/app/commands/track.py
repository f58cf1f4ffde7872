"""``naoloc track -c CFG -m MAP.npz [--to X Y] [--duration S]``: the live pose, one JSON line
per camera frame, while the robot walks (or stands)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

from naoloc.config import Config


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """A short look, then a pose per frame while walking to ``--to`` (map frame)."""
    from naoloc.app.commands.localize import in_the_map, recorder, run_outputs
    from naoloc.behaviours.track import TrackPoint, track
    from naoloc.errors import NoEstimate
    from naoloc.geometry import Pose2D
    from naoloc.viz.live import follow_track

    route = [Pose2D(float(args.to[0]), float(args.to[1]))] if args.to is not None else []

    def check(vmap: Any) -> None:
        """Refuse, before connecting, a --to the map does not know as free floor."""
        from naoloc.errors import ConfigError
        from naoloc.navigation.grid import grid_of_map

        for goal in route:
            free = grid_of_map(vmap).free_test(clearance=False)
            if not free(np.array([goal.x]), np.array([goal.y]))[0]:
                raise ConfigError(
                    f"--to ({goal.x:g}, {goal.y:g}) is not on the map's free floor (map frame, "
                    "m: from the survey's start); the robot did not move"
                )

    with (
        in_the_map(args, cfg, check) as (robot, live, vmap),
        recorder(args, cfg, vmap, "track") as rec,
    ):
        shown = follow_track(live)

        def emit(point: TrackPoint) -> None:
            shown(point)
            print(json.dumps(point.to_json()), flush=True)

        result = track(
            robot, vmap, cfg, route=route, duration_s=args.duration, on_point=emit,
            localizer=rec,
        )  # fmt: skip
    points = result.points
    found = [p for p in points if p.estimate.found]
    span = points[-1].t - points[0].t if len(points) > 1 else 0.0
    summary: dict[str, Any] = {
        "poses": len(points),
        "tracking": len(found),
        "rate_hz": round((len(points) - 1) / span, 2) if span > 0 else None,
        "cpu_ms_median": round(1e3 * sorted(p.cpu_s for p in points)[len(points) // 2], 2)
        if points
        else None,
        "walked_m": round(result.walked_m, 3),
    }
    summary.update(run_outputs(args, vmap))
    errors = [e for p in found if (e := p.error_m) is not None]
    if errors:
        summary["median_error_m"] = round(sorted(errors)[len(errors) // 2], 4)
    if result.reason:
        summary["reason"] = result.reason
    print(
        f"track: {len(points)} poses ({len(found)} tracking) at {summary['rate_hz']} Hz, "
        f"{result.walked_m:.2f} m walked",
        file=sys.stderr,
    )
    if not result.first.estimate.found:
        raise NoEstimate(f"no estimate to track from: {result.first.estimate.reason}", summary)
    return summary
