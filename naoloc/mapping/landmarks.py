"""3-D landmarks: camera poses of keyframes and triangulation between nearby keyframes.

Frames: the map frame is 3-D here (x forward, y left, z up from the floor, metres); a
robot pose (x, y, theta) in the map frame is the rigid transform ``T_map_robot``; the
camera's optical frame (OpenCV: z along the view, x right, y down) sits at
``T_map_robot @ camera_in_robot(head_yaw, head_pitch, index)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from naoloc.keyframe import camera_in_robot

# Pair selection: camera centres this far apart (m) and views within this angle (rad).
PAIR_MIN_BASELINE_M = 0.05
PAIR_MAX_BASELINE_M = 1.2
PAIR_MAX_VIEW_ANGLE = math.radians(50.0)
PAIRS_PER_KEYFRAME = 4
RATIO_TEST = 0.8
MAX_REPROJECTION_PX = 2.0
EPIPOLAR_PX = 3.0
MIN_PARALLAX_RAD = math.radians(1.0)
DEPTH_RANGE_M = (0.15, 12.0)


def robot_matrix(x: float, y: float, theta: float) -> np.ndarray:
    """``T_map_robot`` (4x4) of a planar robot pose in the map frame."""
    c, s = math.cos(theta), math.sin(theta)
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    t[0, 3], t[1, 3] = x, y
    return t


def camera_matrix_in_map(
    pose: Sequence[float], head_yaw: float, head_pitch: float, index: int = 0
) -> np.ndarray:
    """``T_map_cam`` (4x4): the camera's optical frame in the map frame."""
    return robot_matrix(*pose) @ camera_in_robot(head_yaw, head_pitch, index)


def planar_pose(t_map_robot: np.ndarray) -> tuple[float, float, float]:
    """(x, y, theta) of a 4x4 robot transform projected on the floor (m, m, rad)."""
    return (
        float(t_map_robot[0, 3]),
        float(t_map_robot[1, 3]),
        math.atan2(float(t_map_robot[1, 0]), float(t_map_robot[0, 0])),
    )


def hamming_matcher(binary: bool) -> object:
    """A brute-force OpenCV matcher for the descriptor kind."""
    import cv2

    return cv2.BFMatcher(cv2.NORM_HAMMING if binary else cv2.NORM_L2)


def ratio_matches(
    matcher: object, query: np.ndarray, train: np.ndarray, ratio: float = RATIO_TEST
) -> np.ndarray:
    """Lowe-ratio-tested nearest-neighbour matches ``(m, 2)``: query index, train index.

    One-to-one: when several query keypoints pick the same train keypoint, only the closest
    is kept (a train image with few keypoints otherwise "matches" a whole query image).
    """
    if query.shape[0] == 0 or train.shape[0] < 2:
        return np.zeros((0, 2), np.int64)
    knn = matcher.knnMatch(query, train, k=2)  # type: ignore[attr-defined]
    best: dict[int, tuple[float, int]] = {}
    for m in knn:
        if len(m) == 2 and m[0].distance < ratio * m[1].distance:
            held = best.get(m[0].trainIdx)
            if held is None or m[0].distance < held[0]:
                best[m[0].trainIdx] = (m[0].distance, m[0].queryIdx)
    pairs = sorted((q, t) for t, (_d, q) in best.items())
    return np.asarray(pairs, dtype=np.int64).reshape(-1, 2)


@dataclass(frozen=True)
class LandmarkSet:
    """Triangulated points attached to keyframe keypoints.

    Attributes:
        points: ``(n_total, 3)`` float64 map-frame position of each keypoint of every
            keyframe (rows concatenated in keyframe order); NaN where none was triangulated.
        pairs: Keyframe pairs that were matched.
        matches: ``(K, 2)`` int64 row indices (into ``points``) of the keypoint pairs that
            were triangulated; they link keypoints into tracks.
    """

    points: np.ndarray
    pairs: int
    matches: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))


def select_pairs(cams: np.ndarray) -> list[tuple[int, int]]:
    """Keyframe pairs with a usable baseline and overlapping views.

    Args:
        cams: ``(N, 4, 4)`` camera poses ``T_map_cam``.

    Returns:
        Sorted unique pairs ``(i, j)``, i < j; up to PAIRS_PER_KEYFRAME per keyframe.
    """
    centres = cams[:, :3, 3]
    views = cams[:, :3, 2]
    dist = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2)
    cosang = np.clip(views @ views.T, -1.0, 1.0)
    ok = (
        (dist >= PAIR_MIN_BASELINE_M)
        & (dist <= PAIR_MAX_BASELINE_M)
        & (cosang >= math.cos(PAIR_MAX_VIEW_ANGLE))
    )
    pairs: set[tuple[int, int]] = set()
    for i in range(cams.shape[0]):
        cand = np.flatnonzero(ok[i])
        for j in cand[np.argsort(dist[i, cand], kind="stable")][:PAIRS_PER_KEYFRAME]:
            pairs.add((min(i, int(j)), max(i, int(j))))
    return sorted(pairs)


