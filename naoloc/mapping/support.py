"""The landmarks' vote between candidate poses, and along one axis of the room.

Where the pictures verified no pose, the floor-wall lines (:mod:`naoloc.localization.floorfix`) list
the poses the walls allow and the landmarks choose among them. Every query feature is
matched to its nearest landmark descriptors over the whole map once
(:func:`support_matches`); :func:`pose_support` counts the features a pose reprojects
within a few pixels, and :func:`axis_peaks` finds where along one axis of the wall frame the
features' bearings agree, for an axis whose wall no line saw (a wall 4 m away, or hidden
behind furniture).

All poses are robot (FRAME_ROBOT origin) poses when the LAST query was taken, map frame
(metres, radians) unless stated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.geometry import Pose2D
from naoloc.mapping.data import MapData
from naoloc.mapping.landmarks import hamming_matcher, query_camera
from naoloc.mapping.localizer import (
    SUPPORT_NEIGHBOURS,
    SUPPORT_RADIUS_PX,
    pixel_residuals,
    query_projection,
    robot_to_last,
    turn_scale_of,
)
from naoloc.mapping.vocabulary import pad_packed
from naoloc.perception.features import Features
from naoloc.robot.keyframe import Keyframe

# axis_peaks: bins along the axis (m), the window a peak sums over (bins either side), the
# narrowest angle between a feature's ray and the axis (rad; a ray along the axis says
# nothing of where on it the robot is), the nearest and farthest landmark used (m), and
# the smallest count worth a peak.
AXIS_BIN_M = 0.05
AXIS_WINDOW_BINS = 2
AXIS_MIN_ANGLE_RAD = 0.35
AXIS_RANGE_M = (0.3, 6.0)
AXIS_MIN_COUNT = 8
# Peaks along one axis are at least this far apart, m.
AXIS_PEAK_SEPARATION_M = 0.3


@dataclass(frozen=True)
class SupportMatches:
    """Every query feature's nearest landmark descriptors, ready to reproject.

    Attributes:
        points: Landmarks, (n, 3), map frame, m.
        pixels: The query feature's pixel, (n, 2).
        mats: Map point in the last query's robot frame -> the query's pixels, (n, 3, 4).
        owner: An id per query feature, (n,): a feature counts once however many of its
            landmarks agree.
        origin: Each feature's camera centre, (n, 2), the last query's robot frame, m.
        ray: Each feature's ray direction (horizontal, unit), (n, 2), same frame.
    """

    points: np.ndarray
    pixels: np.ndarray
    mats: np.ndarray
    owner: np.ndarray
    origin: np.ndarray
    ray: np.ndarray


def support_matches(
    vmap: MapData,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    *,
    neighbours: int = SUPPORT_NEIGHBOURS,
) -> SupportMatches:
    """Each query feature's ``neighbours`` nearest landmark descriptors over the whole map.

    No retrieval and no ratio test: where the scan verified nothing, retrieval picked the
    wrong places, and look-alike prints fail the ratio.

    Args:
        vmap: The map.
        feats: Features of each query, extracted with the map's extractor.
        queries: The query images (odometry poses and head angles).
        neighbours: Nearest landmark descriptors tried per feature.
    """
    points = np.asarray(vmap.kp_points, np.float64)
    known = np.flatnonzero(np.isfinite(points).all(axis=1))
    obj: list[np.ndarray] = []
    px: list[np.ndarray] = []
    mats: list[np.ndarray] = []
    owner: list[np.ndarray] = []
    if known.size:
        pts, desc = points[known], np.ascontiguousarray(vmap.kp_desc[known])
        if vmap.vocabulary.binary:
            desc = pad_packed(desc)  # once for the scan, not once per picture
        matcher = hamming_matcher(vmap.vocabulary.binary)
        to_last = robot_to_last(queries, turn_scale_of(vmap))
        first = 0
        for qi, (q, f) in enumerate(zip(queries, feats, strict=True)):
            base, first = first, first + len(f)
            if len(f) == 0:
                continue
            _dist, nearest = matcher.knn(f.descriptors, desc, neighbours)
            pairs = np.column_stack(
                [np.repeat(np.arange(len(f)), nearest.shape[1]), nearest.ravel()]
            )
            if pairs.size == 0:
                continue
            m_q = query_projection(query_camera(q).matrix(), q.camera_matrix(), to_last[qi])
            obj.append(pts[pairs[:, 1]])
            px.append(f.xy[pairs[:, 0]].astype(np.float64))
            mats.append(np.repeat(m_q[None], len(pairs), axis=0))
            owner.append(base + pairs[:, 0])
    if not obj:
        empty = np.zeros((0, 2))
        return SupportMatches(
            np.zeros((0, 3)), empty, np.zeros((0, 3, 4)), np.zeros(0, np.int64), empty, empty
        )
    o, u, mm, who = (np.concatenate(v) for v in (obj, px, mats, owner))
    # The pixel's ray: A p + b ~ (u, v, 1) for a point p of the last query's robot frame.
    a_inv = np.linalg.inv(mm[:, :, :3])
    origin = -np.einsum("nij,nj->ni", a_inv, mm[:, :, 3])[:, :2]
    ray = np.einsum("nij,nj->ni", a_inv, np.column_stack([u, np.ones(len(u))]))[:, :2]
    norm = np.linalg.norm(ray, axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        ray = np.where(norm > 1e-9, ray / norm, 0.0)
    return SupportMatches(o, u, mm, who, origin, ray)


def pose_support(
    vmap: MapData,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    poses: Sequence[Pose2D],
    *,
    neighbours: int = SUPPORT_NEIGHBOURS,
    radius_px: float = SUPPORT_RADIUS_PX,
    matches: SupportMatches | None = None,
) -> list[int]:
    """How many query features each candidate pose explains: a vote between poses found
    another way (the floor-wall lines) where no pose had enough matches to be verified.

    A feature supports a pose when one of its landmarks (:func:`support_matches`)
    reprojects within ``radius_px`` of it from there. Measured at 14 floor-line scans of
    room 1595909956, the candidate nearest the truth got the most support every time,
    1.2-10x the next (docs/RESULTS.md, "Issue 12, fifth step").

    Args:
        vmap: The map.
        feats: Features of each query, extracted with the map's extractor.
        queries: The query images (odometry poses and head angles).
        poses: Candidate robot poses when the last query was taken, map frame.
        neighbours: Nearest landmark descriptors tried per feature.
        radius_px: Reprojection tolerance, pixels.
        matches: The features' matches, when already found (saves matching again).
    """
    if not poses:
        return []
    m = matches if matches is not None else support_matches(
        vmap, feats, queries, neighbours=neighbours
    )  # fmt: skip
    if m.owner.size == 0:
        return [0] * len(poses)
    return [
        int(np.unique(m.owner[pixel_residuals(np.array(p.to_list()), m.mats, m.points, m.pixels)
                               < radius_px]).size)
        for p in poses
    ]  # fmt: skip


def axis_peaks(
    matches: SupportMatches,
    frame: Pose2D,
    theta: float,
    axis: int,
    fixed: float,
    span: tuple[float, float],
    *,
    peaks: int = 2,
) -> list[tuple[float, int]]:
    """Where along one axis of ``frame`` the features' bearings agree on the robot.

    With the heading and the other coordinate known (the floor lines give them), each
    feature's ray must pass through its landmark: that puts the robot at one place on the
    axis. Places where many features agree are peaks; wrong matches scatter. Only the
    horizontal bearing is used, so a peak is a candidate for :func:`pose_support` to
    verify, not a pose.

    Args:
        matches: The features' matches (:func:`support_matches`).
        frame: The frame the axis belongs to (the wall frame W) in the map frame.
        theta: The robot's heading in ``frame``, rad.
        axis: 0 to solve the robot's x in ``frame`` (y fixed), 1 to solve y (x fixed).
        fixed: The other coordinate in ``frame``, m.
        span: The part of the axis to search, ``(low, high)`` in ``frame``, m.
        peaks: At most this many peaks, at least :data:`AXIS_PEAK_SEPARATION_M` apart.

    Returns:
        ``(coordinate in frame, features agreeing)`` per peak, best first; empty when no
        place gets :data:`AXIS_MIN_COUNT` features.
    """
    lo, hi = span
    if matches.owner.size == 0 or not hi > lo:
        return []
    inv = frame.inverse()
    c, s = math.cos(inv.theta), math.sin(inv.theta)
    p = matches.points[:, :2] @ np.array([[c, s], [-s, c]]) + (inv.x, inv.y)  # in frame
    ct, st = math.cos(theta), math.sin(theta)
    rot = np.array([[ct, st], [-st, ct]])  # row vectors: v @ rot = R(theta) v
    off, ray = matches.origin @ rot, matches.ray @ rot  # camera offset and ray, in frame
    other = 1 - axis
    along, across = ray[:, axis], ray[:, other]
    ok = np.abs(across) >= math.sin(AXIS_MIN_ANGLE_RAD)
    with np.errstate(divide="ignore", invalid="ignore"):
        # The ray from (robot + off) along `ray` meets the landmark: solve the robot's axis.
        coord = p[:, axis] - off[:, axis] - (p[:, other] - fixed - off[:, other]) * along / across
    centre = np.empty_like(p)
    centre[:, axis], centre[:, other] = coord + off[:, axis], fixed + off[:, other]
    ahead = ((p - centre) * ray).sum(axis=1)
    ok &= np.isfinite(coord) & (coord >= lo) & (coord <= hi)
    ok &= (ahead >= AXIS_RANGE_M[0]) & (ahead <= AXIS_RANGE_M[1])
    if not ok.any():
        return []
    coord, owner = coord[ok], matches.owner[ok]
    n_bins = math.ceil((hi - lo) / AXIS_BIN_M) + 1
    bins = np.clip(((coord - lo) / AXIS_BIN_M).astype(np.int64), 0, n_bins - 1)
    pairs = np.unique(owner * n_bins + bins)  # a feature counts once per bin
    hist = np.bincount(pairs % n_bins, minlength=n_bins).astype(np.float64)
    window = np.convolve(hist, np.ones(2 * AXIS_WINDOW_BINS + 1), mode="same")
    out: list[tuple[float, int]] = []
    sep = round(AXIS_PEAK_SEPARATION_M / AXIS_BIN_M)
    while len(out) < peaks:
        i = int(np.argmax(window))
        if window[i] < AXIS_MIN_COUNT:
            break
        near = np.abs(bins - i) <= AXIS_WINDOW_BINS
        out.append((float(np.median(coord[near])), int(np.unique(owner[near]).size)))
        window[max(0, i - sep) : i + sep + 1] = -1.0
    return out
