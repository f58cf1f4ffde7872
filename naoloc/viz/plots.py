"""Pictures of maps and localizations (PNG), drawn with matplotlib's Agg canvas.

Everything is drawn in the map frame (odometry at the survey start: x forward, y left,
metres). When the map's meta holds ``origin_room_pose`` and ``room_size_m`` (a simulated
survey), the room's walls are drawn too. No pyplot: no global figure state.

One style in every picture (:data:`STYLE`): the truth in black and every estimate in green,
each a dot with a heading arrow; an estimate with a covariance also gets its 95 % position
ellipse; the room's walls dark grey, furniture light grey, the survey path blue, the map's
landmarks small grey dots, neurons red rings, the map origin a black star; the legend sits
right of the map and names the same things the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot.keyframe import Keyframe

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from naoloc.localization.localizer import PoseEstimate as Estimate
    from naoloc.mapping import VisualMap


def room_corners(origin_room_pose: Sequence[float], room_size: Sequence[float]) -> np.ndarray:
    """The room's walls in the map frame as a closed ``(5, 2)`` polygon (m).

    Args:
        origin_room_pose: Pose of the map origin in the room frame ``[x, y, theta]``.
        room_size: Inner room size ``[sx, sy]`` (m).
    """
    o = Pose2D.from_list(origin_room_pose)
    sx, sy = float(room_size[0]), float(room_size[1])
    corners = [(0.0, 0.0), (sx, 0.0), (sx, sy), (0.0, sy), (0.0, 0.0)]
    return np.array([[p.x, p.y] for p in (relative_pose(o, Pose2D(x, y)) for x, y in corners)])


def room_outline(meta: dict[str, Any]) -> np.ndarray | None:
    """:func:`room_corners` from a map's or dataset's meta, or None when the room is unknown.

    Args:
        meta: Map or dataset meta with ``origin_room_pose`` ([x, y, theta], room frame)
            and ``room_size_m`` ([sx, sy]).
    """
    origin, size = meta.get("origin_room_pose"), meta.get("room_size_m")
    if origin is None or size is None:
        return None
    return room_corners(origin, size)


def furniture_footprints(
    cfg: Any, origin_room_pose: Sequence[float] | None
) -> list[tuple[str, np.ndarray]]:
    """Furniture of a simulated room as ``(name, (5, 2) closed polygon)`` in the map frame (m).

    The MuJoCo backend generates its furniture from the config (``world.room``); other
    backends have none. Building the layout does not import mujoco.

    Args:
        cfg: The room's :class:`naoloc.config.Config`.
        origin_room_pose: Pose of the map origin in the room frame ``[x, y, theta]``
            (the survey's start), or None when unknown (then nothing is returned).
    """
    if origin_room_pose is None or cfg.robot.backend != "mujoco" or not cfg.world.room.furniture:
        return []
    from naoloc.backends.mujoco.room import build_layout

    o = Pose2D.from_list(origin_room_pose)
    out = []
    for f in build_layout(cfg).furniture:
        x0, y0, x1, y1 = f.rect
        corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
        poly = [relative_pose(o, Pose2D(x, y)) for x, y in corners]
        out.append((f.name, np.array([[p.x, p.y] for p in poly])))
    return out


def draw_furniture(ax: Axes, furniture: Sequence[tuple[str, np.ndarray]] | None) -> None:
    """Fill furniture footprints (map frame) in grey, labelled once with their count."""
    for i, (_, poly) in enumerate(furniture or ()):
        label = f"furniture ({len(furniture or ())})" if i == 0 else None
        ax.fill(poly[:, 0], poly[:, 1], color="0.8", ec="0.45", lw=0.8, label=label, zorder=1)


# role -> (colour, legend label): the one convention of every picture.
STYLE: dict[str, tuple[str, str]] = {
    "truth": ("black", "truth"),
    "estimate": ("tab:green", "estimate"),
    "start": ("tab:purple", "start"),
    "path": ("tab:green", "path (believed)"),
    "stop": ("tab:orange", "stops to look"),
    "survey": ("tab:blue", "survey path"),
    "landmark": ("0.55", "landmarks"),
    "neuron": ("tab:red", "neurons"),
    "miss": ("magenta", "no estimate"),
}
ELLIPSE_CHI2 = 5.991  # chi-square, 2 degrees of freedom, 95 %


def pose_mark(
    ax: Axes, pose: Pose2D, role: str, label: str | None = None, cov: Any = None,
    length: float = 0.35,
) -> None:  # fmt: skip
    """A pose in :data:`STYLE`'s colour for ``role``: a dot, a heading arrow of ``length``
    metres and, with a covariance (3 x 3, x y theta; m^2, rad^2), its 95 % position
    ellipse."""
    color = STYLE[role][0]
    ax.plot([pose.x], [pose.y], "o", color=color, ms=7, label=label, zorder=5)
    ax.annotate(
        "", xy=(pose.x + length * math.cos(pose.theta), pose.y + length * math.sin(pose.theta)),
        xytext=(pose.x, pose.y), zorder=5,
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.8, "shrinkA": 0, "shrinkB": 0},
    )  # fmt: skip
    if cov is not None:
        ellipse(ax, pose, cov, color)


def ellipse(ax: Axes, pose: Pose2D, cov: Any, color: str) -> None:
    """The 95 % ellipse of the position covariance ``cov[:2, :2]`` (m^2) around ``pose``."""
    from matplotlib.patches import Ellipse

    c = np.asarray(cov, dtype=float)
    if c.shape[0] < 2 or not np.all(np.isfinite(c[:2, :2])):
        return
    values, vectors = np.linalg.eigh(c[:2, :2])
    values = np.clip(values, 0.0, None)
    angle = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
    width, height = 2 * np.sqrt(ELLIPSE_CHI2 * values[::-1])
    ax.add_patch(
        Ellipse((pose.x, pose.y), float(width), float(height), angle=angle, fill=False,
                ec=color, lw=1.2, ls="--", zorder=4)
    )  # fmt: skip


def legend_outside(ax: Axes, fontsize: int = 8) -> None:
    """The legend to the right of the axes, never over the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=fontsize)