def _projection(k: np.ndarray, t_map_cam: np.ndarray) -> np.ndarray:
    t_cam_map = np.linalg.inv(t_map_cam)
    return k @ t_cam_map[:3, :]


def _reproject(p: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = p @ np.vstack([pts.T, np.ones(pts.shape[0])])
    return (h[:2] / h[2]).T, h[2]


def triangulate(
    xy: Sequence[np.ndarray],
    desc: Sequence[np.ndarray],
    cams: np.ndarray,
    intrinsics: Sequence[np.ndarray],
    binary: bool,
    pairs: Sequence[tuple[int, int]] | None = None,
) -> LandmarkSet:
    """Triangulate landmarks from features matched between nearby keyframes.

    Matches pass a ratio test, the epipolar constraint of the odometry poses, a
    reprojection check in both views, a depth range and a minimum parallax; a keypoint
    triangulated in several pairs keeps the mean of its points.

    Args:
        xy: Per keyframe ``(n_i, 2)`` keypoint pixels.
        desc: Per keyframe ``(n_i, d)`` descriptors.
        cams: ``(N, 4, 4)`` ``T_map_cam`` of every keyframe.
        intrinsics: Per keyframe 3x3 K.
        binary: Hamming (True) or L2 matching.
        pairs: Keyframe pairs to match; default: :func:`select_pairs` of the cameras.

    Returns:
        The landmarks, one row per keypoint of every keyframe.
    """
    import cv2

    offsets = np.concatenate([[0], np.cumsum([a.shape[0] for a in xy])]).astype(np.int64)
    sums = np.zeros((int(offsets[-1]), 3))
    counts = np.zeros(int(offsets[-1]))
    linked: list[np.ndarray] = []
    matcher = hamming_matcher(binary)
    pairs = select_pairs(cams) if pairs is None else list(pairs)
    projs = [_projection(intrinsics[i], cams[i]) for i in range(cams.shape[0])]
    for i, j in pairs:
        m = ratio_matches(matcher, desc[i], desc[j])
        if m.shape[0] < 5:
            continue
        a = xy[i][m[:, 0]].astype(np.float64)
        b = xy[j][m[:, 1]].astype(np.float64)
        # Epipolar gate from the odometry poses: F = K_j^-T [t]x R K_i^-1 (cam i -> cam j).
        t_ji = np.linalg.inv(cams[j]) @ cams[i]
        r, t = t_ji[:3, :3], t_ji[:3, 3]
        tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
        f = np.linalg.inv(intrinsics[j]).T @ tx @ r @ np.linalg.inv(intrinsics[i])
        ah = np.hstack([a, np.ones((a.shape[0], 1))])
        bh = np.hstack([b, np.ones((b.shape[0], 1))])
        lines = ah @ f.T
        dist = np.abs(np.einsum("ij,ij->i", bh, lines)) / np.maximum(
            np.hypot(lines[:, 0], lines[:, 1]), 1e-12
        )
        keep = dist < EPIPOLAR_PX
        if keep.sum() < 5:
            continue
        m, a, b = m[keep], a[keep], b[keep]
        hom = cv2.triangulatePoints(projs[i], projs[j], a.T, b.T)
        with np.errstate(divide="ignore", invalid="ignore"):
            pts = (hom[:3] / hom[3]).T
        ra, za = _reproject(projs[i], pts)
        rb, zb = _reproject(projs[j], pts)
        err = np.maximum(np.linalg.norm(ra - a, axis=1), np.linalg.norm(rb - b, axis=1))
        ci, cj = cams[i][:3, 3], cams[j][:3, 3]
        va, vb = pts - ci, pts - cj
        cosp = np.einsum("ij,ij->i", va, vb) / np.maximum(
            np.linalg.norm(va, axis=1) * np.linalg.norm(vb, axis=1), 1e-12
        )
        good = (
            np.isfinite(pts).all(axis=1)
            & (err < MAX_REPROJECTION_PX)
            & (za > DEPTH_RANGE_M[0])
            & (zb > DEPTH_RANGE_M[0])
            & (za < DEPTH_RANGE_M[1])
            & (zb < DEPTH_RANGE_M[1])
            & (cosp < math.cos(MIN_PARALLAX_RAD))
        )
        for col, kf in ((0, i), (1, j)):
            rows = offsets[kf] + m[good, col]
            np.add.at(sums, rows, pts[good])
            np.add.at(counts, rows, 1.0)
        linked.append(np.stack([offsets[i] + m[good, 0], offsets[j] + m[good, 1]], axis=1))
    points = np.full_like(sums, np.nan)
    has = counts > 0
    points[has] = sums[has] / counts[has, None]
    links = np.concatenate(linked).astype(np.int64) if linked else np.zeros((0, 2), np.int64)
    return LandmarkSet(points, len(pairs), links)
