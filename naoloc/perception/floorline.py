"""The floor-wall line: a wall's distance and direction from one image of the floor.

Pure numpy + OpenCV, no robot. The camera's pose in FRAME_ROBOT (NAOqi's
``getTransform(name, FRAME_ROBOT, True)``) and its field of view give each pixel's ray; a
pixel on the floor (z = 0) back-projects to a metric point in FRAME_ROBOT, because the
camera's height is known from the kinematics. The floor-wall line needs no texture on the
wall: only a floor that looks different from what stands on it.

The detector:

1. models the floor's colour from the image rows that look at the floor nearest the robot
   (robust median and spread in CIE Lab, lightness down-weighted against shading);
2. marks each pixel floor or not, closes thin gaps (plank seams, carpet speckle);
3. in each column, takes the top of the lowest run of floor that reaches the image bottom
   or the robot's own body (the first non-floor pixel above it is the wall's foot, or
   whatever stands on the floor in front of the wall);
4. back-projects those pixels to z = 0 and fits a line by RANSAC, then least squares;
5. of two parallel lines, drops the farther when it is a skirting board's top edge taken
   for floor in part of the picture (:func:`skirting_ghost`).

A line is reported only with enough inliers spread along it; otherwise None (a floor and a
wall of the same colour, no wall in view, or a view filled with furniture).

Every threshold is a field of :class:`naoloc.config.FloorLineTuning` (a config's
``camera.floor_lines``), passed as ``tun`` (None: the defaults).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from naoloc.config import FloorLineTuning
from naoloc.errors import FeatureError
from naoloc.geometry import modulo2PI
from naoloc.robot.lens import Lens, pinhole_lens

# The default thresholds (``camera.floor_lines`` of a config tunes them); immutable.
_DEFAULT = FloorLineTuning()


@dataclass(frozen=True, slots=True)
class WallLine:
    """A wall's foot on the floor, in FRAME_ROBOT (x forward, y left, metres, radians).

    Attributes:
        distance: Perpendicular distance from FRAME_ROBOT's origin to the line, m.
        normal: Direction from the origin to the line's nearest point, rad (``-pi/2``: a
            wall straight to the right, parallel to the robot).
        inliers: Boundary pixels on the line.
        fraction: ``inliers`` over the boundary pixels found.
        rms_m: RMS distance of the inliers to the line, m.
        span_m: Length of the line covered by inliers, m.
        ends_m: Where the inliers begin and end along the line, m: coordinates from the
            line's nearest point to FRAME_ROBOT's origin, along the normal turned a
            quarter turn counter-clockwise (for a wall ahead: to the left); None when not
            known.
    """

    distance: float
    normal: float
    inliers: int
    fraction: float
    rms_m: float
    span_m: float
    ends_m: tuple[float, float] | None = None

    def to_dict(self) -> dict[str, float]:
        """JSON-able form (distance m, normal rad, rms and span m)."""
        return {
            "distance_m": round(self.distance, 4),
            "normal_rad": round(self.normal, 4),
            "inliers": self.inliers,
            "fraction": round(self.fraction, 3),
            "rms_m": round(self.rms_m, 4),
            "span_m": round(self.span_m, 3),
        }


def pixel_rays(
    width: int,
    height: int,
    hfov: float,
    vfov: float,
    camera_pose: np.ndarray,
    lens: Lens | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rays of every pixel centre in FRAME_ROBOT.

    Args:
        width: Image width, px.
        height: Image height, px.
        hfov: Horizontal field of view, rad.
        vfov: Vertical field of view, rad.
        camera_pose: 4x4 pose of the camera (NAOqi frame: x optical axis, y left, z up) in
            FRAME_ROBOT, or its 16 floats row-major.
        lens: The camera's lens (None: a pinhole of ``hfov x vfov``).

    Returns:
        ``(origin (3,), directions (height, width, 3))``, directions not normalised.
    """
    t = np.asarray(camera_pose, dtype=np.float64).reshape(4, 4)
    lens = lens or pinhole_lens(hfov, vfov)
    cols, rows = np.meshgrid(
        np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64)
    )
    uu, vv = lens.normalized(cols, rows, width, height)
    # optical (x right, y down, z forward) -> NAOqi camera (x forward, y left, z up)
    cam = np.stack([np.ones_like(uu), -uu, -vv], axis=-1)
    return t[:3, 3].copy(), cam @ t[:3, :3].T


