"""Error statistics, the markdown report and the figures, from synthetic results."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from naoloc.config import load_config
from naoloc.errors import ConfigError
from naoloc.evaluation import figures, report
from naoloc.evaluation.pipeline import parse_studies
from naoloc.evaluation.plan import make_plan
from naoloc.evaluation.stats import (
    cdf,
    group_rows,
    heading_errors,
    percentile,
    position_errors,
    summarize,
)


def test_summary_figures_match_numpy() -> None:
    rng = np.random.default_rng(0)
    err = rng.exponential(0.3, size=101)
    s = summarize(err, np.full(101, math.radians(4.0)))
    assert s.n == 101
    assert s.median_m == pytest.approx(np.median(err))
    assert s.p90_m == pytest.approx(np.percentile(err, 90))
    for q in (0, 33, 50, 90, 100):
        assert percentile(err, q) == pytest.approx(np.percentile(err, q))
    assert s.max_m == pytest.approx(err.max())
    assert s.median_heading_deg == pytest.approx(4.0)
    assert s.within_0_3m == pytest.approx(np.mean(err <= 0.3))


def test_missing_estimates_count_as_failures() -> None:
    s = summarize([0.1, 0.1, float("nan"), float("nan")])
    assert math.isinf(s.max_m) and math.isinf(s.p90_m)
    assert s.median_m == math.inf  # half the estimates failed
    assert s.mean_m == pytest.approx(0.1)
    assert summarize([]).n == 0


def test_errors_and_cdf() -> None:
    truth = np.array([[0.0, 0.0], [1.0, 1.0]])
    est = np.array([[3.0, 4.0], [1.0, 1.0]])
    assert position_errors(truth, est).tolist() == [5.0, 0.0]
    h = heading_errors(np.array([3.0]), np.array([-3.0]))
    assert h[0] == pytest.approx(2 * math.pi - 6.0)
    x, y = cdf([0.3, 0.1, float("nan"), 0.2])
    assert x.tolist() == [0.1, 0.2, 0.3]
    assert y.tolist() == [0.25, 0.5, 0.75]  # the NaN is never "within" any error


def test_group_rows_means_per_position() -> None:
    recs = [
        {"group": 1, "truth": [1, 2, 0], "estimate": [1.1, 2, 0], "error_m": 0.1},
        {"group": 2, "truth": [0, 0, 0], "estimate": [0, 0.5, 0], "error_m": 0.5},
        {"group": 1, "truth": [1, 2, 0], "estimate": [1.3, 2, 0], "error_m": 0.3},
    ]
    rows = group_rows(recs)
    assert [r["group"] for r in rows] == [1, 2]
    assert rows[0]["truth"] == [1.0, 2.0]
    assert rows[0]["estimates"] == [[1.1, 2.0], [1.3, 2.0]]
    assert rows[0]["mean_error_m"] == pytest.approx(0.2)


def test_parse_studies() -> None:
    assert parse_studies("none") == ("main",)
    assert parse_studies("all") == ("main", "compare", "robustness")
    assert parse_studies("robustness,compare") == ("main", "compare", "robustness")
    with pytest.raises(ConfigError, match="unknown study"):
        parse_studies("bogus")


def test_plans_name_every_variant_once() -> None:
    cfg = load_config({"map": {"neurons": 300, "epochs": 300}})
    plan = make_plan(cfg, "paper", ("main", "compare", "robustness"))
    names = [v.name for v in plan.variants]
    assert len(names) == len(set(names))
    assert plan.main.name == "main" and plan.main.mode == "verified"
    assert {"map1-paper", "map3-verified", "nearest-image", "features-sift"} <= set(names)
    assert {"akaze-100", "akaze-200", "akaze-300", "orb-300", "sift-300"} <= set(plan.maps)
    assert "drift-x4" in plan.surveys and "light-0.5" in plan.robots
    for v in plan.variants:
        assert v.map_name in plan.maps
        assert v.strategy == ("scan" if v.mode == "verified" else "paper")
    # A drift survey's odometry is scaled from the config's own.
    odo = cfg.with_overrides(plan.surveys["drift-x4"]).world.odometry
    assert odo.level == pytest.approx(4 * cfg.world.odometry.level)
    assert make_plan(cfg, "random", ("main",)).variants == plan.variants[:1]


def _summary() -> dict:
    variants = {
        "main": {"study": "main", "description": "default", "n": 2, "median_error_m": 0.12,
                 "p90_error_m": 0.2, "max_error_m": 0.21, "within_0_3m": 1.0,
                 "median_heading_error_deg": 2.0, "localize_ms_median": 900.0},
        "map1-paper": {"study": "paper", "description": "map 1", "n": 2, "median_error_m": 1.0,
                       "p90_error_m": 1.5, "max_error_m": 1.6, "within_0_3m": 0.0,
                       "median_heading_error_deg": 30.0, "localize_ms_median": 50.0},
    }  # fmt: skip
    return {
        "protocol": "paper", "n": 2, "median_error_m": 0.12, "p90_error_m": 0.2,
        "max_error_m": 0.21, "median_heading_error_deg": 2.0, "map_build_s": 3.5,
        "localize_ms_median": 900.0, "seed": 1, "workers": 2, "wall_s": 12.0,
        "main_variant": "main", "room_size_m": [6.0, 6.0], "room_seed": 0, "backend": "fake",
        "machine": report.machine(),
        "config": {"survey": {"step_m": 0.2, "laps": 2}},
        "survey": {"frames": 160, "path_m": 32.0, "laps": [
            {"lap": 1, "images": 80, "walls": [20, 20, 20, 20]},
            {"lap": 2, "images": 80, "walls": [19, 21, 20, 20]}]},
        "maps": {"akaze-100": {"images": 160, "neurons": 100, "epochs": 100, "features": "akaze",
                               "distinct_poses": 80, "timings": {"gcs_s": 1.0, "total_s": 3.5}}},
        "variants": variants,
        "positions": [{"group": 1, "truth": [3.5, 0.5], "estimates": [[3.6, 0.5], [3.4, 0.6]],
                       "mean_error_m": 0.12}],
        "table3": [{"number": 1, "paper_map": 1, "truth": [3.5, 0.5], "heading_deg": 0.0,
                    "paper_estimates": [[3.7, 1.7]] * 5, "paper_mean_error_m": 1.2166,
                    "ours": {"map1-paper": {"estimates": [[3.6, 1.0], [3.5, 1.5]],
                                            "mean_error_m": 0.75, "max_error_m": 1.0}}}],
    }  # fmt: skip


def test_report_lays_tables_out_like_the_paper() -> None:
    text = report.render(_summary())
    assert "## Table 1" in text and "| 1 | 80 | 89 | 20 (20)" in text
    assert "## Table 2" in text and "4.063" in text and "| 72 |" in text
    assert "## Table 3" in text
    row = next(line for line in text.splitlines() if line.startswith("| 1 | 1 | (3.5, 0.5)"))
    assert "(3.60, 1.00)" in row and "0.75" in row and "1.22" in row and "(3.7, 1.7)" in row
    assert "median 0.12 m" in text and "![map](map.png)" in text
    json.dumps(_summary())  # the summary the report reads is JSON


def test_figures_write_pngs(tmp_path: Path) -> None:
    kf = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 1.5]], dtype=float)
    neurons = np.array([[0.1, 0, 0], [np.nan, np.nan, np.nan], [1, 0.9, 1]])
    poly = np.array([[-1, -1], [5, -1], [5, 5], [-1, 5]], dtype=float)
    recs = [
        {"truth": [0, 0, 0], "estimate": [0.2, 0.1, 0]},
        {"truth": [1, 1, 0], "estimate": [1, 1.4, 0]},
    ]
    paths = [
        figures.plot_maps(tmp_path / "m.png", [("a", kf, neurons), ("b", kf, neurons)], poly),
        figures.plot_estimates(tmp_path / "e.png", recs, "t", poly, kf),
        figures.plot_cdf(tmp_path / "c.png", {"a": [0.1, 0.5, float("nan")], "b": []}, "t"),
    ]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert p.stat().st_size > 5000
