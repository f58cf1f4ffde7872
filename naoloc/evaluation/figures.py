"""PNG figures of an evaluation: the map (like the paper's Fig. 14), estimates vs truth (like
Fig. 20) and the cumulative distribution of errors.

Everything is drawn in the map frame (m). Figures come from :mod:`naoloc.plots` (their own
Agg canvas, no pyplot), so importing this module costs nothing and needs no display.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.evaluation.stats import cdf
from naoloc.plots import new_figure, save_figure

DPI = 110


def _finish(ax: Any, title: str, legend_size: int, legend_loc: str) -> None:
    """Title, equal aspect, map-frame axis labels, grid and legend of a map panel."""
    ax.set_title(title, fontsize=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size, loc=legend_loc)


def _draw_room(ax: Any, room_polygon: np.ndarray | None) -> None:
    if room_polygon is None:
        return
    poly = np.vstack([room_polygon, room_polygon[:1]])
    ax.plot(poly[:, 0], poly[:, 1], color="0.3", lw=1.5, label="walls")


def plot_maps(
    path: Path,
    maps: Sequence[tuple[str, np.ndarray, np.ndarray]],
    room_polygon: np.ndarray | None = None,
) -> Path:
    """Neuron poses of one or more maps over the survey poses (the paper's Fig. 14).

    Args:
        path: Output PNG.
        maps: ``(title, keyframe_poses (N, 3), neuron_poses (K, 3))`` per map, map frame (m);
            NaN neuron rows (neurons that win no image) are skipped.
        room_polygon: Wall corners in the map frame (open or closed polygon), or None.

    Returns:
        ``path``.
    """
    count = max(1, len(maps))
    fig = new_figure(4.2 * count, 4.4, DPI)
    axes = fig.subplots(1, count, squeeze=False)
    for ax, (title, kf, neurons) in zip(axes[0], maps, strict=False):
        kf = np.asarray(kf, dtype=np.float64).reshape(-1, 3)
        nr = np.asarray(neurons, dtype=np.float64).reshape(-1, 3)
        nr = nr[np.all(np.isfinite(nr), axis=1)]
        _draw_room(ax, room_polygon)
        ax.plot(kf[:, 0], kf[:, 1], ".", color="0.75", ms=3, label=f"survey images ({len(kf)})")
        ax.plot(nr[:, 0], nr[:, 1], "o", color="tab:blue", ms=3.5, label=f"neurons ({len(nr)})")
        _finish(ax, title, 7, "upper right")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_estimates(
    path: Path,
    records: Sequence[Mapping[str, Any]],
    title: str,
    room_polygon: np.ndarray | None = None,
    survey_poses: np.ndarray | None = None,
) -> Path:
    """Estimates against the truth, a line joining each pair (the paper's Fig. 20).

    Args:
        path: Output PNG.
        records: Dicts with ``truth`` and ``estimate`` ([x, y, theta], map frame, m).
        title: Figure title.
        room_polygon: Wall corners in the map frame (open or closed polygon), or None.
        survey_poses: ``(N, 3)`` survey poses to draw faintly, or None.

    Returns:
        ``path``.
    """
    fig = new_figure(5.6, 5.6, DPI)
    ax = fig.add_subplot(1, 1, 1)
    _draw_room(ax, room_polygon)
    if survey_poses is not None and len(survey_poses):
        sp = np.asarray(survey_poses, dtype=np.float64).reshape(-1, 3)
        ax.plot(sp[:, 0], sp[:, 1], "-", color="0.85", lw=1, label="survey path")
    truth = np.array([r["truth"][:2] for r in records], dtype=np.float64).reshape(-1, 2)
    est = np.array([r["estimate"][:2] for r in records], dtype=np.float64).reshape(-1, 2)
    for t, e in zip(truth, est, strict=True):
        ax.plot([t[0], e[0]], [t[1], e[1]], "-", color="tab:red", lw=0.8, alpha=0.6)
    ax.plot(truth[:, 0], truth[:, 1], "o", color="tab:green", ms=5, label="truth")
    ax.plot(est[:, 0], est[:, 1], "x", color="tab:red", ms=5, label="estimate")
    _finish(ax, title, 8, "upper right")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_cdf(path: Path, curves: Mapping[str, Sequence[float]], title: str) -> Path:
    """Cumulative distribution of position errors, one curve per variant.

    Args:
        path: Output PNG.
        curves: Variant name -> position errors (m).
        title: Figure title.

    Returns:
        ``path``.
    """
    fig = new_figure(6.4, 4.2, DPI)
    ax = fig.add_subplot(1, 1, 1)
    top = 0.5
    for name, errors in curves.items():
        x, y = cdf(errors)
        if len(x) == 0:
            continue
        top = max(top, float(np.percentile(x, 95)))
        ax.step(np.concatenate([[0.0], x]), np.concatenate([[0.0], y]), where="post", label=name)
    ax.axvline(0.3, color="0.5", ls="--", lw=0.8)
    ax.set_xlim(0.0, min(top * 1.1, 8.0))
    ax.set_ylim(0.0, 1.0)
    ax.set_xlabel("position error (m)")
    ax.set_ylabel("fraction of estimates")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return save_figure(fig, path)
