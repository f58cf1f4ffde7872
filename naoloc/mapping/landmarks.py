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

from naoloc.config import LandmarkTuning
from naoloc.geometry import planar_pose, robot_matrix
from naoloc.mapping.vocabulary import pad_packed
from naoloc.robot.keyframe import CameraInfo, Keyframe, camera_in_robot

__all__ = [
    "DescriptorMatcher",
    "LandmarkSet",
    "camera_matrix_in_map",
    "camera_poses",
    "hamming_matcher",
    "planar_pose",
    "query_camera",
    "ratio_matches",
    "robot_matrix",
    "select_pairs",
    "triangulate",
]

DEFAULT = LandmarkTuning()


def camera_matrix_in_map(
    pose: Sequence[float], head_yaw: float, head_pitch: float, index: int = 0
) -> np.ndarray:
    """``T_map_cam`` (4x4): the camera's optical frame in the map frame."""
    return robot_matrix(*pose) @ camera_in_robot(head_yaw, head_pitch, index)


def query_camera(kf: Keyframe) -> CameraInfo:
    """The keyframe's camera model at the keyframe's actual image size."""
    h, w = kf.image.shape[:2]
    cam = kf.camera
    return cam if (cam.width, cam.height) == (w, h) else cam.scaled(w, h)


def camera_poses(poses: np.ndarray, heads: np.ndarray, cam_index: Sequence[int]) -> np.ndarray:
    """``(N, 4, 4)`` ``T_map_cam`` of keyframes with robot poses ``poses`` (map frame).

    Args:
        poses: ``(N, 3)`` robot poses (m, m, rad).
        heads: ``(N, 2)`` HeadYaw, HeadPitch (rad).
        cam_index: Per keyframe camera index.
    """
    return np.stack(
        [
            camera_matrix_in_map(poses[i], heads[i, 0], heads[i, 1], cam_index[i])
            for i in range(poses.shape[0])
        ]
    )


