"""Bundle adjustment of planar keyframe poses with 3-D landmarks, odometry and loop edges.

After the pose graph (naoloc.mapping.posegraph) the landmarks are triangulated again from
the refined poses, linked into tracks (a keypoint matched in several keyframe pairs,
including pairs from different laps, is one 3-D point), and keyframe poses (x, y, theta),
points and the odometry heading bias are refined together: pixel reprojection errors
(Huber loss) plus the pose-graph edges. The points are eliminated by the Schur complement
(3x3 blocks), so each Levenberg-Marquardt step solves a dense ``3N + 1`` system. Keyframe 0
is held fixed (the map frame stays the odometry frame at the survey start); the scale comes
from odometry.

Frames: poses in the map frame (m, rad); points in the 3-D map frame (x, y, z up, m);
pixels in the keyframe's image.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.keyframe import camera_in_robot
from naoloc.mapping.posegraph import Edge, graph_cost, graph_system

PIXEL_SIGMA = 1.0  # px
HUBER_PX = 2.0  # px: reprojection errors beyond this get a linear loss
MAX_ERROR_PX = 8.0  # observations beyond this after an iteration are dropped
MIN_TRACK = 2
LONG_TRACK_GAP = 6


@dataclass(frozen=True)
class BundleResult:
    """Result of :func:`bundle_adjust`.

    Attributes:
        poses: ``(N, 3)`` refined keyframe poses (map frame).
        heading_bias: Odometry heading bias (rad per metre walked).
        tracks: Tracks (3-D points) used.
        observations: Pixel observations used at the end.
        rms_px: Root-mean-square reprojection error of those observations at the end.
        long_tracks: Tracks seen by keyframes at least ``long_gap`` captures apart (with
            about half a lap, they tie the laps together).
    """

    poses: np.ndarray
    heading_bias: float
    tracks: int
    observations: int
    rms_px: float
    long_tracks: int = 0


def tracks_from_links(n_keypoints: int, links: np.ndarray) -> np.ndarray:
    """Connected components of keypoints linked by matches.

    Args:
        n_keypoints: Number of keypoints (rows).
        links: ``(K, 2)`` linked row pairs.

    Returns:
        ``(n_keypoints,)`` int64 component label (the smallest row of the component) for
        linked keypoints, -1 for the others.
    """
    lab = np.arange(n_keypoints, dtype=np.int64)
    if links.size == 0:
        return np.full(n_keypoints, -1, np.int64)
    a, b = links[:, 0], links[:, 1]
    while True:
        m = np.minimum(lab[a], lab[b])
        before = lab.copy()
        np.minimum.at(lab, a, m)
        np.minimum.at(lab, b, m)
        lab = lab[lab]  # pointer jumping
        if np.array_equal(lab, before):
            break
    out = np.full(n_keypoints, -1, np.int64)
    linked = np.zeros(n_keypoints, bool)
    linked[a] = True
    linked[b] = True
    out[linked] = lab[linked]
    return out


def _robot_rot(theta: np.ndarray) -> np.ndarray:
    """``(n, 3, 3)`` rotations about z."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.zeros((theta.size, 3, 3))
    r[:, 0, 0], r[:, 0, 1], r[:, 1, 0], r[:, 1, 1], r[:, 2, 2] = c, -s, s, c, 1.0
    return r


