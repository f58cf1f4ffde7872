"""Survey pose refinement: odometry fused with visual loop closures in a 2-D pose graph.

Odometry drifts (scale, heading bias, noise), so the survey's second lap does not land on
the first and the map blurs. Here each keyframe's triangulated landmarks (from temporally
adjacent keyframes only, where odometry is locally exact enough) are matched from
keyframes of other laps that look alike (TF-IDF retrieval) and, after a first solution,
from keyframes whose cameras look at the same place; PnP gives the relative pose between
the two keyframes. Odometry edges plus these loop-closure edges are then solved by
Gauss-Newton on (x, y, theta) per keyframe with the first keyframe held fixed, which keeps
the map frame (the odometry frame at the survey start).

The odometry model follows how a walking robot drifts: a heading bias proportional to the
distance walked (a systematic curve, estimated as one unknown of the graph, rad/m), heading
noise that grows with the square root of the angle turned (corners), and small position
noise per step. Loop closures get a robust (Huber) loss, and closures that still disagree
with the solution are dropped. A pure scale error of odometry is not observable from the
images (the landmarks are triangulated with the same odometry), so it stays in the map.

Frames: all poses are robot poses in the map frame (m, rad).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.config import PoseGraphTuning
from naoloc.geometry import (
    modulo2PI,
    planar_pose,
    robot_matrix,
    se2_compose_local,
    se2_relative,
    wrap_angles,
)
from naoloc.mapping.landmarks import (
    DescriptorMatcher,
    camera_poses,
    hamming_matcher,
    ratio_matches,
    triangulate,
)
from naoloc.mapping.planar import solve_planar
from naoloc.mapping.vocabulary import dbow_scores
from naoloc.robot.keyframe import camera_in_robot

DEFAULT = PoseGraphTuning()
_HOLD = 1e9  # weight that holds node 0 in place (the map frame)
#: ``relative(a, b)``: pose ``b`` in the frame of pose ``a`` (naoloc.geometry.se2_relative).
relative = se2_relative


@dataclass(frozen=True)
class Edge:
    """One pose-graph constraint: the pose of keyframe b measured in keyframe a's frame.

    Attributes:
        a: Index of the reference keyframe.
        b: Index of the measured keyframe.
        z: ``(3,)`` measured pose of b in a's robot frame (m, m, rad).
        info: ``(3, 3)`` information matrix (inverse covariance) of ``z``.
        odometry: True for an odometry edge: its heading is corrected by the estimated
            heading bias times ``dist``.
        dist: Distance walked between a and b (m), for the heading bias.
    """

    a: int
    b: int
    z: np.ndarray
    info: np.ndarray
    odometry: bool = False
    dist: float = 0.0


@dataclass(frozen=True)
class GraphSolution:
    """Result of :func:`solve_pose_graph`.

    Attributes:
        poses: ``(N, 3)`` optimised poses (map frame).
        heading_bias: Estimated odometry heading bias (rad per metre walked); 0 when not
            estimated.
        iterations: Gauss-Newton iterations run.
    """

    poses: np.ndarray
    heading_bias: float
    iterations: int


@dataclass(frozen=True)
class RefinedPoses:
    """Result of :func:`refine_poses`.

    Attributes:
        poses: ``(N, 3)`` refined keyframe poses (map frame).
        loops: Loop-closure edges kept.
        shift_m: Largest position change from the odometry poses, metres.
        heading_bias: Estimated odometry heading bias, rad per metre walked.
        edges: The odometry edges and the loop closures kept.
    """

    poses: np.ndarray
    loops: int
    shift_m: float
    heading_bias: float = 0.0
    edges: tuple[Edge, ...] = ()


def edge_terms(
    x: np.ndarray, edges: Sequence[Edge], bias: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Residuals and Jacobians of all edges at once.

    Returns:
        ``r`` (E, 3) residuals (b's pose error in the measured frame), ``ja`` and ``jb``
        (E, 3, 3) Jacobians w.r.t. poses a and b, ``jbias`` (E,) d r_theta / d bias.
    """
    ia = np.array([e.a for e in edges], np.int64)
    ib = np.array([e.b for e in edges], np.int64)
    z = np.stack([e.z for e in edges])
    jbias = np.array([e.dist if e.odometry else 0.0 for e in edges])
    zth = z[:, 2] - bias * jbias
    ca, sa = np.cos(x[ia, 2]), np.sin(x[ia, 2])
    cz, sz = np.cos(zth), np.sin(zth)
    dt = x[ib, :2] - x[ia, :2]
    # p = R_a^T dt (b's position in a's frame) and its derivative by theta_a.
    p = np.stack([ca * dt[:, 0] + sa * dt[:, 1], -sa * dt[:, 0] + ca * dt[:, 1]], axis=1)
    dp = np.stack([-sa * dt[:, 0] + ca * dt[:, 1], -ca * dt[:, 0] - sa * dt[:, 1]], axis=1)
    q = p - z[:, :2]
    r = np.empty((len(edges), 3))
    r[:, 0] = cz * q[:, 0] + sz * q[:, 1]
    r[:, 1] = -sz * q[:, 0] + cz * q[:, 1]
    r[:, 2] = wrap_angles(x[ib, 2] - x[ia, 2] - zth)
    # R_z^T R_a^T, a 2x2 rotation by -(theta_a + z_theta).
    cc, ss = np.cos(x[ia, 2] + zth), np.sin(x[ia, 2] + zth)
    rot = np.stack([np.stack([cc, ss], 1), np.stack([-ss, cc], 1)], 1)
    jb = np.zeros((len(edges), 3, 3))
    jb[:, :2, :2] = rot
    jb[:, 2, 2] = 1.0
    ja = -jb
    ja[:, 0, 2] = cz * dp[:, 0] + sz * dp[:, 1]
    ja[:, 1, 2] = -sz * dp[:, 0] + cz * dp[:, 1]
    return r, ja, jb, jbias


