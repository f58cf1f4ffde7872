"""``naoloc replay FILE.mcap -m MAP.npz [-c CFG]``: re-run a recorded localization.

Reads a recording of ``localize``, ``track`` or ``go-home`` (``--record``), gives its
observations in order to a new filter over ``MAP.npz`` (the recording's own config's
``localize.filter``, or ``-c``'s) and prints the estimate, with the recorded one and
whether they are the same. No robot is involved. Exit 3 when the replay has no pose.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from naoloc.config import Config


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Replay the recording's observations into a new filter and compare the estimates."""
    from naoloc.config import load_config
    from naoloc.data.recording import estimate_json, read_recording
    from naoloc.errors import NoEstimate
    from naoloc.localization import replay
    from naoloc.localization.observations import Picture
    from naoloc.mapping import load_map

    recording = read_recording(args.recording)
    vmap = load_map(args.map)
    tuning_cfg = load_config(args.config if args.config is not None else recording.config)
    loc = replay(vmap, recording.observations, tuning_cfg.localize.filter, recording.seed)
    est = loc.pose()
    got = estimate_json(est)
    recorded = recording.estimate
    same = recorded is not None and _same(got, recorded)
    pictures = sum(isinstance(o, Picture) for o in recording.observations)
    summary: dict[str, Any] = {
        "recording": str(args.recording),
        "verb": recording.meta.get("recording"),
        "complete": bool(recording.meta.get("complete")),
        "observations": len(recording.observations),
        "pictures": pictures,
        **{k: got.get(k) for k in ("x", "y", "theta", "confidence", "status")},
        "covariance": got.get("covariance"),
        "recorded": recorded,
        "same": same,
        "compute_s": round(loc.cpu_s, 3),
    }
    if est.found:
        print(
            f"replay: ({est.x:.2f}, {est.y:.2f}, {est.theta:.2f}) in the map frame from "
            f"{len(recording.observations)} observations ({pictures} pictures); "
            f"{'the same as' if same else 'NOT the same as'} recorded"
        )
    else:
        print(f"replay: no estimate ({est.reason}); {'the same' if same else 'not'} as recorded")
        raise NoEstimate(f"no estimate: {est.reason}", summary)
    return summary


def _same(got: dict[str, Any], recorded: dict[str, Any]) -> bool:
    """Equal estimates: the same status and, with a pose, the same numbers (1e-9)."""
    if got.get("status") != recorded.get("status"):
        return False
    for key in ("x", "y", "theta", "confidence"):
        a, b = got.get(key), recorded.get(key)
        if (a is None) != (b is None):
            return False
        if a is not None and b is not None and not math.isclose(a, b, abs_tol=1e-9):
            return False
    return True
