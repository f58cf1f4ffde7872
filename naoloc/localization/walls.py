"""The floor-line sensor model: floor-wall lines against the walls the map records.

The survey walked a rectangle a known offset inside the room's walls and placed them
(``meta["wall_poses"]``: the wall frame W in the map frame and the four walls' coordinates
in W, see :mod:`naoloc.mapping.wall_poses`). A floor-wall line seen from pose
``x = (px, py, theta)`` (map frame) is a wall's foot: at distance ``d = c - n . p`` along the
wall's outward normal ``n`` (angle ``alpha``), in direction ``phi = alpha - theta`` in
FRAME_ROBOT. A line that no wall explains (a bench's front, a skirting board in shadow) is
clutter: the model is a mixture of the walls and a uniform clutter density over the
detector's range and all directions, as nav2 AMCL's likelihood field mixes a hit and a
random measurement.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.config import FilterTuning
from naoloc.geometry import Pose2D
from naoloc.perception.floorline import WallLine

__all__ = ["LineFit", "WallMap", "wall_map"]


@dataclass(frozen=True)
class WallMap:
    """The room's walls in the map frame.

    Attributes:
        frame: The wall frame W in the map frame (x along the survey's first wall).
        bounds: The walls in W, ``(x_min, x_max, y_min, y_max)``, m.
        normals: ``(4,)`` outward normal angle of each wall in the map frame, rad.
        coords: ``(4,)`` each wall's coordinate along its normal, m (``n . p = c`` on it).
        faces: ``(F, 4)`` fronts of furniture the survey saw along the walls: each one's
            outward normal (rad) and coordinate (m) as a wall's, and the stretch of it seen,
            ``(lo, hi)`` along ``(-sin, cos)`` of its normal (m, map frame).
    """

    frame: Pose2D
    bounds: tuple[float, float, float, float]
    normals: np.ndarray
    coords: np.ndarray
    faces: np.ndarray = dataclasses.field(default_factory=lambda: np.empty((0, 4)))

    @classmethod
    def of(
        cls,
        frame: Pose2D,
        bounds: tuple[float, float, float, float],
        faces: Sequence[Sequence[float]] = (),
    ) -> WallMap:
        """Walls from their frame (map frame) and their bounds in it (m).

        Args:
            frame: The wall frame W in the map frame.
            bounds: The walls' floor lines in W, ``(x_min, x_max, y_min, y_max)``, m.
            faces: Fronts of furniture along the walls (``wall_poses.faces``: the wall's
                index 0-3 as in :attr:`normals`, how far before its floor line the front
                stands (m) and the two ends of the stretch seen in W, m).
        """
        x0, x1, y0, y1 = bounds
        local = np.array([0.0, math.pi / 2, math.pi, -math.pi / 2])
        normals = frame.theta + local
        n = np.column_stack([np.cos(normals), np.sin(normals)])
        coords = n @ np.array([frame.x, frame.y]) + np.array([x1, y1, -x0, -y0])
        rows = []
        for wall, depth, xa, ya, xb, yb in faces:
            k = int(wall)
            normal = float(normals[k])
            tangent = np.array([-math.sin(normal), math.cos(normal)])
            ends = [frame * Pose2D(xa, ya, 0.0), frame * Pose2D(xb, yb, 0.0)]
            along = sorted(float(tangent @ np.array([e.x, e.y])) for e in ends)
            rows.append([normal, float(coords[k]) - depth, along[0], along[1]])
        face_rows = np.array(rows, dtype=np.float64).reshape(-1, 4)
        return cls(frame, (x0, x1, y0, y1), normals, coords, face_rows)

    def depth(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """How far map-frame points (m, arrays of one shape) stand inside the nearest wall
        (m; negative beyond it)."""
        d = np.full(np.shape(x), np.inf)
        for normal, coord in zip(self.normals, self.coords, strict=True):
            d = np.minimum(d, coord - (math.cos(normal) * x + math.sin(normal) * y))
        return d

    def inside(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Whether the map-frame point (m) is inside the walls by at least ``margin`` (m)."""
        return bool(self.depth(np.asarray(x), np.asarray(y)) >= margin)

    def expected(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each wall's distance (m) and direction (rad, FRAME_ROBOT) seen from ``pose``."""
        _n, dist, direction = _seen(self.normals, self.coords, pose)
        return dist, direction


def _seen(
    normals: np.ndarray, coords: np.ndarray, pose: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lines of outward ``normals`` (rad) at ``coords`` (m) seen from ``pose`` (map frame):
    their unit normals ``(k, 2)``, distances (m) and directions (rad, FRAME_ROBOT)."""
    n = np.column_stack([np.cos(normals), np.sin(normals)])
    return n, coords - n @ pose[:2], np.angle(np.exp(1j * (normals - pose[2])))


def wall_map(meta: dict[str, Any]) -> WallMap | None:
    """Where the floor lines of the walls a map's meta records stand, or None.

    From ``wall_poses.wall_frame`` and ``walls_m`` (the wall surfaces), moved in by
    ``wall_poses.skirting_m`` where the survey recorded skirting boards: the floor line is
    the boards' foot. None for a map whose keyframe poses did not come from the walls.
    """
    wp = meta.get("wall_poses")
    if not isinstance(wp, dict):
        return None
    frame, bounds = wp.get("wall_frame"), wp.get("walls_m")
    if not (isinstance(frame, list) and len(frame) == 3 and isinstance(bounds, list)):
        return None
    values = [*frame, *bounds]
    if len(bounds) != 4 or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values
    ):
        return None
    x0, x1, y0, y1 = (float(v) for v in bounds)
    skirting = wp.get("skirting_m", 0.0)
    if isinstance(skirting, (int, float)) and not isinstance(skirting, bool) and 0 < skirting < 0.1:
        x0, x1, y0, y1 = x0 + skirting, x1 - skirting, y0 + skirting, y1 - skirting
    if not (x0 < x1 and y0 < y1):
        return None
    faces = wp.get("faces")
    rows = [
        face
        for face in (faces if isinstance(faces, list) else [])
        if isinstance(face, list)
        and len(face) == 6
        and face[0] in (0, 1, 2, 3)
        and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in face
        )
        and 0 < face[1] < min(x1 - x0, y1 - y0)
    ]
    return WallMap.of(Pose2D(*(float(v) for v in frame)), (x0, x1, y0, y1), rows)


@dataclass(frozen=True)
class LineFit:
    """One line's best wall at a pose.

    Attributes:
        wall: Index of the wall (0..3) or of a furniture front (4.., among those whose
            stretch the line's foot lies on), or -1 when clutter explains it better.
        residual: ``(2,)`` observed minus expected: distance (m), direction (rad).
        jacobian: ``(2, 3)`` d residual / d pose (x, y, theta).
        sigma: ``(2,)`` the line's noise: distance (m), direction (rad).
        log_ratio: log of (walls-and-clutter mixture / clutter alone), nats.
        log_beyond: What the map's walls say against the line (nats, <= 0): log of the
            mixture whose clutter stands inside the walls over the one whose clutter may
            stand anywhere. About 0 for a wall's foot and for a line inside the room;
            ``log(line_beyond_share)`` for one well beyond the walls, which the mapped room
            cannot show from this pose.
    """

    wall: int
    residual: np.ndarray
    jacobian: np.ndarray
    sigma: np.ndarray
    log_ratio: float
    log_beyond: float = 0.0


def line_sigma(line: WallLine, tun: FilterTuning) -> np.ndarray:
    """A line's noise: distance (m) growing with distance, direction (rad)."""
    return np.array([tun.line_sigma_m + tun.line_sigma_per_m * line.distance, tun.line_sigma_rad])


def clutter_density(walls: WallMap, line: WallLine, pose: np.ndarray, tun: FilterTuning) -> float:
    """Density (per m and rad) of a line that is not a wall's foot, at ``line``.

    Rooms' furniture stands along the walls: a clutter line is within
    ``clutter_aligned_rad`` of a wall's direction with probability ``clutter_aligned``
    (a bench's front, a bookcase's foot), otherwise any direction; at any distance up to
    ``line_range_m``.
    """
    _dist, direction = walls.expected(pose)
    off = np.abs(np.angle(np.exp(1j * (line.normal - direction))))
    width = tun.clutter_aligned_rad
    aligned = float(np.any(off < width)) * tun.clutter_aligned / (4 * 2 * width)
    return (aligned + (1.0 - tun.clutter_aligned) / (2.0 * math.pi)) / tun.line_range_m


def fit_line(
    walls: WallMap, line: WallLine, pose: np.ndarray, tun: FilterTuning, cov: np.ndarray | None
) -> LineFit:
    """The wall that explains ``line`` seen from ``pose`` best, and how much it explains.

    A furniture front the survey saw (:attr:`WallMap.faces`) is a wall too where the
    line's foot lies within ``face_reach_m`` of the stretch seen.

    Args:
        walls: The map's walls.
        line: A floor-wall line, FRAME_ROBOT.
        pose: ``(x, y, theta)`` of the robot at capture, map frame.
        tun: The filter's tuning.
        cov: The pose's covariance, widening the match (None: the pose is exact).

    Returns:
        The best wall (or -1) with the residual, Jacobian and the mixture's log ratio.
    """
    normals, coords = walls.normals, walls.coords
    if len(walls.faces):  # a front explains a line whose foot lies on the stretch seen
        foot = line_point(line, pose)
        tangent = np.column_stack([-np.sin(walls.faces[:, 0]), np.cos(walls.faces[:, 0])])
        along = tangent @ foot
        reach = tun.face_reach_m
        on = (along >= walls.faces[:, 2] - reach) & (along <= walls.faces[:, 3] + reach)
        normals = np.concatenate([normals, walls.faces[on, 0]])
        coords = np.concatenate([coords, walls.faces[on, 1]])
    n, dist, direction = _seen(normals, coords, pose)
    sigma = line_sigma(line, tun)
    r_d = line.distance - dist
    r_a = np.angle(np.exp(1j * (line.normal - direction)))
    best, best_m, best_s = -1, math.inf, np.diag(sigma**2)
    for k in range(len(normals)):
        jac = np.array([[n[k, 0], n[k, 1], 0.0], [0.0, 0.0, 1.0]])
        s = np.diag(sigma**2) + (jac @ cov @ jac.T if cov is not None else 0.0)
        r = np.array([r_d[k], r_a[k]])
        m = float(r @ np.linalg.solve(s, r))
        if m < best_m:
            best, best_m, best_s = k, m, s
    clutter = tun.line_outlier_share * clutter_density(walls, line, pose, tun)
    hit = (
        (1.0 - tun.line_outlier_share)
        * math.exp(-0.5 * best_m)
        / (2.0 * math.pi * math.sqrt(float(np.linalg.det(best_s))))
    )
    # Clutter stands inside the walls: a line beyond them is a detector's error, or not this
    # room (nav2 AMCL's beam model: nothing is seen past the wall but at random).
    # It speaks against the room, not among the places: a place that loses nats to one
    # scan's lines beyond its walls (a door's edge, a window's sill read as the floor's
    # boundary while walking) hands the lead to another at full confidence.
    inside = inside_probability(walls, line, pose, tun, cov)
    kept = tun.line_beyond_share + (1.0 - tun.line_beyond_share) * inside
    log_ratio = math.log((hit + clutter) / clutter)
    log_beyond = math.log((hit + kept * clutter) / (hit + clutter))
    jac = np.array([[n[best, 0], n[best, 1], 0.0], [0.0, 0.0, 1.0]])
    residual = np.array([r_d[best], r_a[best]])
    return LineFit(best if hit > clutter else -1, residual, jac, sigma, log_ratio, log_beyond)


def line_point(line: WallLine, pose: np.ndarray, along: float = 0.0) -> np.ndarray:
    """The map-frame point ``(x, y)`` (m) of ``line`` seen from ``pose``: its foot (the
    nearest point to FRAME_ROBOT's origin) moved ``along`` metres along it (the normal turned
    a quarter turn counter-clockwise, as :attr:`WallLine.ends_m`)."""
    heading = float(pose[2]) + line.normal
    c, s = math.cos(heading), math.sin(heading)
    return np.array(
        [float(pose[0]) + line.distance * c - along * s,
         float(pose[1]) + line.distance * s + along * c]
    )  # fmt: skip


def inside_probability(
    walls: WallMap, line: WallLine, pose: np.ndarray, tun: FilterTuning, cov: np.ndarray | None
) -> float:
    """The probability that ``line`` seen from ``pose`` stands inside the map's walls.

    The line's nearest point to the robot (of its inliers' stretch where known, else the
    foot of its normal) is placed in the map frame and its depth inside the walls, plus
    ``line_ghost_share`` of its range (a skirting board's top edge, read as the floor's
    boundary when the foot is hidden, stands that much farther), weighed against its noise:
    the line's distance noise, the walls' (``wall_sigma_m``) and the pose's own (its
    position and, times the range, its heading), as a normal distribution. The nearest
    point, because a vertical edge (a corner, a cupboard's side) read as a floor line stands
    on the floor only at its near end: the rest is the edge above the floor, projected
    onto it beyond.

    Args:
        walls: The map's walls.
        line: A floor-wall line, FRAME_ROBOT.
        pose: ``(x, y, theta)`` of the robot at capture, map frame.
        tun: The filter's tuning.
        cov: The pose's covariance (None: the pose is exact).

    Returns:
        Between 0 (well beyond a wall) and 1 (well inside).
    """
    along = 0.0 if line.ends_m is None else min(max(0.0, line.ends_m[0]), line.ends_m[1])
    x, y = line_point(line, pose, along)
    reach = math.hypot(line.distance, along)
    depth = float(walls.depth(np.asarray(x), np.asarray(y))) + tun.line_ghost_share * reach
    var = float(line_sigma(line, tun)[0]) ** 2 + tun.wall_sigma_m**2
    if cov is not None:
        var += float(np.linalg.eigvalsh(cov[:2, :2]).max()) + reach**2 * float(cov[2, 2])
    return 0.5 * (1.0 + math.erf(depth / math.sqrt(2.0 * var)))
