"""PNG figures of an evaluation: the map (like the paper's Fig. 14), estimates vs truth (like
Fig. 20) and the cumulative distribution of errors.

Everything is drawn in the map frame (m), with the walls and the furniture when known.
Legends sit outside the data. A test pose without an estimate is drawn as a miss (its own
marker, counted in the legend), never as an estimate. Figures come from :mod:`naoloc.viz.plots`
(their own Agg canvas, no pyplot), so importing this module costs nothing and needs no display.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.evaluation.stats import cdf
from naoloc.viz.plots import draw_furniture, legend_outside, new_figure, save_figure

DPI = 110
Furniture = Sequence[tuple[str, np.ndarray]] | None
LOG_SPAN = 10.0  # a CDF's x axis is logarithmic when its errors span more than this ratio


def _finish(ax: Any, title: str, legend_size: int, outside: bool = True) -> None:
    """Title, equal aspect, map-frame axis labels, grid and legend of a map panel."""
    ax.set_title(title, fontsize=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    if outside:
        legend_outside(ax, legend_size)
    else:  # below the panel, so that side-by-side panels keep their width
        ax.legend(
            fontsize=legend_size, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2,
            frameon=False,
        )  # fmt: skip


def _draw_room(ax: Any, room_polygon: np.ndarray | None) -> None:
    if room_polygon is None:
        return
    poly = np.vstack([room_polygon, room_polygon[:1]])
    ax.plot(poly[:, 0], poly[:, 1], color="0.3", lw=1.5, label="walls")


def plot_maps(
    path: Path,
    maps: Sequence[tuple[str, np.ndarray, np.ndarray]],
    room_polygon: np.ndarray | None = None,
    furniture: Furniture = None,
) -> Path:
    """Neuron poses of one or more maps over the survey poses (the paper's Fig. 14).

    Args:
        path: Output PNG.
        maps: ``(title, keyframe_poses (N, 3), neuron_poses (K, 3))`` per map, map frame (m);
            NaN neuron rows (neurons that win no image) are skipped.
        room_polygon: Wall corners in the map frame (open or closed polygon), or None.
        furniture: ``(name, polygon)`` footprints in the map frame, or None.

    Returns:
        ``path``.
    """
    count = max(1, len(maps))
    fig = new_figure(4.2 * count, 5.2, DPI)
    axes = fig.subplots(1, count, squeeze=False)
    for ax, (title, kf, neurons) in zip(axes[0], maps, strict=False):
        kf = np.asarray(kf, dtype=np.float64).reshape(-1, 3)
        nr = np.asarray(neurons, dtype=np.float64).reshape(-1, 3)
        nr = nr[np.all(np.isfinite(nr), axis=1)]
        _draw_room(ax, room_polygon)
        draw_furniture(ax, furniture)
        ax.plot(kf[:, 0], kf[:, 1], ".", color="0.6", ms=3, label=f"survey images ({len(kf)})")
        ax.plot(nr[:, 0], nr[:, 1], "o", color="tab:blue", ms=3.5, label=f"neurons ({len(nr)})")
        _finish(ax, title, 7, outside=False)
    fig.tight_layout()
    return save_figure(fig, path)


def _finite_xy(value: Any) -> bool:
    return (
        value is not None
        and len(value) >= 2
        and all(v is not None and math.isfinite(float(v)) for v in value[:2])
    )


def plot_estimates(
    path: Path,
    records: Sequence[Mapping[str, Any]],
    title: str,
    room_polygon: np.ndarray | None = None,
    survey_poses: np.ndarray | None = None,
    furniture: Furniture = None,
) -> Path:
    """Estimates against the truth, a line joining each pair (the paper's Fig. 20).

    Args:
        path: Output PNG.
        records: Dicts with ``truth`` and ``estimate`` ([x, y, theta], map frame, m); an
            estimate that is None or not finite is a miss, drawn at its truth.
        title: Figure title.
        room_polygon: Wall corners in the map frame (open or closed polygon), or None.
        survey_poses: ``(N, 3)`` survey poses to draw faintly (map frame: the map's own
            poses of its keyframes), or None.
        furniture: ``(name, polygon)`` footprints in the map frame, or None.

    Returns:
        ``path``.
    """
    fig = new_figure(7.6, 5.6, DPI)
    ax = fig.add_subplot(1, 1, 1)
    _draw_room(ax, room_polygon)
    draw_furniture(ax, furniture)
    if survey_poses is not None and len(survey_poses):
        sp = np.asarray(survey_poses, dtype=np.float64).reshape(-1, 3)
        ax.plot(sp[:, 0], sp[:, 1], "-", color="0.8", lw=1, label="survey path (map)")
    hits = [r for r in records if _finite_xy(r.get("estimate"))]
    misses = [r for r in records if not _finite_xy(r.get("estimate"))]
    truth = np.array([r["truth"][:2] for r in hits], dtype=np.float64).reshape(-1, 2)
    est = np.array([r["estimate"][:2] for r in hits], dtype=np.float64).reshape(-1, 2)
    for t, e in zip(truth, est, strict=True):
        ax.plot([t[0], e[0]], [t[1], e[1]], "-", color="tab:red", lw=0.8, alpha=0.6)
    ax.plot(truth[:, 0], truth[:, 1], "o", color="tab:green", ms=5, label=f"truth ({len(hits)})")
    ax.plot(est[:, 0], est[:, 1], "x", color="tab:red", ms=5, label=f"estimate ({len(hits)})")
    if misses:
        mt = np.array([r["truth"][:2] for r in misses], dtype=np.float64).reshape(-1, 2)
        ax.plot(
            mt[:, 0], mt[:, 1], "o", mfc="none", mec="magenta", mew=1.8, ms=10,
            label=f"no estimate ({len(misses)}), at the truth",
        )  # fmt: skip
    _finish(ax, title, 8)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_cdf(
    path: Path, curves: Mapping[str, Sequence[float]], title: str, log_x: bool | None = None
) -> Path:
    """Cumulative distribution of position errors, one curve per variant.

    Misses (NaN or infinite errors: no estimate) keep a curve below 1 and are counted in its
    legend entry. With several curves whose errors span more than ``LOG_SPAN`` (small errors
    squeezed together on a linear axis), the x axis is logarithmic; line styles alternate so
    that curves lying on top of each other stay visible.

    Args:
        path: Output PNG.
        curves: Variant name -> position errors (m).
        title: Figure title.
        log_x: Force a logarithmic (True) or linear (False) x axis; default: automatic.

    Returns:
        ``path``.
    """
    data = {name: cdf(errors) for name, errors in curves.items()}
    finite = np.concatenate([x for x, _ in data.values() if len(x)] or [np.zeros(0)])
    positive = finite[finite > 0]
    if log_x is None:
        drawn = sum(1 for x, _ in data.values() if len(x))
        span = float(positive.max() / positive.min()) if len(positive) > 1 else 1.0
        log_x = drawn > 1 and span > LOG_SPAN
    fig = new_figure(8.4, 4.4, DPI)
    ax = fig.add_subplot(1, 1, 1)
    styles = ("-", "--", "-.", ":")
    low = max(float(np.percentile(positive, 1)) * 0.5, 1e-3) if len(positive) else 1e-3
    for i, (name, (x, y)) in enumerate(data.items()):
        total = len(np.asarray(curves[name]).ravel())
        missed = total - len(x)
        label = f"{name} (n={total}" + (f", {missed} no estimate)" if missed else ")")
        if len(x) == 0:
            ax.plot([], [], styles[i % 4], label=label + ": nothing to draw")
            continue
        start = low if log_x else 0.0
        xs = np.concatenate([[start], np.maximum(x, start)])
        ax.step(xs, np.concatenate([[0.0], y]), where="post", ls=styles[i % 4], lw=1.4, label=label)
    ax.axvline(0.3, color="0.5", ls="--", lw=0.8)
    top = float(np.percentile(finite, 99)) if len(finite) else 0.5
    if log_x:
        ax.set_xscale("log")
        ax.set_xlim(low, max(top * 1.5, low * 10, 0.5))
        ax.set_xlabel("position error (m, log scale)")
    else:
        ax.set_xlim(0.0, min(max(top, 0.5) * 1.1, 8.0))
        ax.set_xlabel("position error (m)")
    ax.set_ylim(0.0, 1.02)
    ax.set_ylabel("fraction of test poses")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    legend_outside(ax, 7)
    fig.tight_layout()
    return save_figure(fig, path)
