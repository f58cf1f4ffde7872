"""``naoloc localize -c CFG -m MAP.npz [--at X Y THETA] [--png P]``: where am I in the map?"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from naoloc.config import Config
from naoloc.errors import BackendError, ConfigError, NoEstimate
from naoloc.robot import Robot


def teleport_if_asked(robot: Robot, at: list[float] | None) -> None:
    """Put a simulated robot at ``at`` = [x, y, theta] (room frame); nothing when None.

    Raises:
        BackendError: ``--at`` on a robot without a simulator.
    """
    if at is None:
        return
    if robot.sim is None:
        raise BackendError(f"--at needs a simulator; backend {robot.backend!r} has none")
    x, y, theta = (float(v) for v in at)
    robot.sim.teleport(x, y, theta)


def at_in_both_frames(at: list[float] | None, meta: dict[str, Any]) -> dict[str, Any] | None:
    """``--at`` echoed in the room frame (as given) and in the map frame (through the map's
    ``origin_room_pose``: null when the map does not know where its origin stood).

    Returns:
        ``{"room": [x, y, theta], "map": [x, y, theta] | None}``, or None without ``--at``.
    """
    if at is None:
        return None
    from naoloc.geometry import Pose2D, relative_pose

    room = Pose2D(*(float(v) for v in at))
    origin = meta.get("origin_room_pose")
    in_map = None
    if origin is not None:
        in_map = relative_pose(Pose2D.from_list(origin), room).normalized()
    return {
        "room": [round(v, 4) for v in room],
        "map": None if in_map is None else [round(v, 4) for v in in_map],
    }


@contextmanager
def recorder(args: argparse.Namespace, cfg: Config, vmap: Any, verb: str) -> Iterator[Any]:
    """``--record FILE.mcap``: a filter whose every observation is written there as it is
    made (None without ``--record``). A run that fails keeps ``FILE.partial.mcap``.

    Yields:
        A :class:`naoloc.data.recording.RecordedLocalizer`, or None.

    Raises:
        ConfigError: ``--record`` with ``localize.mode: paper`` (it does not use the filter).
    """
    path: Path | None = getattr(args, "record", None)
    if path is None:
        if getattr(args, "format", "naoloc") != "naoloc":
            raise ConfigError("--format ros2 converts a recording: give --record FILE.mcap")
        yield None
        return
    if cfg.localize.mode == "paper":
        raise ConfigError("--record records the filter's observations; localize.mode paper "
                          "does not use the filter")  # fmt: skip
    from naoloc.data.recording import recorded_localizer

    with recorded_localizer(path, cfg, verb, args.map, vmap) as loc:
        yield loc


def run_outputs(args: argparse.Namespace, vmap: Any) -> dict[str, Any]:
    """What a verb on a map adds to its JSON line: the recording (``--record``, and its ROS 2
    copy with ``--format ros2``) and the start in both frames (``--at``)."""
    from naoloc.app.commands.survey import ros2_copy

    out: dict[str, Any] = {}
    if args.record is not None:
        out["record"] = str(args.record)
        ros2 = ros2_copy(args, args.record)
        if ros2 is not None:
            out["ros2"] = str(ros2)
    if args.at is not None:
        out["at"] = at_in_both_frames(args.at, vmap.meta)
    return out


@contextmanager
def in_the_map(
    args: argparse.Namespace, cfg: Config, check: Callable[[Any], None] | None = None
) -> Iterator[tuple[Robot, Any, Any]]:
    """What the verbs on a map share: the map (``-m``), an interruptible run, the live view
    (``--live``) and the connected robot (moved to ``--at`` on a simulator), the map shown.

    Args:
        args: The verb's arguments.
        cfg: The config.
        check: Called with the map before connecting (a verb's own checks: nothing has
            moved yet when it raises).

    Yields:
        The robot (watched by the live view), the live view and the map.
    """
    from naoloc.app.interrupt import interruptible
    from naoloc.mapping import load_map
    from naoloc.robot.registry import connect
    from naoloc.viz.live import live_from_args, show_map, watch

    vmap = load_map(args.map)
    if check is not None:
        check(vmap)
    with interruptible(), live_from_args(args) as live, connect(cfg) as robot:
        teleport_if_asked(robot, args.at)
        show_map(live, vmap)
        yield watch(robot, live), live, vmap


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Localize once (head scan, or the paper's 1-2 pictures in mode paper) and report."""
    from naoloc.behaviours.localize import localize
    from naoloc.data.outputs import config_path_for, staged
    from naoloc.mapping.checks import map_checked
    from naoloc.viz.live import show_estimate
    from naoloc.viz.plots import furniture_footprints, plot_localization
    from naoloc.viz.progress import Progress

    png: Path | None = args.png
    with in_the_map(args, cfg) as (robot, live, vmap), recorder(args, cfg, vmap, "localize") as rec:
        with Progress(None, "localize") as bar:
            loc = localize(robot, vmap, cfg, on_step=bar.note, localizer=rec)
        show_estimate(live, loc.estimate)
    summary = loc.summary()
    summary.update(run_outputs(args, vmap))
    summary["map_checked"] = map_checked(vmap)
    if not summary["map_checked"]:
        print("localize: this map failed build-map's checks (kept with --keep-unchecked): "
              "its poses may be off", file=sys.stderr)  # fmt: skip
    est = loc.estimate
    if est.found:
        line = (
            f"localize: ({est.x:.2f}, {est.y:.2f}, {est.theta:.2f}) in the map frame, "
            f"confidence {est.confidence:.2f}, {len(loc.queries)} images ({loc.strategy})"
        )
        if loc.error_m is not None:
            line += f"; error {loc.error_m:.2f} m, {loc.heading_error_deg:.1f} deg"
    else:
        line = f"localize: no estimate ({est.reason}) from {len(loc.queries)} images"
    print(line)
    if png is not None:  # the picture and its config copy appear together, or not at all
        with staged(png, config_path_for(png)) as (tmp_png, tmp_cfg):
            furniture = furniture_footprints(cfg, vmap.meta.get("origin_room_pose"))
            plot_localization(
                vmap, est, tmp_png, truth=loc.truth, queries=loc.queries, furniture=furniture
            )  # fmt: skip
            tmp_cfg.write_text(cfg.to_yaml(), encoding="utf-8")
        summary["png"] = str(png)
        print(f"localize: picture -> {png}")
    summary["localize_s"] = round(loc.wall_s, 3)
    if not est.found:
        raise NoEstimate(f"no estimate: {est.reason} in {len(loc.queries)} images", summary)
    return summary