def floor_points(
    rows: np.ndarray,
    cols: np.ndarray,
    origin: np.ndarray,
    rays: np.ndarray,
    *,
    tun: FloorLineTuning | None = None,
) -> np.ndarray:
    """Back-project pixels ``(rows, cols)`` onto the floor z = 0; ``(n, 2)`` x, y in m.

    Pixels whose ray does not go down, or that land beyond ``tun.max_range_m``, come back NaN
    (``tun``: the detector's thresholds, None: the defaults).
    """
    tun = _DEFAULT if tun is None else tun
    d = rays[rows, cols]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -origin[2] / d[:, 2]
    s = np.where(d[:, 2] < -1e-6, s, np.nan)
    xy = origin[None, :2] + s[:, None] * d[:, :2]
    far = np.hypot(xy[:, 0] - origin[0], xy[:, 1] - origin[1]) > tun.max_range_m
    xy[far] = np.nan
    return xy


def _norm_last(v: np.ndarray) -> np.ndarray:
    """Euclidean norm over the last axis (2 or 3 channels), the same float32 bits as
    ``np.linalg.norm(v, axis=-1)`` (squares summed in channel order) in a quarter of its
    time on an image."""
    sq = v[..., 0] * v[..., 0]
    for k in range(1, v.shape[-1]):
        sq += v[..., k] * v[..., k]
    return np.sqrt(sq)


