"""``naoloc evaluate``: measure localization error with the paper or random protocol.

Surveys the simulated room, builds the maps, localizes at the protocol's test poses over
a process pool (or a Ray cluster: ``--executor ray [--ray-address ADDR]``), and writes
summary.json, report.md and PNGs into OUTDIR. The JSON line has protocol, n,
median_error_m, p90_error_m, max_error_m, median_heading_error_deg, map_build_s,
localize_ms_median (docs/cli.md).
"""

from __future__ import annotations

import argparse
from typing import Any

from naoloc.config import Config
from naoloc.evaluation.pipeline import check_simulated, evaluate, parse_studies
from naoloc.evaluation.runner import make_executor


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Run ``naoloc evaluate`` from parsed arguments.

    Args:
        args: ``protocol``, ``n``, ``seed``, ``workers``, ``output`` and optionally
            ``studies``, ``executor`` (local | ray) and ``ray_address``.
        cfg: The resolved config; its robot must be simulated.

    Returns:
        The JSON line.

    Raises:
        BackendError: The config's robot is not simulated.
        ConfigError: Bad protocol, study or -n.
        DependencyNotInstalled: ``--executor ray`` without Ray.
    """
    check_simulated(cfg)
    studies = parse_studies(getattr(args, "studies", None))
    name = getattr(args, "executor", None) or "local"
    executor = make_executor(name, getattr(args, "ray_address", None), args.workers)
    try:
        result = evaluate(
            cfg,
            args.protocol,
            int(args.n),
            int(args.seed),
            args.output,
            workers=args.workers,
            studies=studies,
            executor=executor,
            record=bool(getattr(args, "record", False)),
        )
    finally:
        executor.close()
    result["executor"] = name
    print(
        f"{result['protocol']} protocol: median {result['median_error_m']} m, "
        f"p90 {result['p90_error_m']} m over {result['n']} estimates; report {result['report']}"
    )
    return result