def _huber_weights(chi2: np.ndarray, k: float) -> np.ndarray:
    """IRLS weights of the Huber loss for residuals of squared Mahalanobis norm ``chi2``."""
    m = np.sqrt(np.maximum(chi2, 0.0))
    return np.where(m <= k, 1.0, k / np.maximum(m, 1e-12))


def solve_pose_graph(
    init: np.ndarray,
    edges: Sequence[Edge],
    iterations: int = 15,
    *,
    estimate_bias: bool = False,
    huber_k: float | None = None,
    sigma_bias_prior: float = DEFAULT.sigma_bias_prior,
) -> GraphSolution:
    """Gauss-Newton on a 2-D pose graph, node 0 fixed.

    Args:
        init: ``(N, 3)`` initial poses (map frame).
        edges: The constraints.
        iterations: Gauss-Newton iterations at most.
        estimate_bias: Also estimate one odometry heading bias (rad/m) shared by the
            odometry edges (a weak prior keeps it near 0 when unobservable).
        huber_k: Huber threshold (in sigmas) for the non-odometry edges; None: least squares.
        sigma_bias_prior: Standard deviation of the heading bias's prior (rad/m).

    Returns:
        The optimised poses and heading bias.
    """
    x = init.astype(np.float64).copy()
    n = x.shape[0]
    if not edges:
        return GraphSolution(x, 0.0, 0)
    bias = 0.0
    done = 0
    for it in range(1, iterations + 1):
        done = it
        h, g = graph_system(
            x, edges, bias, estimate_bias=estimate_bias, huber_k=huber_k,
            sigma_bias_prior=sigma_bias_prior,
        )  # fmt: skip
        h[:3, :3] += np.eye(3) * _HOLD  # hold node 0
        try:
            dx = np.linalg.solve(h + np.eye(h.shape[0]) * 1e-9, -g)
        except np.linalg.LinAlgError:
            break
        x += dx[: 3 * n].reshape(n, 3)
        bias += float(dx[-1])
        if np.abs(dx).max() < 1e-7:
            break
    return GraphSolution(x, bias, done)


