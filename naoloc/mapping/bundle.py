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
from dataclasses import dataclass, field

import numpy as np

from naoloc.config import BundleTuning, PoseGraphTuning
from naoloc.geometry import rotations_z, wrap_angles
from naoloc.mapping.posegraph import Edge, graph_cost, graph_system
from naoloc.robot.keyframe import camera_in_robot

_HOLD = 1e9  # weight that holds keyframe 0 in place (the map frame)
_REGULARISE = 1e-9  # keeps the normal equations invertible


@dataclass(frozen=True)
class BundleProblem:
    """What bundle adjustment refines: keyframes, their keypoints and the pose-graph edges.

    Attributes:
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
        graph: Pose-graph tuning (the heading-bias prior of the edges' cost).
        priors: ``(N, 3)`` absolute poses each keyframe is held near (map frame), e.g. the
            wall-referenced poses; None for none.
        prior_sigma: Standard deviations of those priors: position (m), heading (rad).
    """

    poses: np.ndarray
    heads: np.ndarray
    cam_index: Sequence[int]
    intrinsics: Sequence[np.ndarray]
    kp_xy: np.ndarray
    kp_frame: np.ndarray
    track: np.ndarray
    points: np.ndarray
    edges: Sequence[Edge]
    graph: PoseGraphTuning = field(default_factory=PoseGraphTuning)
    priors: np.ndarray | None = None
    prior_sigma: tuple[float, float] = (0.05, 0.01)


