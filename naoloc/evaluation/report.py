"""The markdown report of an evaluation: tables laid out like the paper's Tables 1-3 with the
paper's own figures in the next column, then the comparisons and the robustness sweeps.

Everything is rendered from ``summary.json`` (a plain dict), so a report can be rebuilt
from a finished run without re-running it.
"""

from __future__ import annotations

import math
import os
import platform
from collections.abc import Sequence
from typing import Any

from naoloc.evaluation.protocols import PAPER_HEADING_JITTER_RAD, PAPER_TABLE1, PAPER_TABLE2


def machine() -> dict[str, Any]:
    """The machine a run is measured on: CPU model, cores, OS, Python."""
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "os": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
    }


def _f(value: Any, digits: int = 2) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def _xy(pair: Sequence[float] | None, digits: int = 2) -> str:
    if pair is None or not all(math.isfinite(v) for v in pair[:2]):
        return "(none)"  # no estimate: a miss
    return f"({pair[0]:.{digits}f}, {pair[1]:.{digits}f})"


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A markdown table from a header and rows of cells (converted with ``str``)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def table1(summary: dict[str, Any]) -> str:
    """Table 1: images per lap and per wall, ours then the paper's."""
    paper = {lap: (images, walls) for lap, images, walls in PAPER_TABLE1}
    rows = []
    for row in summary["survey"]["laps"]:
        p_images, p_walls = paper.get(row["lap"], (None, (None,) * 4))
        cells = [row["lap"], row["images"]]
        for ours, theirs in zip(row["walls"], p_walls, strict=True):
            cells.append(f"{ours} ({_f(theirs)})")
        cells.insert(2, _f(p_images))
        rows.append(cells)
    header = ["Lap", "Images", "Paper", "Wall 1 (paper)", "Wall 2", "Wall 3", "Wall 4"]
    return table(header, rows)


def table2(summary: dict[str, Any]) -> str:
    """Table 2: every map built, with the paper's experiment of the same size alongside."""
    paper = {neurons: (t, poses) for _, _, neurons, _, t, poses in PAPER_TABLE2}
    rows = []
    for i, (name, m) in enumerate(summary["maps"].items(), start=1):
        t = m["timings"]
        p_time, p_poses = paper.get(m["neurons"], (None, None))
        same_size = m["neurons"] == m["epochs"] and m["features"] == "akaze" and "/" not in name
        rows.append(
            [
                i,
                name,
                m["images"],
                m["neurons"],
                m["epochs"],
                _f(t.get("gcs_s")),
                _f(t.get("total_s")),
                _f(p_time, 3) if same_size else "-",
                m["distinct_poses"],
                _f(p_poses) if same_size else "-",
            ]
        )
    header = [
        "Exp.", "Map", "Training", "Neurons", "Epochs", "GCS time (s)", "Total build (s)",
        "Paper time (s)", "Distinct poses", "Paper poses",
    ]  # fmt: skip
    return table(header, rows)


def table3(summary: dict[str, Any], mode: str) -> str:
    """Table 3 for the paper protocol: the paper's layout (maps 1, 1, 2, 3) in ``mode``."""
    rows = []
    for row in summary["table3"]:
        ours = row["ours"].get(f"map{row['paper_map']}-{mode}")
        if ours is None:
            continue
        ests = [_xy(e) for e in ours["estimates"]]
        paper = " ".join(_xy(e, 1) for e in row["paper_estimates"])
        rows.append(
            [row["number"], row["paper_map"], _xy(row["truth"], 1), *ests,
             _f(ours["mean_error_m"]), paper, _f(row["paper_mean_error_m"])]
        )  # fmt: skip
    n = max((len(r) - 6 for r in rows), default=5)
    header = ["N°", "Map", "(x, y) m", *[str(i) for i in range(1, n + 1)], "Mean error (m)",
              "Paper 1-5", "Paper mean error (m)"]  # fmt: skip
    return table(header, rows)


def table3_all_maps(summary: dict[str, Any]) -> str:
    """Mean error at each Table 3 position with every map (columns) in both modes."""
    names = [v for v in summary["variants"] if v.startswith("map")]
    rows = []
    for row in summary["table3"]:
        cells: list[Any] = [row["number"], _xy(row["truth"], 1)]
        for name in names:
            ours = row["ours"].get(name)
            cells.append(
                "-" if ours is None else f"{_f(ours['mean_error_m'])} / {_f(ours['max_error_m'])}"
            )
        cells.append(_f(row["paper_mean_error_m"]))
        rows.append(cells)
    return table(["N°", "(x, y) m", *names, "Paper (its map)"], rows)


def variants_table(summary: dict[str, Any], studies: Sequence[str]) -> str:
    """Median, p90, max error and more for the variants of the given studies."""
    rows = []
    for name, v in summary["variants"].items():
        if v["study"] not in studies:
            continue
        what = v["description"] + (f" (skipped: {v['skipped']})" if "skipped" in v else "")
        rows.append(
            [
                name,
                what,
                v["n"],
                _f(v["median_error_m"]),
                _f(v["p90_error_m"]),
                _f(v["max_error_m"]),
                _f(v["within_0_3m"]),
                _f(v["median_heading_error_deg"], 1),
                _f(v["localize_ms_median"], 0),
            ]
        )
    header = ["Variant", "What", "n", "Median (m)", "p90 (m)", "Max (m)", "<= 0.3 m",
              "Heading med. (deg)", "ms/estimate"]  # fmt: skip
    return table(header, rows)


