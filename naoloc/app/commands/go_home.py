"""``naoloc go-home -c CFG -m MAP.npz [--at X Y THETA] [--png P]``: walk back to the map origin."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from naoloc.config import Config


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """A short look, then a walk home on the live pose; report where it ended."""
    from naoloc.app.commands.localize import in_the_map, recorder, run_outputs
    from naoloc.behaviours.go_home import go_home
    from naoloc.data.outputs import config_path_for, staged
    from naoloc.viz.live import follow_track
    from naoloc.viz.plots import furniture_footprints, plot_go_home
    from naoloc.viz.progress import Progress

    png: Path | None = args.png
    with (
        in_the_map(args, cfg) as (robot, live, vmap),
        recorder(args, cfg, vmap, "go-home") as rec,
        Progress(None, "go-home poses") as bar,
    ):
        shown = follow_track(live)

        def on_point(point: Any) -> None:
            shown(point)
            bar.update(1)

        result = go_home(
            robot, vmap, cfg, on_point=on_point, on_step=bar.note, localizer=rec
        )  # fmt: skip
    summary = result.summary()
    summary.update(run_outputs(args, vmap))
    verdict = "reached home" if result.reached else "gave up"
    line = (
        f"go-home: {verdict} in {result.robot_s:.1f} s ({result.looks} looks, "
        f"{result.walked_m:.2f} m walked; the planned {result.path_m:.2f} m take "
        f"{result.walk_s:.1f} s at a NAO's speed)"
    )
    if result.reason:
        line += f": {result.reason}"
    if result.error_m is not None:
        line += f"; truly {result.error_m:.2f} m from the origin"
    print(line)
    if png is not None:
        believed = [p.estimate.pose() for p in result.trail if p.estimate.found]
        with staged(png, config_path_for(png)) as (tmp_png, tmp_cfg):
            plot_go_home(
                vmap, believed, result.stops, tmp_png, truth=result.truth,
                reached=result.reached,
                furniture=furniture_footprints(cfg, vmap.meta.get("origin_room_pose")),
            )  # fmt: skip
            tmp_cfg.write_text(cfg.to_yaml(), encoding="utf-8")
        summary["png"] = str(png)
    return summary