def floor_mask(
    bgr: np.ndarray, sample_rows: np.ndarray, *, tun: FloorLineTuning | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Pixels that look like the floor; the colour model comes from ``sample_rows``.

    Args:
        bgr: ``(h, w, 3)`` uint8 image.
        sample_rows: Boolean ``(h,)``: rows known to look at the near floor.
        tun: The detector's thresholds (``tone_ratio``, ``darkest_foot``, ``chroma_tol``);
            None: the defaults.

    Returns:
        Boolean ``(h, w)`` mask, the weighted Lab image ``(h, w, 3)``, the floor's
        colour in it ``(3,)`` and the colour distance taken as floor.
    """
    import cv2

    tun = _DEFAULT if tun is None else tun
    blurred = cv2.GaussianBlur(bgr, (5, 5), 0)
    lab = cv2.cvtColor(blurred, cv2.COLOR_BGR2LAB).astype(np.float32)
    lab[..., 0] *= 0.3  # shading and plank tones change lightness more than colour
    sample = lab[sample_rows].reshape(-1, 3)
    centre = np.median(sample, axis=0)
    dist = _norm_last(lab - centre)
    sdist = dist[sample_rows].ravel()
    # the near floor is mostly floor: its 75th percentile bounds the floor's own spread
    threshold = max(8.0, 2.5 * float(np.percentile(sdist, 75)))
    mask = dist < threshold
    # Planks of another tone (a lighter or darker board, the same wood): the floor's own
    # chroma at a lightness the floor's boards span. A skirting of the floor's wood is
    # darker than that (about half), a painted wall or skirting has another chroma.
    # Chromaticity (each channel's share of the sum) does not change when a colour is
    # only lighter or darker, as a board of another tone is.
    channels = blurred.astype(np.float32)
    total = channels[..., 0] + channels[..., 1] + channels[..., 2] + 1.0  # exact: integers
    rg = channels[..., 1:] / total[..., None]  # (g, r) shares
    chroma = _norm_last(rg - np.median(rg[sample_rows].reshape(-1, 2), axis=0))
    chroma_tol = float(np.clip(2.5 * np.percentile(chroma[sample_rows], 75), *tun.chroma_tol))
    ratio = total / max(1.0, float(np.median(total[sample_rows])))
    mask |= (chroma < chroma_tol) & (ratio > tun.tone_ratio[0]) & (ratio < tun.tone_ratio[1])
    # bands of another tone across the floor (plank rows, seams, shadows) are shorter in
    # the image than what stands on the floor: close them
    kernel = np.ones((max(7, bgr.shape[0] // 18) | 1, 3), np.uint8)
    closed = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, kernel)
    mask = cv2.morphologyEx(closed, cv2.MORPH_OPEN, np.ones((5, 5), np.uint8)).astype(bool)
    # Much darker than the floor is never floor, whatever closing did: a skirting of the
    # floor's wood (its blur into a lighter wall above can look like floor).
    mask &= ratio > tun.darkest_foot
    return mask, lab, centre, threshold


def refine_boundary(
    lab: np.ndarray,
    floor: np.ndarray,
    threshold: float,
    rows: np.ndarray,
    cols: np.ndarray,
    reach: int,
    *,
    tun: FloorLineTuning | None = None,
) -> np.ndarray:
    """Move each boundary up through floor pixels darker or lighter than the floor model.

    A wall's foot often sits on a band of shadowed floor (contact shadow, a plank of
    another tone): from the first non-floor pixel, each pixel is given to the floor while
    its colour is nearer the floor's than the wall's (sampled a few pixels higher) and
    within three times the floor's threshold.

    Args:
        lab: Weighted Lab image from :func:`floor_mask`.
        floor: The floor's colour ``(3,)``.
        threshold: The floor's colour distance threshold.
        rows: Boundary rows (the top floor pixel of each column).
        cols: Their columns.
        reach: Most pixels to move up.
        tun: The detector's thresholds (``darkest_foot``); None: the defaults.

    Returns:
        The refined rows.
    """
    tun = _DEFAULT if tun is None else tun
    out = rows.copy()
    ok = rows - reach - 6 >= 0
    if not ok.any() or reach < 1:
        return out
    r, c = rows[ok], cols[ok]
    top = r - reach - 6
    wall = np.median(lab[top[:, None] + np.arange(6), c[:, None]], axis=1)  # (n, 3)
    # Pixels r-1, r-2, ... r-reach above each boundary: (n, reach, 3).
    px = lab[r[:, None] - np.arange(1, reach + 1), c[:, None]]
    to_floor = np.linalg.norm(px - floor, axis=-1)
    lighter = px[..., 0] > tun.darkest_foot * floor[0]  # much darker: a skirting, not floor
    floorish = (
        lighter
        & (to_floor < 3.0 * threshold)
        & (to_floor < np.linalg.norm(px - wall[:, None, :], axis=-1))
    )
    # Each boundary moves up while its pixels stay floorish: the first that is not stops it.
    steps = np.where(floorish.all(axis=1), reach, np.argmin(floorish, axis=1))
    out[ok] = r - steps
    return out


def subpixel_edges(
    lab: np.ndarray, floor: np.ndarray, rows: np.ndarray, cols: np.ndarray
) -> np.ndarray:
    """Sub-pixel image rows of the floor-wall edges (continuous: 0 is the image's top).

    The image was blurred, so the colour goes smoothly from the wall's (sampled just above
    the edge) to the floor's across a few rows; the edge is where it is half-way, by linear
    interpolation between pixel centres. Columns where that fails keep the top of their
    boundary pixel.

    Args:
        lab: Weighted Lab image from :func:`floor_mask`.
        floor: The floor's colour ``(3,)``.
        rows: Boundary rows (the top floor pixel of each column).
        cols: Their columns.
    """
    h = lab.shape[0]
    out = rows.astype(np.float64)
    ok = (rows >= 7) & (rows + 4 < h)
    if not ok.any():
        return out
    r, c = rows[ok], cols[ok]
    wall = np.median(lab[r[:, None] + np.arange(-7, -3), c[:, None]], axis=1)  # (n, 3)
    d = wall - floor
    n2 = np.einsum("nj,nj->n", d, d)
    # ~1 on the wall, ~0 on the floor, rows r-3 .. r+3: (n, 7)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("nkj,nj->nk", lab[r[:, None] + np.arange(-3, 4), c[:, None]] - floor, d)
        t = t / n2[:, None]
    cross = (t[:, :6] >= 0.5) & (t[:, 1:] < 0.5)  # the first k with t[k] >= 0.5 > t[k+1]
    found = cross.any(axis=1) & (n2 >= 1e-6)
    k = np.argmax(cross, axis=1)
    rows_n = np.arange(len(r))
    tk, tk1 = t[rows_n, k], t[rows_n, k + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        edge = (r - 3 + k) + 0.5 + (tk - 0.5) / (tk - tk1)
    sub = out[ok]
    sub[found] = edge[found]
    out[ok] = sub
    return out


def rays_at(
    v: np.ndarray,
    cols: np.ndarray,
    size: tuple[int, int],
    hfov: float,
    vfov: float,
    pose: np.ndarray,
    lens: Lens | None = None,
) -> np.ndarray:
    """FRAME_ROBOT rays ``(n, 3)`` through continuous rows ``v`` of columns ``cols`` (centres).

    Args:
        v: Continuous image rows (0 is the top edge), ``(n,)``.
        cols: Pixel columns, ``(n,)``.
        size: ``(width, height)`` in pixels.
        hfov: Horizontal field of view, rad.
        vfov: Vertical field of view, rad.
        pose: The camera's 4x4 pose in FRAME_ROBOT.
        lens: The camera's lens (None: a pinhole of ``hfov x vfov``).
    """
    w, h = size
    lens = lens or pinhole_lens(hfov, vfov)
    # continuous rows have 0 at the top edge; pixel centres sit at index + 0.5
    u, vv = lens.normalized(np.asarray(cols, np.float64), np.asarray(v, np.float64) - 0.5, w, h)
    cam = np.stack([np.ones_like(u), -u, -vv], axis=-1)
    return cam @ pose[:3, :3].T


def boundary_pixels(mask: np.ndarray, min_run: int) -> tuple[np.ndarray, np.ndarray]:
    """Per column, the top of the lowest sustained floor run (the floor's far edge).

    Scanning up from the image bottom, non-floor pixels at the very bottom (the robot's own
    body) are skipped; the floor run that follows must be at least ``min_run`` pixels long;
    its top, when something non-floor lies above it in the image, is the column's boundary.

    Returns:
        ``(rows, cols)`` of the boundary pixels (the last floor pixel of each column).
    """
    h = mask.shape[0]
    col = mask[::-1]  # from the bottom up
    start = np.argmax(col, axis=0)  # the first floor pixel from the bottom
    above = np.arange(h)[:, None] >= start[None, :]
    gaps = ~col & above
    end = np.where(gaps.any(axis=0), np.argmax(gaps, axis=0), h)  # the run's end
    # floor up to the top of the image, or no sustained floor: no boundary
    keep = col.any(axis=0) & (end < h) & (end - start >= min_run)
    cols = np.flatnonzero(keep)
    return (h - end[cols]).astype(np.int64), cols.astype(np.int64)


def fit_line(
    points: np.ndarray, seed: int = 0, *, tun: FloorLineTuning | None = None
) -> tuple[np.ndarray, np.ndarray] | None:
    """RANSAC then least-squares line through 2-D points.

    Args:
        points: ``(n, 2)`` points, m.
        seed: Seed of RANSAC.
        tun: The detector's thresholds (``min_inliers``, ``ransac_samples``,
            ``ransac_tolerance_m``); None: the defaults.

    Returns:
        ``(point on the line, unit direction)`` and the inlier mask as a pair, or None.
    """
    tun = _DEFAULT if tun is None else tun
    n = len(points)
    if n < tun.min_inliers:
        return None
    # tun.ransac_samples random pairs of distinct points (drawn one pair at a time, as ever: the
    # same seed gives the same lines), scored at once.
    rng = np.random.default_rng(seed)
    pairs = np.array([rng.choice(n, 2, replace=False) for _ in range(tun.ransac_samples)])
    d = points[pairs[:, 1]] - points[pairs[:, 0]]
    norm = np.hypot(d[:, 0], d[:, 1])
    usable = norm >= 0.05
    if not usable.any():
        return None
    d, norm, first = d[usable], norm[usable], points[pairs[usable, 0]]
    normal = np.column_stack([-d[:, 1], d[:, 0]]) / norm[:, None]
    # |(p - p_i) . normal| for every point and pair: (pairs, n)
    res = np.abs(
        (points[None, :, 0] - first[:, 0, None]) * normal[:, 0, None]
        + (points[None, :, 1] - first[:, 1, None]) * normal[:, 1, None]
    )
    counts = (res < tun.ransac_tolerance_m).sum(axis=1)
    k = int(np.argmax(counts))  # the first of the best
    best, best_count = res[k] < tun.ransac_tolerance_m, int(counts[k])
    if best_count < tun.min_inliers:
        return None
    inl = best
    for _ in range(2):
        p = points[inl]
        centre = p.mean(axis=0)
        _, _, vt = np.linalg.svd(p - centre, full_matrices=False)  # not the n x n U
        direction = vt[0]
        normal = np.array([-direction[1], direction[0]])
        inl = np.abs((points - centre) @ normal) < tun.ransac_tolerance_m
        if inl.sum() < tun.min_inliers:
            return None
    return np.vstack([centre, direction]), inl


def detect_wall_lines(
    image: np.ndarray,
    hfov: float,
    vfov: float,
    camera_pose: np.ndarray,
    *,
    near_m: float = 0.6,
    max_lines: int = 2,
    seed: int = 0,
    lens: Lens | None = None,
    tun: FloorLineTuning | None = None,
) -> list[WallLine]:
    """The floor-wall lines in one image (up to ``max_lines``, most inliers first), FRAME_ROBOT.

    Args:
        image: ``(h, w, 3)`` BGR uint8 (a grey ``(h, w)`` image is accepted).
        hfov: Horizontal field of view, rad.
        vfov: Vertical field of view, rad.
        camera_pose: The camera's 4x4 pose in FRAME_ROBOT (NAOqi camera frame), or 16 floats.
        near_m: Floor nearer than this (from FRAME_ROBOT's origin) models the floor's colour;
            the rows looking there must be mostly floor.
        max_lines: Most lines to fit (a corner shows two walls).
        seed: Seed of RANSAC.
        lens: The camera's lens, undone before pixels become rays (None: a pinhole).
        tun: The detector's thresholds (a config's ``camera.floor_lines``; None: the
            defaults).

    Returns:
        The lines seen well enough (possibly none).

    Raises:
        FeatureError: The image or camera pose has the wrong shape.
    """
    import cv2

    tun = _DEFAULT if tun is None else tun
    img = np.asarray(image)
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
        raise FeatureError(f"floor line: expected an (h, w, 3) uint8 image, got {img.shape}")
    pose = np.asarray(camera_pose, dtype=np.float64)
    if pose.size != 16 or not np.all(np.isfinite(pose)):
        raise FeatureError("floor line: the camera pose must be 16 finite floats (4x4)")
    h, w = img.shape[:2]
    # the rows whose centre column looks at the floor between 0.25 m and near_m (pixel
    # centres at integer coordinates, as pixel_rays has them)
    origin = pose.reshape(4, 4)[:3, 3].copy()
    mid = rays_at(np.arange(h) + 0.5, np.full(h, w // 2), (w, h), hfov, vfov,
                  pose.reshape(4, 4), lens)  # fmt: skip
    centre = floor_points(np.arange(h), np.zeros(h, np.int64), origin, mid[:, None], tun=tun)
    reach = np.hypot(centre[:, 0], centre[:, 1])
    sample_rows = (reach > 0.2) & (reach < near_m)
    if sample_rows.sum() < 5:
        sample_rows = np.zeros(h, bool)
        sample_rows[int(h * 0.75) :] = True
    mask, lab, floor, threshold = floor_mask(img, sample_rows, tun=tun)
    rows, cols = boundary_pixels(mask, max(4, h // 20))
    rows = refine_boundary(lab, floor, threshold, rows, cols, max(4, h // 24), tun=tun)
    if rows.size < tun.min_inliers:
        return []
    # the foot of the wall, to a fraction of a pixel: a line nearly parallel to the image
    # rows would otherwise be quantised to whole rows (3 cm at 2 m in QVGA)
    edge = rays_at(subpixel_edges(lab, floor, rows, cols), cols, (w, h), hfov, vfov,
                   pose.reshape(4, 4), lens)  # fmt: skip
    pts = floor_points(
        np.arange(rows.size), np.zeros(rows.size, np.int64), origin, edge[:, None], tun=tun
    )
    finite = np.all(np.isfinite(pts), axis=1)
    pts, rows, cols = pts[finite], rows[finite], cols[finite]
    lines: list[WallLine] = []
    members: list[np.ndarray] = []  # each line's boundary pixels (indices into pts)
    remaining = np.arange(len(pts))
    for k in range(max_lines):
        line, inl = _one_line(pts[remaining], seed + k, tun=tun)
        if line is None:
            break
        lines.append(line)
        members.append(remaining[inl])
        remaining = remaining[~inl]
    if len(lines) == 2 and (pair := _parallel_pair(lines, tun=tun)) is not None:
        near, far = pair
        band = _ghost_band(lab, rows[members[far]], cols[members[far]], lines[near],
                           (w, h), hfov, vfov, pose.reshape(4, 4), lens, tun=tun)  # fmt: skip
        if band is not None and skirting_ghost(
            _band_colours(lab, rows[members[near]], cols[members[near]]), band, tun=tun
        ):
            del lines[far]
    return lines


def _parallel_pair(lines: list[WallLine], *, tun: FloorLineTuning) -> tuple[int, int] | None:
    """``(near, far)`` indices of two lines that could be a wall's foot and its skirting
    board's top edge (within ``tun.ghost_parallel_rad`` of parallel, the far one
    ``tun.ghost_ratio`` times as far), else None."""
    a, b = lines
    if abs(modulo2PI(a.normal - b.normal)) > tun.ghost_parallel_rad:
        return None
    near, far = (0, 1) if a.distance <= b.distance else (1, 0)
    ratio = lines[far].distance / max(lines[near].distance, 1e-9)
    return (near, far) if tun.ghost_ratio[0] <= ratio <= tun.ghost_ratio[1] else None


def _band_colours(lab: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """The colours (weighted Lab, median over the pixels) just above boundary pixels (what
    stands at the line) and just below them (the floor): ``(2, 3)``."""
    h = lab.shape[0]
    above = np.clip(rows[:, None] - np.arange(2, 5), 0, h - 1)
    below = np.clip(rows[:, None] + np.arange(2, 5), 0, h - 1)
    return np.stack([
        np.median(lab[above, cols[:, None]].reshape(-1, 3), axis=0),
        np.median(lab[below, cols[:, None]].reshape(-1, 3), axis=0),
    ])  # fmt: skip


def _ghost_band(
    lab: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    near: WallLine,
    size: tuple[int, int],
    hfov: float,
    vfov: float,
    pose: np.ndarray,
    lens: Lens | None,
    *,
    tun: FloorLineTuning,
) -> np.ndarray | None:
    """In the far line's columns (its boundary ``rows``, ``cols``): the colour between the
    far line and where the near line would meet the floor, and the colour of the floor
    nearer than that, ``(2, 3)`` (weighted Lab, medians). A column counts where the near
    line meets the floor 3 or more pixels below the far line and 3 above the image's
    bottom; None when fewer than ``tun.min_inliers // 2`` columns do (``tun``: the
    detector's thresholds)."""
    h, n = size[1], len(cols)
    below = np.arange(h)
    rays = rays_at(np.repeat(below + 0.5, n), np.tile(cols, h), size, hfov, vfov,
                   pose, lens).reshape(h, n, 3)  # fmt: skip
    xy = floor_points(np.repeat(below, n), np.tile(np.arange(n), h), pose[:3, 3], rays, tun=tun)
    normal = np.array([math.cos(near.normal), math.sin(near.normal)])
    # (h, n): the pixel's floor point is before the near line, below the far line
    nearer = ((xy @ normal) < near.distance).reshape(h, n) & (below[:, None] > rows[None, :])
    # the near line's row in each column: the first such row from the far line down
    foot = np.where(nearer.any(axis=0), np.argmax(nearer, axis=0), -1)
    ok = (foot - rows >= 3) & (foot + 3 < h)
    if ok.sum() < tun.min_inliers // 2:
        return None
    c, r, f = cols[ok], rows[ok], foot[ok]
    # the band: rows r+1 .. f-2 of each column
    inside = (below[:, None] > r[None, :]) & (below[:, None] < f[None, :] - 1)
    band = lab[:, c][inside]
    floor = lab[f[:, None] + np.arange(1, 4), c[:, None]].reshape(-1, 3)
    return np.stack([np.median(band, axis=0), np.median(floor, axis=0)])