def new_figure(width: float, height: float, dpi: int = 100) -> Any:
    """A matplotlib Figure on its own Agg canvas (no pyplot, no global figure state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Any, path: Path) -> Path:
    """Write ``fig`` as PNG at ``path`` (creating its folder).

    Raises:
        NaolocError: The file cannot be written.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, format="png")
    except OSError as err:
        raise NaolocError(f"{path}: cannot write the picture: {err.strerror}") from None
    return path


def _draw_map(
    ax: Axes, vmap: VisualMap, furniture: Sequence[tuple[str, np.ndarray]] | None = None
) -> None:
    outline = room_outline(vmap.meta)
    if outline is not None:
        ax.plot(outline[:, 0], outline[:, 1], "-", color="0.3", lw=2, label="room walls")
    draw_furniture(ax, furniture)
    path = np.asarray(vmap.keyframe_poses, dtype=float)[: vmap.wall_images]  # no far pictures
    points = landmark_points(vmap)
    if len(points):  # those beyond the room (or the walk) by 0.5 m stay out of the frame
        extent = outline if outline is not None else path[:, :2]
        if len(extent):
            lo, hi = extent.min(axis=0) - 0.5, extent.max(axis=0) + 0.5
            points = points[np.all((points >= lo) & (points <= hi), axis=1)]
        ax.plot(points[:, 0], points[:, 1], ".", color=STYLE["landmark"][0], ms=1.5, zorder=2,
                label=f"{STYLE['landmark'][1]} ({len(points)})")  # fmt: skip
    if len(path):
        blue = STYLE["survey"][0]
        ax.plot(path[:, 0], path[:, 1], "-", color=blue, lw=0.8, alpha=0.6)
        ax.plot(path[:, 0], path[:, 1], ".", color=blue, ms=3,
                label=f"{STYLE['survey'][1]} ({len(path)} pictures)")  # fmt: skip
    neurons = np.asarray(vmap.neuron_poses, dtype=float)
    if neurons.size:
        ok = np.all(np.isfinite(neurons), axis=1)
        ax.plot(
            neurons[ok, 0], neurons[ok, 1], "o", mfc="none", mec=STYLE["neuron"][0], ms=5,
            label=f"{STYLE['neuron'][1]} ({int(ok.sum())} with images)",
        )  # fmt: skip
    ax.plot([0.0], [0.0], "k*", ms=12, label="map origin")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    ax.grid(True, alpha=0.3)


def landmark_points(vmap: VisualMap) -> np.ndarray:
    """The map's triangulated landmarks, ``(n, 2)`` x y in the map frame (m)."""
    points = getattr(vmap, "kp_points", None)
    if points is None:
        return np.zeros((0, 2))
    xyz = np.asarray(points, dtype=float).reshape(-1, 3)
    return xyz[np.all(np.isfinite(xyz), axis=1), :2]