def graph_cost(
    x: np.ndarray,
    edges: Sequence[Edge],
    bias: float,
    sigma_bias_prior: float = DEFAULT.sigma_bias_prior,
) -> float:
    """Sum of the edges' squared Mahalanobis residuals plus the heading bias prior.

    Twice the cost whose gradient :func:`graph_system` returns (same edges, no Huber).
    """
    cost = (bias / sigma_bias_prior) ** 2
    if edges:
        r, _, _, _ = edge_terms(x, edges, bias)
        info = np.stack([e.info for e in edges])
        cost += float(np.einsum("ei,eij,ej->", r, info, r))
    return cost


def graph_system(
    x: np.ndarray,
    edges: Sequence[Edge],
    bias: float,
    *,
    estimate_bias: bool = False,
    huber_k: float | None = None,
    sigma_bias_prior: float = DEFAULT.sigma_bias_prior,
) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton normal equations ``H dx = -g`` of the pose-graph edges.

    The unknowns are the ``N`` poses (3 each, in order) and the heading bias (last);
    the bias's weak prior is included; without ``estimate_bias`` its column is zero
    except for the prior, so it stays at ``bias``. Node 0 is not held here.

    Args:
        x: ``(N, 3)`` current poses.
        edges: The constraints.
        bias: Current heading bias (rad/m).
        estimate_bias: Let the odometry edges depend on the bias.
        huber_k: Huber threshold (in sigmas) for the non-odometry edges; None: least squares.
        sigma_bias_prior: Standard deviation of the heading bias's prior (rad/m).

    Returns:
        ``h`` ``(3N + 1, 3N + 1)`` and ``g`` ``(3N + 1,)``.
    """
    n = x.shape[0]
    dim = 3 * n + 1
    h = np.zeros((dim, dim))
    g = np.zeros(dim)
    h[-1, -1] += 1.0 / sigma_bias_prior**2
    g[-1] += bias / sigma_bias_prior**2
    if not edges:
        return h, g
    ia = np.array([e.a for e in edges], np.int64)
    ib = np.array([e.b for e in edges], np.int64)
    info = np.stack([e.info for e in edges])
    r, ja, jb, jbias = edge_terms(x, edges, bias)
    if huber_k is not None:
        loop = np.array([not e.odometry for e in edges])
        chi2 = np.einsum("ei,eij,ej->e", r, info, r)
        w = np.where(loop, _huber_weights(chi2, huber_k), 1.0)
        info = info * w[:, None, None]
    # Jacobian rows of every edge over [pose a | pose b | bias].
    jfull = np.concatenate([ja, jb, np.zeros((len(edges), 3, 1))], axis=2)
    jfull[:, 2, 6] = jbias if estimate_bias else 0.0
    jti = np.einsum("eki,ekl->eil", jfull, info)  # J^T W, (E, 7, 3)
    hb = np.einsum("eil,elj->eij", jti, jfull)  # (E, 7, 7)
    gb = np.einsum("eil,el->ei", jti, r)  # (E, 7)
    idx = np.concatenate(
        [
            3 * ia[:, None] + np.arange(3),
            3 * ib[:, None] + np.arange(3),
            np.full((len(edges), 1), dim - 1),
        ],
        axis=1,
    )
    np.add.at(h, (idx[:, :, None], idx[:, None, :]), hb)
    np.add.at(g, idx, gb)
    return h, g


def odometry_info(z: np.ndarray, tuning: PoseGraphTuning = DEFAULT) -> np.ndarray:
    """Information matrix of an odometry edge ``z`` (pose of b in a's frame)."""
    dist = math.hypot(z[0], z[1])
    s_xy, s_th = tuning.sigma_odo_xy, tuning.sigma_odo_theta
    sxy = s_xy[0] + s_xy[1] * dist
    sth = s_th[0] + s_th[1] * math.sqrt(abs(z[2])) + s_th[2] * dist
    return np.diag([1 / sxy**2, 1 / sxy**2, 1 / sth**2])


def odometry_edges(poses: np.ndarray, tuning: PoseGraphTuning = DEFAULT) -> list[Edge]:
    """Edges between consecutive keyframes from their odometry poses."""
    out = []
    for i in range(poses.shape[0] - 1):
        z = relative(poses[i], poses[i + 1])
        out.append(Edge(i, i + 1, z, odometry_info(z, tuning), True, math.hypot(z[0], z[1])))
    return out


@dataclass
class _LoopContext:
    """What loop-closure detection needs, computed once."""

    poses: np.ndarray
    heads: np.ndarray
    xy: Sequence[np.ndarray]
    desc: Sequence[np.ndarray]
    intrinsics: Sequence[np.ndarray]
    cam_index: Sequence[int]
    points: np.ndarray  # (M, 3) local landmarks, map frame of the odometry poses
    offsets: np.ndarray
    matcher: DescriptorMatcher
    tuning: PoseGraphTuning


def _loop_edge(ctx: _LoopContext, i: int, j: int) -> Edge | None:
    """Relative pose of keyframe j in keyframe i's frame by PnP on i's local landmarks."""
    import cv2

    tun = ctx.tuning
    m = ratio_matches(ctx.matcher, ctx.desc[j], ctx.desc[i])
    if m.shape[0] < tun.loop_min_inliers:
        return None
    obj_map = ctx.points[ctx.offsets[i] : ctx.offsets[i + 1]][m[:, 1]]
    ok_pts = np.isfinite(obj_map[:, 0])
    if ok_pts.sum() < tun.loop_min_inliers:
        return None
    t_ri_map = np.linalg.inv(robot_matrix(*ctx.poses[i]))
    obj = obj_map[ok_pts] @ t_ri_map[:3, :3].T + t_ri_map[:3, 3]
    img = ctx.xy[j][m[ok_pts, 0]].astype(np.float64)
    try:
        cv2.setRNGSeed(i * 100003 + j)  # reproducible RANSAC whatever ran before (see localizer)
        ok, rvec, tvec, inl = cv2.solvePnPRansac(
            obj,
            img,
            ctx.intrinsics[j],
            None,
            iterationsCount=200,
            reprojectionError=tun.loop_reprojection_px,
            confidence=0.999,
            flags=cv2.SOLVEPNP_SQPNP,
        )
    except cv2.error:
        return None
    if not ok or inl is None or len(inl) < tun.loop_min_inliers:
        return None
    rot, _ = cv2.Rodrigues(rvec)
    t_cam_ri = np.eye(4)
    t_cam_ri[:3, :3], t_cam_ri[:3, 3] = rot, tvec.ravel()
    c_j = camera_in_robot(float(ctx.heads[j, 0]), float(ctx.heads[j, 1]), ctx.cam_index[j])
    t_ri_rj = np.linalg.inv(t_cam_ri) @ np.linalg.inv(c_j)
    if abs(t_ri_rj[2, 3]) > tun.max_height_change_m:  # both robots stand on the same floor
        return None
    sel = np.asarray(inl).ravel()
    z0 = np.array(planar_pose(t_ri_rj))
    fit = planar_pnp(z0, obj[sel], img[sel], ctx.intrinsics[j], c_j, tun)
    if fit is None:
        return None
    return Edge(i, j, fit[0], fit[1])


def _project_planar(
    z: np.ndarray, obj: np.ndarray, kmat: np.ndarray, c_j: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels and depths of points ``obj`` (robot-i frame) seen from robot pose ``z``."""
    t_cam = np.linalg.inv(robot_matrix(*z) @ c_j)
    pc = obj @ t_cam[:3, :3].T + t_cam[:3, 3]
    h = pc @ kmat.T
    with np.errstate(divide="ignore", invalid="ignore"):
        return h[:, :2] / h[:, 2:3], pc[:, 2]


def planar_pnp(
    z0: np.ndarray,
    obj: np.ndarray,
    img: np.ndarray,
    kmat: np.ndarray,
    c_j: np.ndarray,
    tuning: PoseGraphTuning = DEFAULT,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Planar (x, y, theta) pose from 3-D to 2-D matches, and its information matrix.

    Gauss-Newton (naoloc.mapping.planar) on the reprojection error with the camera height
    and pitch fixed by the head (``c_j``); points beyond ``tuning.loop_reprojection_px``
    are left out at each iteration. The information is ``J^T J / sigma^2`` of the pixel
    residuals, with the matches counted at most ``loop_effective_matches`` times (landmark
    errors are correlated) and the residual spread taken when it is larger than
    ``loop_pixel_sigma``.

    Args:
        z0: ``(3,)`` initial pose of the robot in the landmarks' frame (m, m, rad).
        obj: ``(n, 3)`` points in that frame (m).
        img: ``(n, 2)`` their pixels.
        kmat: 3x3 camera matrix.
        c_j: 4x4 camera-in-robot transform of the image.
        tuning: Thresholds (pixels, inliers).

    Returns:
        ``(z, info)`` (3-vector, 3x3), or None with too few consistent matches.
    """
    kept: list[int] = [obj.shape[0]]

    def linearise(
        z: np.ndarray,
    ) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]] | None:
        uv, depth = _project_planar(z, obj, kmat, c_j)
        err = np.linalg.norm(uv - img, axis=1)
        keep = np.isfinite(err) & (depth > 0.05) & (err < tuning.loop_reprojection_px)
        kept[0] = int(keep.sum())
        if kept[0] < tuning.loop_min_inliers:
            return None
        obj_k, img_k = obj[keep], img[keep]

        def at(zz: np.ndarray) -> np.ndarray:
            return (_project_planar(zz, obj_k, kmat, c_j)[0] - img_k).ravel()

        return (uv[keep] - img_k).ravel(), at

    fit = solve_planar(
        linearise, z0, iterations=5, fd_step=1e-5, tol=1e-7, retract=se2_compose_local
    )
    if fit is None:
        return None
    res, jac = fit.residuals, fit.jacobian
    sigma = max(tuning.loop_pixel_sigma, float(np.sqrt(np.mean(res**2))))
    info = jac.T @ jac / sigma**2 * min(1.0, tuning.loop_effective_matches / kept[0])
    if not np.isfinite(info).all():
        return None
    return fit.x, info