def skirting_ghost(
    near: np.ndarray, far_band: np.ndarray, *, tun: FloorLineTuning | None = None
) -> bool:
    """Whether a farther line is a skirting board's top edge taken for the floor line.

    Where the floor's colour model takes a skirting board for floor (a grey board on a grey
    carpet, in the columns where the light makes them alike), the top of the "floor" is the
    board's top edge, 8-12 cm up the wall: projected to the floor from the camera it is a
    line parallel to the wall's foot, ``tun.ghost_ratio`` times as far. In the columns where
    the board is not taken for floor, the same image shows the foot. In the far line's
    columns, the band between it and where the near line would meet the floor is then the
    board, not floor: in a channel of colour in which the board at the near line differs
    from the floor (by ``tun.ghost_min_step`` or more), the band has moved from the floor's
    toward the board's by more than ``tun.ghost_band_share`` of the way (a board in shade
    keeps its hue and loses its lightness). A wall seen beyond a piece of furniture has
    open floor there.

    Args:
        near: The near line's colours just above and below it (:func:`_band_colours`).
        far_band: The far line's band and the floor below it (:func:`_ghost_band`).
        tun: The detector's thresholds (a config's ``camera.floor_lines``; None: the
            defaults).
    """
    tun = _DEFAULT if tun is None else tun
    board, floor = near
    axis = board - floor
    seen = np.abs(axis) >= tun.ghost_min_step  # the channels in which the board differs
    if not seen.any():
        return False
    share = (far_band[0] - far_band[1])[seen] / axis[seen]
    return float(share.max()) > tun.ghost_band_share