def positions_table(summary: dict[str, Any]) -> str:
    """One row per test position of the main variant (map frame)."""
    rows = []
    for row in summary["positions"]:
        est = " ".join(_xy(e) for e in row["estimates"])
        rows.append([row["group"], _xy(row["truth"]), est, _f(row["mean_error_m"])])
    return table(["#", "Truth (x, y) m", "Estimates", "Mean error (m)"], rows)


def render(summary: dict[str, Any]) -> str:
    """The whole markdown report of a run."""
    proto = summary["protocol"]
    main = summary["variants"][summary["main_variant"]]
    mach = summary["machine"]
    cfg = summary["config"]
    out = [
        f"# naoloc evaluation: {proto} protocol",
        "",
        f"Room {summary['room_size_m'][0]:g} x {summary['room_size_m'][1]:g} m, room seed "
        f"{summary['room_seed']}, backend {summary['backend']}; pose seed {summary['seed']}; "
        f"{summary['workers']} workers; {summary['wall_s']} s wall time. Machine: {mach['cpu']}, "
        f"{mach['cores']} cores, {mach['os']}, Python {mach['python']}.",
        "",
        f"Main result ({main['description']}): **median {_f(summary['median_error_m'])} m, "
        f"90th percentile {_f(summary['p90_error_m'])} m, max {_f(summary['max_error_m'])} m**, "
        f"median heading error {_f(summary['median_heading_error_deg'], 1)} deg over "
        f"{summary['n']} estimates; map built in {_f(summary['map_build_s'])} s; "
        f"{_f(summary['localize_ms_median'], 0)} ms per estimate (pictures and map).",
        "",
        "Frames: map frame = odometry at the survey start (x forward, y left); truth is the "
        "simulator's pose converted into it. Errors are Euclidean distances in metres.",
        "",
        "## Table 1: survey (ours, paper in brackets)",
        "",
        f"{summary['survey']['frames']} images over {summary['survey']['path_m']:.1f} m of "
        f"odometry path; survey step {cfg['survey']['step_m']} m, {cfg['survey']['laps']} laps. "
        "Walls are numbered counter-clockwise from the one on the robot's right at the start; "
        "an image counts for the wall its optical axis hits.",
        "",
        table1(summary),
        "",
        "## Table 2: maps (paper's figures for the same neurons/epochs alongside)",
        "",
        table2(summary),
        "",
    ]
    if proto == "paper":
        jitter = round(PAPER_HEADING_JITTER_RAD * 180 / 3.141592653589793)
        out += [
            "## Table 3: localization at the paper's positions",
            "",
            "Headings (ours; the paper gives none): the survey's direction along the nearest "
            f"side of the circuit; the five evaluations differ by a seeded heading perturbation "
            f"of up to +-{jitter} deg. Each evaluation takes its own pictures.",
            "",
            "### The paper's layout (maps 1, 1, 2, 3), paper mode",
            "",
            table3(summary, "paper"),
            "",
            "### The paper's layout, verified mode",
            "",
            table3(summary, "verified"),
            "",
            "### Every map in both modes: mean / max error (m)",
            "",
            table3_all_maps(summary),
            "",
        ]
    out += ["## Main variant", "", variants_table(summary, ("main", "paper")), ""]
    if any(v["study"] == "compare" for v in summary["variants"].values()):
        out += [
            "## Comparisons on the same survey data",
            "",
            "Same survey, same test poses; variants with the same strategy re-score the very "
            "same pictures (scan: the localize scan's pictures; paper: nearest wall, 2 "
            "pictures). ms/estimate of re-scored variants counts the map's work only. "
            "Re-scored scans get the floor step with the floor-wall lines the localization "
            "measured at the pose (they do not depend on the map), as their own "
            "localization's last floor step would have; the scan cannot turn in place "
            "again for them.",
            "",
            variants_table(summary, ("compare",)),
            "",
        ]
    if any(v["study"] == "robustness" for v in summary["variants"].values()):
        out += [
            "## Robustness",
            "",
            "Drift levels re-survey and re-map, then re-score the main variant's pictures "
            "(and its floor lines) with their own map; the others localize with the base "
            "map in a robot changed after mapping.",
            "",
            variants_table(summary, ("robustness",)),
            "",
            "![robustness CDF](cdf_robustness.png)",
            "",
        ]
    out += [
        "## Figures",
        "",
        "![map](map.png)",
        "",
        "![estimates vs truth](estimates.png)",
        "",
        "![error CDF](cdf.png)",
        "",
        "## Test positions (main variant, map frame)",
        "",
        positions_table(summary),
        "",
    ]
    return "\n".join(out)