def _prior_terms(problem: BundleProblem, x: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Whitened residuals ``(N, 3)`` of the pose priors and their weights, or None."""
    if problem.priors is None:
        return None
    r = x - problem.priors
    r[:, 2] = wrap_angles(r[:, 2])
    sxy, sth = problem.prior_sigma
    w = np.array([1.0 / sxy**2, 1.0 / sxy**2, 1.0 / sth**2])
    return r, w


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


@dataclass(frozen=True)
class Observations:
    """One pixel observation per (track, keyframe), of tracks seen by enough keyframes.

    Attributes:
        rows: ``(n,)`` keypoint row of each observation.
        kf: ``(n,)`` keyframe of each observation.
        tr: ``(n,)`` track of each observation, 0 .. ``n_pts - 1``.
        uv: ``(n, 2)`` float64 pixels.
        n_pts: Number of tracks.
    """

    rows: np.ndarray
    kf: np.ndarray
    tr: np.ndarray
    uv: np.ndarray
    n_pts: int


@dataclass(frozen=True)
class CameraModels:
    """Per keyframe ``T_cam_robot`` rotation ``(N, 3, 3)``, translation ``(N, 3)`` and K."""

    rot: np.ndarray
    t: np.ndarray
    kmats: np.ndarray


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


def observations(problem: BundleProblem, tuning: BundleTuning) -> Observations:
    """The observations of tracks seen by at least ``tuning.min_track`` keyframes."""
    n = problem.poses.shape[0]
    use = (problem.track >= 0) & np.isfinite(problem.points[:, 0])
    labels, inv = np.unique(problem.track[use], return_inverse=True)
    rows = np.flatnonzero(use)
    kf = problem.kp_frame[rows].astype(np.int64)
    # One observation per (track, keyframe); tracks seen by at least min_track keyframes.
    key = inv * n + kf
    _, first = np.unique(key, return_index=True)
    rows, kf, tr = rows[first], kf[first], inv[first]
    seen = np.bincount(tr, minlength=labels.size)
    ok = seen[tr] >= tuning.min_track
    rows, kf, tr = rows[ok], kf[ok], tr[ok]
    if rows.size == 0:
        return Observations(rows, kf, tr, np.zeros((0, 2)), 0)
    _, tr = np.unique(tr, return_inverse=True)
    uv = problem.kp_xy[rows].astype(np.float64)
    return Observations(rows, kf, tr, uv, int(tr.max()) + 1)


def long_track_count(obs: Observations, n: int, long_gap: int) -> int:
    """Tracks whose keyframes span at least ``long_gap`` captures."""
    lo = np.full(obs.n_pts, n, np.int64)
    hi = np.zeros(obs.n_pts, np.int64)
    np.minimum.at(lo, obs.tr, obs.kf)
    np.maximum.at(hi, obs.tr, obs.kf)
    return int(np.sum(hi - lo >= long_gap))


def initial_points(obs: Observations, points: np.ndarray) -> np.ndarray:
    """``(n_pts, 3)`` mean of the keypoints' triangulated points per track."""
    pts = np.zeros((obs.n_pts, 3))
    np.add.at(pts, obs.tr, points[obs.rows])
    pts /= np.bincount(obs.tr, minlength=obs.n_pts)[:, None]
    return pts


def camera_models(problem: BundleProblem) -> CameraModels:
    """The head cameras of the keyframes (robot frame) and their intrinsics."""
    heads, cam_index = problem.heads, problem.cam_index
    cams = [
        camera_in_robot(float(heads[i, 0]), float(heads[i, 1]), cam_index[i])
        for i in range(problem.poses.shape[0])
    ]
    cam_inv = np.stack([np.linalg.inv(c) for c in cams])
    kmats = np.stack([np.asarray(k, np.float64) for k in problem.intrinsics])
    return CameraModels(cam_inv[:, :3, :3], cam_inv[:, :3, 3], kmats)


def reprojection(
    poses: np.ndarray,
    pts: np.ndarray,
    kf: np.ndarray,
    tr: np.ndarray,
    uv: np.ndarray,
    cams: CameraModels,
    jacobians: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reprojection residuals ``(n, 2)`` (px), depth ``(n,)`` (m), and the analytic
    Jacobians by pose ``(n, 2, 3)`` and by point ``(n, 2, 3)`` (empty without
    ``jacobians``)."""
    rt = np.transpose(rotations_z(poses[kf, 2]), (0, 2, 1))  # R^T
    d = pts[tr] - np.concatenate([poses[kf, :2], np.zeros((kf.size, 1))], axis=1)
    p_r = np.einsum("nij,nj->ni", rt, d)
    p_c = np.einsum("nij,nj->ni", cams.rot[kf], p_r) + cams.t[kf]
    z = p_c[:, 2]
    zs = np.where(np.abs(z) < 1e-6, 1e-6, z)
    k = cams.kmats[kf]
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
    a = np.einsum("nij,njk->nik", dproj, cams.rot[kf])  # d uv / d p_r
    # p_r = R^T (X - t): d/dX = R^T; d/d(x, y) = -R^T[:, :2]; d/dtheta = (y_r, -x_r, 0).
    jp = np.zeros((kf.size, 3, 3))
    jp[:, :, :2] = -rt[:, :, :2]
    jp[:, 0, 2] = p_r[:, 1]
    jp[:, 1, 2] = -p_r[:, 0]
    j_pose = np.einsum("nij,njk->nik", a, jp)
    j_pt = np.einsum("nij,njk->nik", a, rt)
    return res, z, j_pose, j_pt


@dataclass
class _State:
    """The unknowns and the bookkeeping of one adjustment."""

    x: np.ndarray  # (N, 3) poses
    pts: np.ndarray  # (P, 3) track points
    bias: float
    active: np.ndarray  # (n,) observations in use
    lam: float


def _cost(
    problem: BundleProblem,
    tuning: BundleTuning,
    obs: Observations,
    cams: CameraModels,
    active: np.ndarray,
    x: np.ndarray,
    pts: np.ndarray,
    bias: float,
) -> float:
    """Huber cost of the active observations plus the pose-graph cost."""
    r, z, _, _ = reprojection(x, pts, obs.kf[active], obs.tr[active], obs.uv[active], cams, False)
    e = np.linalg.norm(r, axis=1) / tuning.pixel_sigma_px
    e = np.where(z > tuning.min_depth_m, e, tuning.max_error_px)
    hub = tuning.huber_px
    rho = np.where(e <= hub, e**2, 2 * hub * e - hub**2)
    prior = _prior_terms(problem, x)
    held = 0.0 if prior is None else float(np.sum(prior[0] ** 2 * prior[1]))
    return (
        float(rho.sum()) + held + graph_cost(x, problem.edges, bias, problem.graph.sigma_bias_prior)
    )


@dataclass(frozen=True)
class _Normal:
    """Blocks of the normal equations of the active observations and the graph."""

    k_: np.ndarray  # keyframe of each active observation
    t_: np.ndarray  # track of each active observation
    hpp: np.ndarray  # (n, 3, 3) pose-pose
    hpl: np.ndarray  # (n, 3, 3) pose-point
    hl: np.ndarray  # (P, 3, 3) point-point, summed per track
    gp: np.ndarray  # (n, 3) pose gradient
    gll: np.ndarray  # (P, 3) point gradient, summed per track
    h_graph: np.ndarray
    g_graph: np.ndarray


def _normal_equations(
    problem: BundleProblem,
    tuning: BundleTuning,
    obs: Observations,
    cams: CameraModels,
    st: _State,
) -> _Normal:
    k_, t_ = obs.kf[st.active], obs.tr[st.active]
    r, z, j_pose, j_pt = reprojection(st.x, st.pts, k_, t_, obs.uv[st.active], cams, True)
    sig, hub = tuning.pixel_sigma_px, tuning.huber_px
    e = np.linalg.norm(r, axis=1) / sig
    w = np.where(e <= hub, 1.0, hub / np.maximum(e, 1e-12)) / sig**2
    w = np.where(z > tuning.min_depth_m, w, 0.0)
    # Blocks: pose-pose (per keyframe), point-point (per track), pose-point (per obs).
    hpp = np.einsum("n,nki,nkj->nij", w, j_pose, j_pose)
    hll = np.einsum("n,nki,nkj->nij", w, j_pt, j_pt)
    hpl = np.einsum("n,nki,nkj->nij", w, j_pose, j_pt)
    gp = np.einsum("n,nki,nk->ni", w, j_pose, r)
    gl = np.einsum("n,nki,nk->ni", w, j_pt, r)
    hl = np.zeros((obs.n_pts, 3, 3))
    np.add.at(hl, t_, hll)
    gll = np.zeros((obs.n_pts, 3))
    np.add.at(gll, t_, gl)
    h_graph, g_graph = graph_system(
        st.x, problem.edges, st.bias, estimate_bias=True,
        sigma_bias_prior=problem.graph.sigma_bias_prior,
    )  # fmt: skip
    prior = _prior_terms(problem, st.x)
    if prior is not None:
        r_p, w_p = prior
        n3 = r_p.size
        h_graph[np.arange(n3), np.arange(n3)] += np.tile(w_p, r_p.shape[0])
        g_graph[:n3] += (r_p * w_p).ravel()
    return _Normal(k_, t_, hpp, hpl, hl, gp, gll, h_graph, g_graph)


def _schur_step(eq: _Normal, n: int, lam: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Damped step ``(dx, dl)``: poses and bias ``(3N + 1,)``, points ``(P, 3)``.

    The points are eliminated by the Schur complement (3x3 blocks per track); None when
    the reduced system is singular.
    """
    k_, t_, hpl = eq.k_, eq.t_, eq.hpl
    dim = 3 * n + 1
    hl_d = eq.hl + np.eye(3) * (lam * np.trace(eq.hl, axis1=1, axis2=2)[:, None, None] / 3 + 1e-9)
    hl_inv = np.linalg.inv(hl_d)
    s = eq.h_graph.copy()
    g = eq.g_graph.copy()
    blk = np.zeros((n, n, 3, 3))
    np.add.at(blk, (k_, k_), eq.hpp)
    # Schur complement: - sum over pairs of observations of one track.
    a_mat = np.einsum("nij,njk->nik", hpl, hl_inv[t_])  # H_pl H_ll^-1, (obs, 3, 3)
    order = np.argsort(t_, kind="stable")
    ts = t_[order]
    starts = np.flatnonzero(np.r_[True, ts[1:] != ts[:-1]])
    counts = np.diff(np.r_[starts, ts.size])
    for c in np.unique(counts).tolist():
        grp = starts[counts == c]
        idx = order[grp[:, None] + np.arange(c)]  # (tracks, c) observation indices
        prod = np.einsum("tair,tbjr->tabij", a_mat[idx], hpl[idx])
        kk = k_[idx]
        np.add.at(blk, (kk[:, :, None].repeat(c, 2), kk[:, None, :].repeat(c, 1)), -prod)
    s[: 3 * n, : 3 * n] += blk.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)
    gred = np.zeros((n, 3))
    np.add.at(gred, k_, eq.gp - np.einsum("nij,nj->ni", a_mat, eq.gll[t_]))
    g[: 3 * n] += gred.ravel()
    s[:3, :3] += np.eye(3) * _HOLD  # hold keyframe 0
    s += np.diag(np.diag(s)) * lam + np.eye(dim) * _REGULARISE
    try:
        dx = np.linalg.solve(s, -g)
    except np.linalg.LinAlgError:
        return None
    dpose = dx[: 3 * n].reshape(n, 3)
    rhs = eq.gll.copy()
    np.add.at(rhs, t_, np.einsum("nji,nj->ni", hpl, dpose[k_]))
    dl = -np.einsum("nij,nj->ni", hl_inv, rhs)
    return dx, dl


def bundle_adjust(
    problem: BundleProblem,
    tuning: BundleTuning | None = None,
    *,
    heading_bias: float = 0.0,
    iterations: int | None = None,
    long_gap: int | None = None,
) -> BundleResult:
    """Refine keyframe poses, track points and the heading bias together (module doc).

    Args:
        problem: Keyframes, keypoints, tracks, initial points and pose-graph edges.
        tuning: Loss, outlier and damping settings; default :class:`BundleTuning`.
        heading_bias: Initial heading bias (rad/m).
        iterations: Levenberg-Marquardt iterations at most; default ``tuning.iterations``.
        long_gap: Capture-index span that makes a track count in ``long_tracks``; default
            ``tuning.long_track_gap``.

    Returns:
        The refined poses; the input poses when there is nothing to adjust.
    """
    tuning = tuning or BundleTuning()
    iterations = tuning.iterations if iterations is None else iterations
    long_gap = tuning.long_track_gap if long_gap is None else long_gap
    poses = problem.poses
    n = poses.shape[0]
    obs = observations(problem, tuning)
    if obs.rows.size == 0:
        return BundleResult(poses.copy(), heading_bias, 0, 0, 0.0)
    long_tracks = long_track_count(obs, n, long_gap)
    cams = camera_models(problem)
    lam0, lam_min, lam_max = tuning.lm_lambda
    st = _State(
        poses.astype(np.float64).copy(), initial_points(obs, problem.points), heading_bias,
        np.ones(obs.rows.size, bool), lam0,
    )  # fmt: skip
    failed = BundleResult(poses.copy(), heading_bias, obs.n_pts, 0, float("nan"), long_tracks)

    def cost(x: np.ndarray, pts: np.ndarray, bias: float) -> float:
        return _cost(problem, tuning, obs, cams, st.active, x, pts, bias)

    current = cost(st.x, st.pts, st.bias)
    for _ in range(iterations):
        eq = _normal_equations(problem, tuning, obs, cams, st)
        while True:
            step = _schur_step(eq, n, st.lam)
            if step is None:
                return failed
            dx, dl = step
            x_new = st.x + dx[: 3 * n].reshape(n, 3)
            pts_new, bias_new = st.pts + dl, st.bias + float(dx[-1])
            new_cost = cost(x_new, pts_new, bias_new)
            if new_cost < current:
                st.x, st.pts, st.bias, current = x_new, pts_new, bias_new, new_cost
                st.lam = max(st.lam / 10, lam_min)
                break
            st.lam *= 10
            if st.lam > lam_max:
                break
        if st.lam > lam_max or np.abs(dx[: 3 * n]).max() < 1e-6:
            break
        r_all, z_all, _, _ = reprojection(st.x, st.pts, obs.kf, obs.tr, obs.uv, cams, False)
        st.active = (np.linalg.norm(r_all, axis=1) < tuning.max_error_px) & (
            z_all > tuning.min_depth_m
        )
        current = cost(st.x, st.pts, st.bias)
    a = st.active
    r_end, _, _, _ = reprojection(st.x, st.pts, obs.kf[a], obs.tr[a], obs.uv[a], cams, False)
    rms = float(np.sqrt(np.mean(np.sum(r_end**2, axis=1)))) if r_end.size else 0.0
    if not (np.isfinite(st.x).all() and np.isfinite(st.bias)):
        return failed
    return BundleResult(st.x, st.bias, obs.n_pts, int(a.sum()), rms, long_tracks)