def _map_figure(
    vmap: VisualMap, furniture: Sequence[tuple[str, np.ndarray]] | None
) -> tuple[Any, Axes]:
    """A 9 x 7 inch figure with one axes showing the map (:func:`_draw_map`)."""
    fig = new_figure(9.0, 7.0)
    ax = fig.add_subplot(1, 1, 1)
    _draw_map(ax, vmap, furniture)
    return fig, ax


def plot_map(
    vmap: VisualMap,
    path: str | Path,
    title: str | None = None,
    furniture: Sequence[tuple[str, np.ndarray]] | None = None,
) -> Path:
    """Draw a map like the paper's Fig. 14: neuron poses over the survey path and the room.

    Args:
        vmap: The map.
        path: PNG file to write.
        title: Figure title; default a summary of the map.
        furniture: Footprints to draw (:func:`furniture_footprints`), map frame.

    Returns:
        The path written.
    """
    fig, ax = _map_figure(vmap, furniture)
    neurons = np.asarray(vmap.neuron_poses, dtype=float).reshape(-1, 3)
    with_images = int(np.all(np.isfinite(neurons), axis=1).sum())
    far = int(getattr(vmap, "far_images", 0))
    ax.set_title(
        title
        or f"{vmap.images} images ({vmap.images - far} on the walk, {far} far), "
        f"{with_images} neurons with images at {vmap.distinct_poses} distinct poses"
    )
    legend_outside(ax)
    fig.tight_layout()
    return save_figure(fig, Path(path))


def plot_localization(
    vmap: VisualMap,
    estimate: Estimate,
    path: str | Path,
    *,
    truth: Pose2D | None = None,
    queries: Sequence[Keyframe] = (),
    title: str | None = None,
    furniture: Sequence[tuple[str, np.ndarray]] | None = None,
) -> Path:
    """Draw an estimate (and the truth, if known) on the map, with the query images.

    Args:
        vmap: The map.
        estimate: The estimate in the map frame.
        path: PNG file to write.
        truth: True pose in the map frame, when known.
        queries: The images used, shown in a strip below the map (at most 10).
        title: Figure title; default the estimate and error.
        furniture: Footprints to draw (:func:`furniture_footprints`), map frame.

    Returns:
        The path written.
    """
    shown = list(queries)[:10]
    rows = 2 if shown else 1
    fig = new_figure(10.0, 8.0 + (1.6 if shown else 0.0))
    grid = fig.add_gridspec(rows, max(1, len(shown)), height_ratios=[5, 1][:rows])
    ax = fig.add_subplot(grid[0, :])
    _draw_map(ax, vmap, furniture)
    if estimate.found:
        est = Pose2D(estimate.x, estimate.y, estimate.theta)
        label = f"estimate (confidence {estimate.confidence:.2f}; 95 % ellipse)"
        pose_mark(ax, est, "estimate", label, cov=estimate.covariance)
        text = f"estimate ({est.x:.2f}, {est.y:.2f}) m"
    else:
        text = "no estimate: nothing recognised"
    if truth is not None:
        pose_mark(ax, truth, "truth", "truth")
        if estimate.found:
            text += f", error {est.distance(truth):.2f} m"
    ax.set_title(title or text)
    legend_outside(ax)
    for i, kf in enumerate(shown):
        sub = fig.add_subplot(grid[1, i])
        img = kf.image if kf.image.ndim == 2 else kf.image[..., ::-1]
        sub.imshow(img, cmap="gray" if kf.image.ndim == 2 else None)
        sub.set_title(f"yaw {math.degrees(kf.head_yaw):.0f}°", fontsize=7)
        sub.axis("off")
    fig.tight_layout()
    return save_figure(fig, Path(path))