def _retrieval_pairs(histograms: np.ndarray, tuning: PoseGraphTuning) -> list[tuple[int, int]]:
    """(landmark keyframe, query keyframe) pairs from TF-IDF retrieval, far apart in time."""
    n = histograms.shape[0]
    gap = tuning.loop_min_gap
    out = []
    for j in range(n):
        scores = dbow_scores(histograms[j], histograms)
        scores[max(0, j - gap + 1) : j + gap] = -1.0
        for i in np.argsort(-scores, kind="stable")[: tuning.loop_candidates].tolist():
            if scores[i] > 0:
                out.append((int(i), j))
    return out


def _geometric_pairs(cams: np.ndarray, tuning: PoseGraphTuning) -> list[tuple[int, int]]:
    """Pairs far apart in time whose cameras (of a first solution) see the same place.

    Each camera's look-at point ``geometric_lookahead_m`` ahead on its optical axis is
    compared; the closest ones with views within ``geometric_max_angle_deg`` pair up.
    """
    n = cams.shape[0]
    look = cams[:, :3, 3] + tuning.geometric_lookahead_m * cams[:, :3, 2]
    views = cams[:, :3, 2]
    dist = np.linalg.norm(look[:, None, :] - look[None, :, :], axis=2)
    ok = (views @ views.T) > math.cos(math.radians(tuning.geometric_max_angle_deg))
    idx = np.arange(n)
    ok &= np.abs(idx[:, None] - idx[None, :]) >= tuning.loop_min_gap
    dist[~ok] = np.inf
    out = []
    for j in range(n):
        for i in np.argsort(dist[j], kind="stable")[: tuning.geometric_candidates].tolist():
            if math.isfinite(dist[j, i]) and dist[j, i] < tuning.geometric_max_distance_m:
                out.append((int(i), j))
    return out