@dataclass(frozen=True)
class DescriptorMatcher:
    """Brute-force nearest descriptors: Hamming for binary descriptors, L2 otherwise.

    Attributes:
        binary: Whether the descriptors are binary (uint8 bit strings).
    """

    binary: bool

    def knn(self, query: np.ndarray, train: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Each query row's ``k`` nearest train rows, nearest first.

        Args:
            query: ``(n, d)`` descriptors.
            train: ``(m, d)`` descriptors.
            k: Neighbours per query row.

        Returns:
            ``(distances (n, k'), indices (n, k'))`` with ``k' = min(k, m)``: Hamming bit
            counts (binary) or L2 distances, and the train rows (int64); the same as
            OpenCV's ``BFMatcher.knnMatch``, whose ranking (ties included) it uses.
        """
        import cv2

        kk = min(k, train.shape[0])
        n = query.shape[0]
        if n == 0 or kk == 0:
            return np.zeros((n, kk)), np.zeros((n, kk), np.int64)
        if self.binary:
            q, t = pad_packed(query), pad_packed(train)
            norm, dtype = cv2.NORM_HAMMING, cv2.CV_32S
        else:
            q, t = np.asarray(query, np.float32), np.asarray(train, np.float32)
            norm, dtype = cv2.NORM_L2, cv2.CV_32F
        dist, idx = cv2.batchDistance(q, t, dtype, normType=norm, K=kk)
        return dist.astype(np.float64), idx.astype(np.int64)


def hamming_matcher(binary: bool) -> DescriptorMatcher:
    """A brute-force matcher for the descriptor kind (Hamming when ``binary``)."""
    return DescriptorMatcher(binary)


def ratio_matches(
    matcher: DescriptorMatcher,
    query: np.ndarray,
    train: np.ndarray,
    ratio: float = DEFAULT.ratio_test,
) -> np.ndarray:
    """Lowe-ratio-tested nearest-neighbour matches ``(m, 2)``: query index, train index.

    One-to-one: when several query keypoints pick the same train keypoint, only the closest
    is kept (the first of equally close ones; a train image with few keypoints otherwise
    "matches" a whole query image). Rows are sorted by query index.
    """
    if query.shape[0] == 0 or train.shape[0] < 2:
        return np.zeros((0, 2), np.int64)
    dist, idx = matcher.knn(query, train, 2)
    qi = np.flatnonzero(dist[:, 0] < ratio * dist[:, 1])
    if qi.size == 0:
        return np.zeros((0, 2), np.int64)
    ti, d = idx[qi, 0], dist[qi, 0]
    order = np.lexsort((qi, d, ti))  # by train row, then distance, then query row
    ti_sorted = ti[order]
    first = np.ones(order.size, bool)
    first[1:] = ti_sorted[1:] != ti_sorted[:-1]
    pos = order[first]
    pos = pos[np.argsort(qi[pos])]
    return np.column_stack([qi[pos], ti[pos]]).astype(np.int64)


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


# Pairs of far pictures (the survey's views across the room, walls 2-7 m away): baselines
# 0.6-2 m, views within 30 deg. The wall pictures' nearest neighbours (0.2-0.4 m) would
# place a point 5 m away to +-0.4 m per pixel of error; spread up to 2 m apart, to a few cm.
FAR_BASELINE_M = (0.6, 2.0)
FAR_VIEW_DEG = 30.0


def select_pairs(
    cams: np.ndarray, tuning: LandmarkTuning = DEFAULT, far_from: int | None = None
) -> list[tuple[int, int]]:
    """Keyframe pairs with a usable baseline and overlapping views.

    A wall picture pairs with its nearest wall pictures; a far picture (index ``far_from``
    on) with far pictures :data:`FAR_BASELINE_M` apart, spread over that range.

    Args:
        cams: ``(N, 4, 4)`` camera poses ``T_map_cam``.
        tuning: Baseline and view-angle limits (wall pictures).
        far_from: Index of the first far picture (they follow the wall pictures); None:
            none.

    Returns:
        Sorted unique pairs ``(i, j)``, i < j; up to ``pairs_per_keyframe`` per keyframe.
    """
    centres = cams[:, :3, 3]
    views = cams[:, :3, 2]
    dist = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2)
    cosang = np.clip(views @ views.T, -1.0, 1.0)
    ok = (
        (dist >= tuning.pair_min_baseline_m)
        & (dist <= tuning.pair_max_baseline_m)
        & (cosang >= math.cos(math.radians(tuning.pair_max_view_angle_deg)))
    )
    pairs: set[tuple[int, int]] = set()
    n = cams.shape[0]
    first_far = n if far_from is None else far_from
    for i in range(first_far):
        cand = np.flatnonzero(ok[i, :first_far])
        for j in cand[np.argsort(dist[i, cand], kind="stable")][: tuning.pairs_per_keyframe]:
            pairs.add((min(i, int(j)), max(i, int(j))))
    far_ok = (
        (dist >= FAR_BASELINE_M[0])
        & (dist <= FAR_BASELINE_M[1])
        & (cosang >= math.cos(math.radians(FAR_VIEW_DEG)))
    )
    for i in range(first_far, n):
        cand = np.flatnonzero(far_ok[i, first_far:]) + first_far
        if cand.size == 0:
            continue
        order = cand[np.argsort(dist[i, cand], kind="stable")]
        k = min(tuning.pairs_per_keyframe, order.size)
        for j in order[np.linspace(0, order.size - 1, k).round().astype(int)]:
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
    tuning: LandmarkTuning = DEFAULT,
    far_from: int | None = None,
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
        tuning: Matching and triangulation thresholds.
        far_from: Index of the first far picture, for :func:`select_pairs`.

    Returns:
        The landmarks, one row per keypoint of every keyframe.
    """
    import cv2

    offsets = np.concatenate([[0], np.cumsum([a.shape[0] for a in xy])]).astype(np.int64)
    sums = np.zeros((int(offsets[-1]), 3))
    counts = np.zeros(int(offsets[-1]))
    linked: list[np.ndarray] = []
    matcher = hamming_matcher(binary)
    pairs = select_pairs(cams, tuning, far_from) if pairs is None else list(pairs)
    lo_m, hi_m = tuning.depth_range_m
    projs = [_projection(intrinsics[i], cams[i]) for i in range(cams.shape[0])]
    for i, j in pairs:
        m = ratio_matches(matcher, desc[i], desc[j], tuning.ratio_test)
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
        keep = dist < tuning.epipolar_px
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
            & (err < tuning.max_reprojection_px)
            & (za > lo_m)
            & (zb > lo_m)
            & (za < hi_m)
            & (zb < hi_m)
            & (cosp < math.cos(math.radians(tuning.min_parallax_deg)))
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