def _one_line(
    pts: np.ndarray, seed: int, *, tun: FloorLineTuning
) -> tuple[WallLine | None, np.ndarray]:
    """The best line through ``pts`` and its inlier mask; (None, all False) when none (a
    line needs ``tun.min_span_m`` of span and half ``tun.min_inlier_fraction`` of ``pts``)."""
    none = np.zeros(len(pts), bool)
    fit = fit_line(pts, seed, tun=tun)
    if fit is None:
        return None, none
    (point, direction), inl = fit
    p = pts[inl]
    normal = np.array([-direction[1], direction[0]])
    offset = float(point @ normal)
    if offset < 0:
        normal, offset = -normal, -offset
    along = p @ direction
    span = float(along.max() - along.min())
    fraction = float(inl.sum()) / len(pts)
    if span < tun.min_span_m or fraction < tun.min_inlier_fraction / 2:
        return None, none
    rms = float(np.sqrt(np.mean(((p - point) @ normal) ** 2)))
    side = p @ np.array([-normal[1], normal[0]])  # along the line, from the nearest point
    ends = (float(side.min()), float(side.max()))
    line = WallLine(
        offset, math.atan2(normal[1], normal[0]), int(inl.sum()), fraction, rms, span, ends
    )
    return line, inl


def detect_wall_line(
    image: np.ndarray,
    hfov: float,
    vfov: float,
    camera_pose: np.ndarray,
    *,
    expect_normal: float | None = None,
    tolerance: float = 0.5,
    seed: int = 0,
    lens: Lens | None = None,
    tun: FloorLineTuning | None = None,
) -> WallLine | None:
    """The floor-wall line nearest in direction to ``expect_normal`` (or the best one).

    Args:
        image: ``(h, w, 3)`` BGR uint8.
        hfov: Horizontal field of view, rad.
        vfov: Vertical field of view, rad.
        camera_pose: The camera's 4x4 pose in FRAME_ROBOT, or 16 floats.
        expect_normal: Expected direction of the wall's normal in FRAME_ROBOT, rad (e.g.
            ``-pi/2`` for a wall on the right); None takes the line with most inliers.
        tolerance: Largest accepted difference from ``expect_normal``, rad.
        seed: Seed of RANSAC.
        lens: The camera's lens (None: a pinhole).
        tun: The detector's thresholds (a config's ``camera.floor_lines``; None: the
            defaults).

    Returns:
        The line with at least half of the boundary pixels it was fitted among, or None.
    """
    lines = wall_line_candidates(
        image, hfov, vfov, camera_pose, expect_normal=expect_normal, tolerance=tolerance,
        seed=seed, lens=lens, tun=tun,
    )  # fmt: skip
    return lines[0] if lines else None


def wall_line_candidates(
    image: np.ndarray,
    hfov: float,
    vfov: float,
    camera_pose: np.ndarray,
    *,
    expect_normal: float | None = None,
    tolerance: float = 0.5,
    seed: int = 0,
    lens: Lens | None = None,
    tun: FloorLineTuning | None = None,
) -> list[WallLine]:
    """Every line :func:`detect_wall_line` could return, the one it returns first.

    Args: as :func:`detect_wall_line`.

    Returns:
        The lines within ``tolerance`` of ``expect_normal`` (all of them for None), most
        inliers first; a line after the image's best one needs ``tun.min_inlier_fraction``
        of the boundary pixels left to it.
    """
    tun = _DEFAULT if tun is None else tun
    lines = detect_wall_lines(image, hfov, vfov, camera_pose, seed=seed, lens=lens, tun=tun)
    if expect_normal is not None:
        lines = [ln for ln in lines if abs(modulo2PI(ln.normal - expect_normal)) <= tolerance]
    return [ln for ln in lines if ln.fraction >= tun.min_inlier_fraction or ln is lines[0]]