def _solve_robust(
    init: np.ndarray, odo: list[Edge], loops: list[Edge], tuning: PoseGraphTuning
) -> tuple[GraphSolution, list[Edge]]:
    """Robust solve, drop loop closures that still disagree, solve again."""
    prior = tuning.sigma_bias_prior
    sol = solve_pose_graph(
        init, odo + loops, estimate_bias=True, huber_k=tuning.huber_k, sigma_bias_prior=prior
    )
    kept = []
    for e in loops:
        r = relative(sol.poses[e.a], sol.poses[e.b]) - e.z
        r[2] = modulo2PI(r[2])
        if float(r @ e.info @ r) < tuning.outlier_chi2:
            kept.append(e)
    if len(kept) < len(loops):
        sol = solve_pose_graph(
            init, odo + kept, estimate_bias=True, huber_k=tuning.huber_k, sigma_bias_prior=prior
        )
    return sol, kept


def refine_poses(
    poses: np.ndarray,
    heads: np.ndarray,
    xy: Sequence[np.ndarray],
    desc: Sequence[np.ndarray],
    intrinsics: Sequence[np.ndarray],
    cam_index: Sequence[int],
    histograms: np.ndarray,
    binary: bool,
    tuning: PoseGraphTuning = DEFAULT,
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
        tuning: Loop-closure and odometry-noise settings.

    Returns:
        The refined poses (the odometry poses when no loop closure is found).
    """
    n = poses.shape[0]
    cams = camera_poses(poses, heads, cam_index)
    win = tuning.local_window
    local = [(i, j) for i in range(n) for j in range(i + 1, min(n, i + win + 1))]
    lm = triangulate(xy, desc, cams, intrinsics, binary, pairs=local)
    offsets = np.concatenate([[0], np.cumsum([a.shape[0] for a in xy])]).astype(np.int64)
    ctx = _LoopContext(
        poses, heads, xy, desc, intrinsics, cam_index, lm.points, offsets,
        hamming_matcher(binary), tuning,
    )  # fmt: skip
    odo = odometry_edges(poses, tuning)
    tried: set[tuple[int, int]] = set()
    loops: list[Edge] = []

    def add(pairs: list[tuple[int, int]]) -> None:
        for i, j in pairs:
            key = (min(i, j), max(i, j))
            if key in tried:
                continue
            tried.add(key)
            edge = _loop_edge(ctx, i, j)
            if edge is not None:
                loops.append(edge)

    add(_retrieval_pairs(histograms, tuning))
    if not loops:
        return RefinedPoses(poses.copy(), 0, 0.0, 0.0, tuple(odo))
    sol, kept = _solve_robust(poses, odo, loops, tuning)
    # Second pass: pairs that look at the same place according to the first solution.
    add(_geometric_pairs(camera_poses(sol.poses, heads, cam_index), tuning))
    sol, kept = _solve_robust(sol.poses, odo, loops, tuning)
    refined = sol.poses
    shift = float(np.max(np.hypot(*(refined[:, :2] - poses[:, :2]).T)))
    return RefinedPoses(refined, len(kept), shift, sol.heading_bias, tuple(odo + kept))
