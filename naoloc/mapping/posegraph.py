"""Survey pose refinement: odometry fused with visual loop closures in a 2-D pose graph.

Odometry drifts (scale, heading bias, noise), so the survey's second lap does not land on
the first and the map blurs. Here each keyframe's triangulated landmarks (from temporally
adjacent keyframes only, where odometry is locally exact enough) are matched from
keyframes of other laps that look alike (TF-IDF retrieval); PnP gives the relative pose
between the two keyframes. Odometry edges plus these loop-closure edges are then solved
by Gauss-Newton on (x, y, theta) per keyframe with the first keyframe held fixed, which
keeps the map frame (the odometry frame at the survey start).

Frames: all poses are robot poses in the map frame (m, rad).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.keyframe import camera_in_robot
from naoloc.mapping.landmarks import (
    camera_matrix_in_map,
    hamming_matcher,
    planar_pose,
    ratio_matches,
    robot_matrix,
    triangulate,
)
from naoloc.mapping.vocabulary import dbow_scores

LOCAL_WINDOW = 3  # keyframes either side used to triangulate a keyframe's landmarks
LOOP_MIN_GAP = 6  # keyframes closer in time than this are tied by odometry only
LOOP_CANDIDATES = 3  # retrieval candidates per keyframe
LOOP_MIN_INLIERS = 15
SIGMA_ODO_XY = (0.01, 0.03)  # m: constant, per metre travelled
SIGMA_ODO_TH = (0.005, 0.02, 0.01)  # rad: constant, per rad turned, per metre travelled
SIGMA_LOOP_XY = 0.03  # m
SIGMA_LOOP_TH = 0.01  # rad


@dataclass(frozen=True)
class RefinedPoses:
    """Result of :func:`refine_poses`.

    Attributes:
        poses: ``(N, 3)`` refined keyframe poses (map frame).
        loops: Loop-closure edges kept.
        shift_m: Largest position change from the odometry poses, metres.
    """

    poses: np.ndarray
    loops: int
    shift_m: float


def _v2t(p: np.ndarray) -> np.ndarray:
    c, s = math.cos(p[2]), math.sin(p[2])
    return np.array([[c, -s, p[0]], [s, c, p[1]], [0.0, 0.0, 1.0]])


def _t2v(t: np.ndarray) -> np.ndarray:
    return np.array([t[0, 2], t[1, 2], math.atan2(t[1, 0], t[0, 0])])


def _relative(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return _t2v(np.linalg.inv(_v2t(a)) @ _v2t(b))


def solve_pose_graph(
    init: np.ndarray, edges: Sequence[tuple[int, int, np.ndarray, np.ndarray]], iterations: int = 10
) -> np.ndarray:
    """Gauss-Newton on a 2-D pose graph, node 0 fixed.

    Args:
        init: ``(N, 3)`` initial poses.
        edges: ``(a, b, z, info)``: measured pose of b in a's frame and its 3x3 information.
        iterations: Gauss-Newton iterations at most.

    Returns:
        ``(N, 3)`` optimised poses.
    """
    x = init.astype(np.float64).copy()
    n = x.shape[0]
    for _ in range(iterations):
        h = np.zeros((3 * n, 3 * n))
        g = np.zeros(3 * n)
        for a, b, z, info in edges:
            ca, sa = math.cos(x[a, 2]), math.sin(x[a, 2])
            rat = np.array([[ca, sa], [-sa, ca]])  # R_a^T
            drat = np.array([[-sa, ca], [-ca, -sa]])  # d R_a^T / d theta_a
            cz, sz = math.cos(z[2]), math.sin(z[2])
            rzt = np.array([[cz, sz], [-sz, cz]])
            dt = x[b, :2] - x[a, :2]
            e = np.empty(3)
            e[:2] = rzt @ (rat @ dt - z[:2])
            e[2] = math.remainder(x[b, 2] - x[a, 2] - z[2], 2.0 * math.pi)
            ja = np.zeros((3, 3))
            ja[:2, :2] = -rzt @ rat
            ja[:2, 2] = rzt @ drat @ dt
            ja[2, 2] = -1.0
            jb = np.zeros((3, 3))
            jb[:2, :2] = rzt @ rat
            jb[2, 2] = 1.0
            ia, ib = slice(3 * a, 3 * a + 3), slice(3 * b, 3 * b + 3)
            h[ia, ia] += ja.T @ info @ ja
            h[ia, ib] += ja.T @ info @ jb
            h[ib, ia] += jb.T @ info @ ja
            h[ib, ib] += jb.T @ info @ jb
            g[ia] += ja.T @ info @ e
            g[ib] += jb.T @ info @ e
        h[:3, :3] += np.eye(3) * 1e9  # hold node 0
        try:
            dx = np.linalg.solve(h + np.eye(3 * n) * 1e-9, -g)
        except np.linalg.LinAlgError:
            break
        x += dx.reshape(n, 3)
        if np.abs(dx).max() < 1e-7:
            break
    return x


def _odometry_info(z: np.ndarray) -> np.ndarray:
    dist = math.hypot(z[0], z[1])
    sxy = SIGMA_ODO_XY[0] + SIGMA_ODO_XY[1] * dist
    sth = SIGMA_ODO_TH[0] + SIGMA_ODO_TH[1] * abs(z[2]) + SIGMA_ODO_TH[2] * dist
    return np.diag([1 / sxy**2, 1 / sxy**2, 1 / sth**2])


def refine_poses(
    poses: np.ndarray,
    heads: np.ndarray,
    xy: Sequence[np.ndarray],
    desc: Sequence[np.ndarray],
    intrinsics: Sequence[np.ndarray],
    cam_index: Sequence[int],
    histograms: np.ndarray,
    binary: bool,
) -> RefinedPoses:
    """Refine survey keyframe poses with visual loop closures (see module docstring).

    Args:
        poses: ``(N, 3)`` odometry poses in capture order (map frame).
        heads: ``(N, 2)`` HeadYaw, HeadPitch (rad).
        xy: Per keyframe keypoint pixels.
        desc: Per keyframe descriptors.
        intrinsics: Per keyframe 3x3 K.
        cam_index: Per keyframe camera index.
        histograms: ``(N, V)`` TF-IDF histograms for retrieval.
        binary: Hamming (True) or L2 descriptors.

    Returns:
        The refined poses (the odometry poses when no loop closure is found).
    """
    import cv2

    n = poses.shape[0]
    cams = np.stack(
        [camera_matrix_in_map(poses[i], heads[i, 0], heads[i, 1], cam_index[i]) for i in range(n)]
    )
    local = [(i, j) for i in range(n) for j in range(i + 1, min(n, i + LOCAL_WINDOW + 1))]
    lm = triangulate(xy, desc, cams, intrinsics, binary, pairs=local)
    offsets = np.concatenate([[0], np.cumsum([a.shape[0] for a in xy])]).astype(np.int64)
    matcher = hamming_matcher(binary)
    edges: list[tuple[int, int, np.ndarray, np.ndarray]] = []
    for i in range(n - 1):
        z = _relative(poses[i], poses[i + 1])
        edges.append((i, i + 1, z, _odometry_info(z)))
    tried: set[tuple[int, int]] = set()
    loops = 0
    for j in range(n):
        scores = dbow_scores(histograms[j], histograms)
        scores[max(0, j - LOOP_MIN_GAP + 1) : j + LOOP_MIN_GAP] = -1.0
        for i in np.argsort(-scores, kind="stable")[:LOOP_CANDIDATES].tolist():
            if scores[i] <= 0 or (min(i, j), max(i, j)) in tried:
                continue
            tried.add((min(i, j), max(i, j)))
            pts_i = lm.points[offsets[i] : offsets[i + 1]]
            m = ratio_matches(matcher, desc[j], desc[i])
            if m.shape[0] < LOOP_MIN_INLIERS:
                continue
            obj_map = pts_i[m[:, 1]]
            ok_pts = np.isfinite(obj_map[:, 0])
            if ok_pts.sum() < LOOP_MIN_INLIERS:
                continue
            t_ri_map = np.linalg.inv(robot_matrix(*poses[i]))
            obj = obj_map[ok_pts] @ t_ri_map[:3, :3].T + t_ri_map[:3, 3]
            img = xy[j][m[ok_pts, 0]].astype(np.float64)
            try:
                ok, rvec, tvec, inl = cv2.solvePnPRansac(
                    obj,
                    img,
                    intrinsics[j],
                    None,
                    iterationsCount=200,
                    reprojectionError=3.0,
                    confidence=0.999,
                    flags=cv2.SOLVEPNP_SQPNP,
                )
            except cv2.error:
                continue
            if not ok or inl is None or len(inl) < LOOP_MIN_INLIERS:
                continue
            rot, _ = cv2.Rodrigues(rvec)
            t_cam_ri = np.eye(4)
            t_cam_ri[:3, :3], t_cam_ri[:3, 3] = rot, tvec.ravel()
            c_j = camera_in_robot(float(heads[j, 0]), float(heads[j, 1]), cam_index[j])
            t_ri_rj = np.linalg.inv(t_cam_ri) @ np.linalg.inv(c_j)
            if abs(t_ri_rj[2, 3]) > 0.1:  # both robots stand on the same floor
                continue
            z = np.array(planar_pose(t_ri_rj))
            info = np.diag([1 / SIGMA_LOOP_XY**2, 1 / SIGMA_LOOP_XY**2, 1 / SIGMA_LOOP_TH**2])
            edges.append((i, j, z, info))
            loops += 1
    if loops == 0:
        return RefinedPoses(poses.copy(), 0, 0.0)
    refined = solve_pose_graph(poses, edges)
    # Drop loop closures that disagree with the solution (wrong matches), solve again.
    kept = edges[: n - 1]
    for a, b, z, info in edges[n - 1 :]:
        e = _relative(refined[a], refined[b]) - z
        e[2] = math.remainder(e[2], 2.0 * math.pi)
        if float(e @ info @ e) < 9.0 * 3:
            kept.append((a, b, z, info))
    if len(kept) < len(edges):
        refined = solve_pose_graph(poses, kept)
    shift = float(np.max(np.hypot(*(refined[:, :2] - poses[:, :2]).T)))
    return RefinedPoses(refined, len(kept) - (n - 1), shift)