def plot_estimates(
    vmap: VisualMap,
    pairs: Sequence[tuple[Pose2D | None, Pose2D | None]],
    path: str | Path,
    title: str | None = None,
    furniture: Sequence[tuple[str, np.ndarray]] | None = None,
    covariances: Sequence[Any] | None = None,
) -> Path:
    """Draw several estimates on the map, each joined to its truth when known.

    A miss (no estimate: None or a non-finite pose) is drawn at its truth with its own
    marker and counted in the legend; it is never drawn as an estimate.

    Args:
        vmap: The map.
        pairs: ``(estimate, truth)`` poses in the map frame; either may be None.
        path: PNG file to write.
        title: Figure title.
        furniture: Footprints to draw (:func:`furniture_footprints`), map frame.
        covariances: Per pair, the estimate's 3 x 3 covariance (or None): its ellipse.

    Returns:
        The path written.
    """
    fig, ax = _map_figure(vmap, furniture)
    covs = list(covariances) if covariances is not None else [None] * len(pairs)

    def found(p: Pose2D | None) -> bool:
        return p is not None and math.isfinite(p.x) and math.isfinite(p.y)

    hits = [(e, t) for e, t in pairs if found(e)]
    misses = [t for e, t in pairs if not found(e)]
    truths = 0
    for i, (est, truth) in enumerate(pairs):
        if truth is not None:
            pose_mark(ax, truth, "truth", "truth" if truths == 0 else None, length=0.25)
            truths += 1
            ax.annotate(str(i + 1), (truth.x, truth.y), textcoords="offset points", xytext=(5, 5))
        if found(est):
            assert est is not None
            label = f"estimate ({len(hits)}; 95 % ellipse)" if est is hits[0][0] else None
            pose_mark(ax, est, "estimate", label, cov=covs[i] if i < len(covs) else None,
                      length=0.25)  # fmt: skip
            if truth is not None:
                ax.plot([truth.x, est.x], [truth.y, est.y], "-", color=STYLE["estimate"][0], lw=1)
    shown = [t for t in misses if t is not None]
    if misses:
        ax.plot(
            [t.x for t in shown], [t.y for t in shown], "o", mfc="none", mec=STYLE["miss"][0],
            mew=2, ms=14, label=f"{STYLE['miss'][1]} ({len(misses)}), at the truth",
        )  # fmt: skip
    ax.set_title(title or f"{len(pairs)} localizations, {len(misses)} without an estimate")
    legend_outside(ax)
    fig.tight_layout()
    return save_figure(fig, Path(path))


def plot_go_home(
    vmap: VisualMap,
    trail: Sequence[Pose2D],
    estimates: Sequence[Estimate],
    path: str | Path,
    *,
    blocked: Sequence[Pose2D] = (),
    truth: Pose2D | None = None,
    reached: bool = False,
    title: str | None = None,
    furniture: Sequence[tuple[str, np.ndarray]] | None = None,
) -> Path:
    """Draw a walk home: start, the path believed walked, every fix, blocked places, the end.

    Args:
        vmap: The map.
        trail: Believed poses from the start to the end (map frame).
        estimates: Every localization's estimate (misses are counted, not drawn).
        path: PNG file to write.
        blocked: Where walks were blocked (map frame).
        truth: True final pose in the map frame, when known.
        reached: Whether the robot believes it arrived.
        title: Figure title; default a summary.
        furniture: Footprints to draw (:func:`furniture_footprints`), map frame.

    Returns:
        The path written.
    """
    fig = new_figure(9.5, 7.0)
    ax = fig.add_subplot(1, 1, 1)
    _draw_map(ax, vmap, furniture)
    if trail:
        xy = np.array([[p.x, p.y] for p in trail])
        ax.plot(xy[:, 0], xy[:, 1], "-", color=STYLE["path"][0], lw=2, label=STYLE["path"][1])
        pose_mark(ax, trail[0], "start", "start (believed)")
        pose_mark(ax, trail[-1], "estimate", "end (believed)")
    found = [e for e in estimates if e.found]
    for i, e in enumerate(found):
        label = f"{STYLE['stop'][1]} ({len(found)}; 95 % ellipse)" if i == 0 else None
        ax.plot([e.x], [e.y], "D", color=STYLE["stop"][0], ms=6, label=label, zorder=5)
        if e.covariance is not None:
            ellipse(ax, Pose2D(e.x, e.y, e.theta), e.covariance, STYLE["stop"][0])
    misses = len(estimates) - len(found)
    if misses:
        ax.plot([], [], " ", label=f"no estimate: {misses} looks")
    if blocked:
        ax.plot([b.x for b in blocked], [b.y for b in blocked], "X", color="red", ms=10,
                label="blocked walk")  # fmt: skip
    if truth is not None:
        pose_mark(ax, truth, "truth", "end (truth)")
    verdict = "reached home" if reached else "did not reach home"
    ax.set_title(title or f"go-home: {verdict}")
    legend_outside(ax)
    fig.tight_layout()
    return save_figure(fig, Path(path))
