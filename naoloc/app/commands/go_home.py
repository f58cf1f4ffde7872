"""``naoloc go-home -c CFG -m MAP.npz [--at X Y THETA] [--png P]``: walk back to the map origin."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from naoloc.config import Config


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Localize, walk to the origin, repeat (``go_home`` config); report where it ended."""
    from naoloc.app.commands.localize import teleport_if_asked
    from naoloc.app.interrupt import interruptible
    from naoloc.behaviours.go_home import go_home
    from naoloc.behaviours.localize import Localization
    from naoloc.data.outputs import config_path_for, staged
    from naoloc.mapping import load_map
    from naoloc.robot.registry import connect
    from naoloc.viz.live import follow_rounds, live_from_args, show_map, watch
    from naoloc.viz.plots import plot_go_home
    from naoloc.viz.progress import Progress

    vmap = load_map(args.map)
    png: Path | None = args.png

    def report(tries: int, loc: Localization) -> None:
        est = loc.estimate
        bar.update(1, f"walk {tries}")
        if not est.found:
            print(f"go-home: after {tries} walks: nothing recognised")
            return
        extra = "" if loc.error_m is None else f", error {loc.error_m:.2f} m"
        print(
            f"go-home: after {tries} walks: estimate ({est.x:.2f}, {est.y:.2f}, "
            f"{est.theta:.2f}), {math.hypot(est.x, est.y):.2f} m from home{extra}"
        )

    bar = Progress(cfg.go_home.max_tries + 1, "go-home")
    with interruptible(), live_from_args(args) as live, connect(cfg) as robot, bar:
        teleport_if_asked(robot, args.at)
        show_map(live, vmap)
        result = go_home(watch(robot, live), vmap, cfg, on_round=follow_rounds(live, report))
    summary = result.summary()
    verdict = "reached home after" if result.reached else "gave up after"
    line = f"go-home: {verdict} {result.tries} walks, {result.path_m:.2f} m walked"
    if result.reason:
        line += f" ({result.reason})"
    if result.error_m is not None:
        line += f"; truly {result.error_m:.2f} m from the origin"
    print(line)
    if png is not None:
        with staged(png, config_path_for(png)) as (tmp_png, tmp_cfg):
            plot_go_home(
                vmap, result.trail, [r.estimate for r in result.rounds], tmp_png,
                blocked=result.blocked_at, truth=result.truth, reached=result.reached,
            )  # fmt: skip
            tmp_cfg.write_text(cfg.to_yaml(), encoding="utf-8")
        summary["png"] = str(png)
    return summary