def _residuals(
    poses: np.ndarray,
    pts: np.ndarray,
    kf: np.ndarray,
    tr: np.ndarray,
    uv: np.ndarray,
    cam_rot: np.ndarray,
    cam_t: np.ndarray,
    kmats: np.ndarray,
    jacobians: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reprojection residuals ``(n, 2)``, depth, and Jacobians by pose ``(n, 2, 3)`` and
    point ``(n, 2, 3)``."""
    rt = np.transpose(_robot_rot(poses[kf, 2]), (0, 2, 1))  # R^T
    d = pts[tr] - np.concatenate([poses[kf, :2], np.zeros((kf.size, 1))], axis=1)
    p_r = np.einsum("nij,nj->ni", rt, d)
    p_c = np.einsum("nij,nj->ni", cam_rot[kf], p_r) + cam_t[kf]
    z = p_c[:, 2]
    zs = np.where(np.abs(z) < 1e-6, 1e-6, z)
    k = kmats[kf]
    u = k[:, 0, 0] * p_c[:, 0] / zs + k[:, 0, 2]
    v = k[:, 1, 1] * p_c[:, 1] / zs + k[:, 1, 2]
    res = np.stack([u, v], axis=1) - uv
    if not jacobians:
        return res, z, np.zeros(0), np.zeros(0)
    dproj = np.zeros((kf.size, 2, 3))
    dproj[:, 0, 0] = k[:, 0, 0] / zs
    dproj[:, 0, 2] = -k[:, 0, 0] * p_c[:, 0] / zs**2
    dproj[:, 1, 1] = k[:, 1, 1] / zs
    dproj[:, 1, 2] = -k[:, 1, 1] * p_c[:, 1] / zs**2
    a = np.einsum("nij,njk->nik", dproj, cam_rot[kf])  # d uv / d p_r
    # p_r = R^T (X - t): d/dX = R^T; d/d(x, y) = -R^T[:, :2]; d/dtheta = (y_r, -x_r, 0).
    jp = np.zeros((kf.size, 3, 3))
    jp[:, :, :2] = -rt[:, :, :2]
    jp[:, 0, 2] = p_r[:, 1]
    jp[:, 1, 2] = -p_r[:, 0]
    j_pose = np.einsum("nij,njk->nik", a, jp)
    j_pt = np.einsum("nij,njk->nik", a, rt)
    return res, z, j_pose, j_pt


def bundle_adjust(
    poses: np.ndarray,
    heads: np.ndarray,
    cam_index: Sequence[int],
    intrinsics: Sequence[np.ndarray],
    kp_xy: np.ndarray,
    kp_frame: np.ndarray,
    track: np.ndarray,
    points: np.ndarray,
    edges: Sequence[Edge],
    heading_bias: float = 0.0,
    iterations: int = 6,
    long_gap: int = LONG_TRACK_GAP,
) -> BundleResult:
    """Refine keyframe poses, track points and the heading bias together (module doc).

    Args:
        poses: ``(N, 3)`` initial keyframe poses (map frame); keyframe 0 stays fixed.
        heads: ``(N, 2)`` HeadYaw, HeadPitch (rad).
        cam_index: Per keyframe camera index.
        intrinsics: Per keyframe 3x3 K.
        kp_xy: ``(M, 2)`` keypoint pixels of all keyframes (concatenated).
        kp_frame: ``(M,)`` keyframe of each keypoint.
        track: ``(M,)`` track label of each keypoint, -1 for none (see
            :func:`tracks_from_links`).
        points: ``(M, 3)`` initial 3-D point of each keypoint (map frame), NaN if none.
        edges: Pose-graph edges (odometry edges carry the heading bias).
        heading_bias: Initial heading bias (rad/m).
        iterations: Levenberg-Marquardt iterations at most.
        long_gap: Capture-index span that makes a track count in ``long_tracks``.

    Returns:
        The refined poses; the input poses when there is nothing to adjust.
    """
    n = poses.shape[0]
    use = (track >= 0) & np.isfinite(points[:, 0])
    labels, inv = np.unique(track[use], return_inverse=True)
    rows = np.flatnonzero(use)
    kf = kp_frame[rows].astype(np.int64)
    # One observation per (track, keyframe); tracks seen by at least MIN_TRACK keyframes.
    key = inv * n + kf
    _, first = np.unique(key, return_index=True)
    rows, kf, tr = rows[first], kf[first], inv[first]
    seen = np.bincount(tr, minlength=labels.size)
    ok = seen[tr] >= MIN_TRACK
    rows, kf, tr = rows[ok], kf[ok], tr[ok]
    if rows.size == 0:
        return BundleResult(poses.copy(), heading_bias, 0, 0, 0.0)
    _, tr = np.unique(tr, return_inverse=True)
    n_pts = int(tr.max()) + 1
    lo = np.full(n_pts, n, np.int64)
    hi = np.zeros(n_pts, np.int64)
    np.minimum.at(lo, tr, kf)
    np.maximum.at(hi, tr, kf)
    long_tracks = int(np.sum(hi - lo >= long_gap))
    pts = np.zeros((n_pts, 3))
    np.add.at(pts, tr, points[rows])
    pts /= np.bincount(tr, minlength=n_pts)[:, None]
    uv = kp_xy[rows].astype(np.float64)
    cams = [camera_in_robot(float(heads[i, 0]), float(heads[i, 1]), cam_index[i]) for i in range(n)]
    cam_inv = np.stack([np.linalg.inv(c) for c in cams])
    cam_rot, cam_t = cam_inv[:, :3, :3], cam_inv[:, :3, 3]
    kmats = np.stack([np.asarray(k, np.float64) for k in intrinsics])
    x = poses.astype(np.float64).copy()
    bias = heading_bias
    active = np.ones(rows.size, bool)
    lam = 1e-3

    def total_cost(xx: np.ndarray, pp: np.ndarray, bb: float) -> float:
        r, z, _, _ = _residuals(xx, pp, kf[active], tr[active], uv[active], cam_rot, cam_t,
                                kmats, False)  # fmt: skip
        e = np.linalg.norm(r, axis=1) / PIXEL_SIGMA
        e = np.where(z > 0.05, e, MAX_ERROR_PX)
        rho = np.where(e <= HUBER_PX, e**2, 2 * HUBER_PX * e - HUBER_PX**2)
        return float(rho.sum()) + graph_cost(xx, edges, bb)

    cost = total_cost(x, pts, bias)
    for _ in range(iterations):
        k_, t_ = kf[active], tr[active]
        r, z, j_pose, j_pt = _residuals(x, pts, k_, t_, uv[active], cam_rot, cam_t, kmats, True)
        e = np.linalg.norm(r, axis=1) / PIXEL_SIGMA
        w = np.where(e <= HUBER_PX, 1.0, HUBER_PX / np.maximum(e, 1e-12)) / PIXEL_SIGMA**2
        w = np.where(z > 0.05, w, 0.0)
        # Blocks: pose-pose (per keyframe), point-point (per track), pose-point (per obs).
        hpp = np.einsum("n,nki,nkj->nij", w, j_pose, j_pose)
        hll = np.einsum("n,nki,nkj->nij", w, j_pt, j_pt)
        hpl = np.einsum("n,nki,nkj->nij", w, j_pose, j_pt)
        gp = np.einsum("n,nki,nk->ni", w, j_pose, r)
        gl = np.einsum("n,nki,nk->ni", w, j_pt, r)
        hl = np.zeros((n_pts, 3, 3))
        np.add.at(hl, t_, hll)
        gll = np.zeros((n_pts, 3))
        np.add.at(gll, t_, gl)
        h_graph, g_graph = graph_system(x, edges, bias, estimate_bias=True)
        dim = 3 * n + 1
        while True:
            hl_d = hl + np.eye(3) * (lam * np.trace(hl, axis1=1, axis2=2)[:, None, None] / 3 + 1e-9)
            hl_inv = np.linalg.inv(hl_d)
            s = h_graph.copy()
            g = g_graph.copy()
            blk = np.zeros((n, n, 3, 3))
            np.add.at(blk, (k_, k_), hpp)
            # Schur complement: - sum over pairs of observations of one track.
            a_mat = np.einsum("nij,njk->nik", hpl, hl_inv[t_])  # H_pl H_ll^-1, (obs, 3, 3)
            order = np.argsort(t_, kind="stable")
            ts = t_[order]
            starts = np.flatnonzero(np.r_[True, ts[1:] != ts[:-1]])
            counts = np.diff(np.r_[starts, ts.size])
            for c in np.unique(counts).tolist():
                grp = starts[counts == c]
                idx = order[grp[:, None] + np.arange(c)]  # (tracks, c) observation indices
                left = a_mat[idx]  # (T, c, 3, 3)
                right = hpl[idx]  # (T, c, 3, 3)
                prod = np.einsum("tair,tbjr->tabij", left, right)
                kk = k_[idx]
                np.add.at(
                    blk,
                    (kk[:, :, None].repeat(c, 2), kk[:, None, :].repeat(c, 1)),
                    -prod,
                )
            s[: 3 * n, : 3 * n] += blk.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)
            gred = np.zeros((n, 3))
            np.add.at(gred, k_, gp - np.einsum("nij,nj->ni", a_mat, gll[t_]))
            g[: 3 * n] += gred.ravel()
            s[:3, :3] += np.eye(3) * 1e9  # hold keyframe 0
            s += np.diag(np.diag(s)) * lam + np.eye(dim) * 1e-9
            try:
                dx = np.linalg.solve(s, -g)
            except np.linalg.LinAlgError:
                return BundleResult(poses.copy(), heading_bias, n_pts, 0, float("nan"), long_tracks)
            dpose = dx[: 3 * n].reshape(n, 3)
            rhs = gll.copy()
            np.add.at(rhs, t_, np.einsum("nji,nj->ni", hpl, dpose[k_]))
            dl = -np.einsum("nij,nj->ni", hl_inv, rhs)
            x_new, pts_new, bias_new = x + dpose, pts + dl, bias + float(dx[-1])
            new_cost = total_cost(x_new, pts_new, bias_new)
            if new_cost < cost:
                x, pts, bias, cost = x_new, pts_new, bias_new, new_cost
                lam = max(lam / 10, 1e-7)
                break
            lam *= 10
            if lam > 1e4:
                break
        if lam > 1e4 or np.abs(dx[: 3 * n]).max() < 1e-6:
            break
        r_all, z_all, _, _ = _residuals(x, pts, kf, tr, uv, cam_rot, cam_t, kmats, False)
        active = (np.linalg.norm(r_all, axis=1) < MAX_ERROR_PX) & (z_all > 0.05)
        cost = total_cost(x, pts, bias)
    r_end, _, _, _ = _residuals(x, pts, kf[active], tr[active], uv[active], cam_rot, cam_t,
                                kmats, False)  # fmt: skip
    rms = float(np.sqrt(np.mean(np.sum(r_end**2, axis=1)))) if r_end.size else 0.0
    if not (np.isfinite(x).all() and np.isfinite(bias)):
        return BundleResult(poses.copy(), heading_bias, n_pts, 0, float("nan"), long_tracks)
    return BundleResult(x, bias, n_pts, int(active.sum()), rms, long_tracks)
