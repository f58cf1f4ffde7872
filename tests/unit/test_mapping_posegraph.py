"""Pose graph, planar PnP, tracks and bundle adjustment on a synthetic two-lap survey.

The scene: a 6 x 6 m room whose walls carry random 3-D points, each with its own binary
descriptor; the robot walks two counter-clockwise laps of a 4 x 4 m square 1 m from the
walls in 0.2 m steps, head turned to the right-hand wall. Odometry drifts like the
simulators' (scale, heading bias per metre, noise). Everything is seeded.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass

import numpy as np
import pytest

from naoloc.config import PoseGraphTuning
from naoloc.geometry import robot_matrix
from naoloc.mapping.bundle import BundleProblem, bundle_adjust, tracks_from_links
from naoloc.mapping.landmarks import camera_matrix_in_map, triangulate
from naoloc.mapping.posegraph import (
    Edge,
    graph_system,
    odometry_edges,
    planar_pnp,
    refine_poses,
    relative,
    solve_pose_graph,
)
from naoloc.robot.keyframe import CameraInfo, camera_in_robot

SIGMA_BIAS_PRIOR = PoseGraphTuning().sigma_bias_prior
HEAD = (-math.pi / 2, 0.1)  # HeadYaw (right), HeadPitch (rad)
CAM = CameraInfo(320, 240, math.radians(56.3), math.radians(43.7), 0)
BIAS = 0.01  # rad/m, twice the simulators' default


@dataclass
class Scene:
    truth: np.ndarray  # (N, 3) map frame
    odometry: np.ndarray  # (N, 3)
    xy: list[np.ndarray]
    desc: list[np.ndarray]
    ids: list[np.ndarray]  # point id of each keypoint
    histograms: np.ndarray
    points: np.ndarray  # (P, 3)


def _square(laps: int) -> np.ndarray:
    poses = []
    for _lap in range(laps):
        for side in range(4):
            th = side * math.pi / 2
            corner = [np.array([0.0, 0.0]), np.array([4.0, 0.0]), np.array([4.0, 4.0]),
                      np.array([0.0, 4.0])][side]  # fmt: skip
            for k in range(20):
                p = corner + 0.2 * k * np.array([math.cos(th), math.sin(th)])
                poses.append([p[0], p[1], th])
    return np.array(poses[1:])  # keyframe 0 after the first step, as in a survey


def _drift(truth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    out = [truth[0].copy()]
    for a, b in itertools.pairwise(truth):
        z = relative(a, b)
        d = math.hypot(z[0], z[1])
        z = np.array([z[0] * 1.01, z[1] * 1.01, z[2] + BIAS * d])
        z += rng.normal(0.0, [0.001, 0.001, 0.001 + 0.006 * math.sqrt(abs(z[2]))])
        c, s = math.cos(out[-1][2]), math.sin(out[-1][2])
        p = out[-1]
        out.append(np.array([p[0] + c * z[0] - s * z[1], p[1] + s * z[0] + c * z[1], p[2] + z[2]]))
    return np.array(out)


def _scene(seed: int = 0, laps: int = 2, pixel_noise: float = 0.3) -> Scene:
    rng = np.random.default_rng(seed)
    n_wall = 700
    t = rng.uniform(-1.0, 5.0, (4, n_wall))
    z = rng.uniform(0.2, 1.6, (4, n_wall))
    walls = [
        np.stack([t[0], np.full(n_wall, -1.0), z[0]], 1),
        np.stack([np.full(n_wall, 5.0), t[1], z[1]], 1),
        np.stack([t[2], np.full(n_wall, 5.0), z[2]], 1),
        np.stack([np.full(n_wall, -1.0), t[3], z[3]], 1),
    ]
    points = np.concatenate(walls)
    codes = rng.integers(0, 256, (points.shape[0], 61), dtype=np.uint8)
    truth = _square(laps)
    odometry = _drift(truth, rng)
    k = CAM.matrix()
    xy, desc, ids = [], [], []
    vocab = 64
    hists = np.zeros((truth.shape[0], vocab))
    for i, pose in enumerate(truth):
        t_cam_map = np.linalg.inv(camera_matrix_in_map(pose, *HEAD, 0))
        pc = points @ t_cam_map[:3, :3].T + t_cam_map[:3, 3]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = (pc @ k.T)[:, :2] / pc[:, 2:3]
        vis = (pc[:, 2] > 0.2) & (uv[:, 0] > 2) & (uv[:, 0] < 318) & (uv[:, 1] > 2)
        vis &= uv[:, 1] < 238
        sel = np.flatnonzero(vis)
        xy.append((uv[sel] + rng.normal(0, pixel_noise, (sel.size, 2))).astype(np.float32))
        desc.append(codes[sel])
        ids.append(sel)
        np.add.at(hists[i], sel % vocab, 1.0)
    hists /= np.maximum(np.linalg.norm(hists, axis=1, keepdims=True), 1e-12)
    return Scene(truth, odometry, xy, desc, ids, hists, points)


def _errors(poses: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    d = np.hypot(*(poses[:, :2] - truth[:, :2]).T)
    th = np.abs(np.remainder(poses[:, 2] - truth[:, 2] + np.pi, 2 * np.pi) - np.pi)
    return float(d.mean()), float(th.mean())


@pytest.fixture(scope="module")
def scene() -> Scene:
    return _scene()


def test_graph_recovers_heading_bias_from_exact_loops(scene: Scene) -> None:
    truth, odo = scene.truth, scene.odometry
    n = truth.shape[0]
    info = np.diag([1e4, 1e4, 1e5])
    loops = [Edge(i, i + 80, relative(truth[i], truth[i + 80]), info) for i in range(0, n - 80, 3)]
    sol = solve_pose_graph(odo, odometry_edges(odo) + loops, estimate_bias=True)
    assert sol.heading_bias == pytest.approx(BIAS, abs=0.003)
    np.testing.assert_allclose(sol.poses[0], odo[0], atol=1e-9)  # keyframe 0 is held
    before, after = _errors(odo, truth), _errors(sol.poses, truth)
    assert after[1] < 0.25 * before[1]
    assert after[0] < 0.35 * before[0]
    plain = solve_pose_graph(odo, odometry_edges(odo) + loops, estimate_bias=False)
    assert _errors(plain.poses, truth)[1] > after[1]


def test_graph_without_loops_keeps_odometry(scene: Scene) -> None:
    sol = solve_pose_graph(scene.odometry, odometry_edges(scene.odometry), estimate_bias=True)
    np.testing.assert_allclose(sol.poses, scene.odometry, atol=1e-6)
    assert abs(sol.heading_bias) < 1e-6


def test_huber_resists_a_wrong_loop_closure(scene: Scene) -> None:
    truth, odo = scene.truth, scene.odometry
    info = np.diag([1e4, 1e4, 1e5])
    loops = [Edge(i, i + 80, relative(truth[i], truth[i + 80]), info) for i in range(0, 79, 4)]
    bad = Edge(10, 130, np.array([0.0, 0.0, 0.0]), info)  # 10 and 130 are 4 m apart
    edges = odometry_edges(odo) + loops + [bad]
    robust = solve_pose_graph(odo, edges, estimate_bias=True, huber_k=2.0)
    naive = solve_pose_graph(odo, edges, estimate_bias=True)
    assert _errors(robust.poses, truth)[0] < 0.5 * _errors(naive.poses, truth)[0]


def test_graph_system_gradient_matches_finite_differences(scene: Scene) -> None:
    rng = np.random.default_rng(1)
    x = scene.truth[:12] + rng.normal(0, [0.05, 0.05, 0.03], (12, 3))
    loop = Edge(1, 9, relative(scene.truth[1], scene.truth[9]), np.diag([400.0, 900.0, 2500.0]))
    edges = [*odometry_edges(scene.odometry[:12]), loop]

    def cost(xx: np.ndarray, b: float) -> float:
        total = 0.0
        for e in edges:
            zth = e.z[2] - b * e.dist if e.odometry else e.z[2]
            z = np.array([e.z[0], e.z[1], zth])
            rel = relative(xx[e.a], xx[e.b])
            c, s = math.cos(zth), math.sin(zth)
            d = rel[:2] - z[:2]
            r = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
            r = np.append(r, math.remainder(rel[2] - zth, 2 * math.pi))
            total += 0.5 * float(r @ e.info @ r)
        return total + 0.5 * (b / SIGMA_BIAS_PRIOR) ** 2

    bias = 0.003
    _h, g = graph_system(x, edges, bias, estimate_bias=True)
    num = np.zeros(g.size)
    for k in range(g.size):
        xp, xm = x.copy().ravel(), x.copy().ravel()
        if k < x.size:
            xp[k] += 1e-6
            xm[k] -= 1e-6
            num[k] = (cost(xp.reshape(x.shape), bias) - cost(xm.reshape(x.shape), bias)) / 2e-6
        else:
            num[k] = (cost(x, bias + 1e-6) - cost(x, bias - 1e-6)) / 2e-6
    np.testing.assert_allclose(g, num, rtol=1e-4, atol=1e-3)


def test_planar_pnp_recovers_a_pose_with_a_positive_information(scene: Scene) -> None:
    rng = np.random.default_rng(2)
    ref, query = scene.truth[5], scene.truth[86]
    pts_map = scene.points[scene.ids[86]]
    t_ref_map = np.linalg.inv(robot_matrix(*ref))
    obj = pts_map @ t_ref_map[:3, :3].T + t_ref_map[:3, 3]
    img = scene.xy[86].astype(np.float64)
    z_true = relative(ref, query)
    c_j = camera_in_robot(*HEAD, 0)
    start = z_true + rng.normal(0, [0.05, 0.05, 0.03])
    fit = planar_pnp(start, obj, img, CAM.matrix(), c_j)
    assert fit is not None
    z, info = fit
    assert np.hypot(*(z[:2] - z_true[:2])) < 0.01
    assert abs(z[2] - z_true[2]) < 0.003
    assert np.all(np.linalg.eigvalsh(info) > 0)
    assert planar_pnp(start, obj[:5], img[:5], CAM.matrix(), c_j) is None


def test_tracks_from_links_are_connected_components() -> None:
    links = np.array([[0, 3], [3, 5], [7, 8], [5, 0]])
    tr = tracks_from_links(10, links)
    assert tr.tolist() == [0, -1, -1, 0, -1, 0, -1, 7, 7, -1]
    assert tracks_from_links(3, np.zeros((0, 2), np.int64)).tolist() == [-1, -1, -1]


def test_triangulate_links_matching_keypoints(scene: Scene) -> None:
    n = 30
    cams = np.stack([camera_matrix_in_map(p, *HEAD, 0) for p in scene.truth[:n]])
    lm = triangulate(scene.xy[:n], scene.desc[:n], cams, [CAM.matrix()] * n, True)
    ids = np.concatenate(scene.ids[:n])
    assert lm.matches.shape[0] > 1000
    assert np.all(ids[lm.matches[:, 0]] == ids[lm.matches[:, 1]])
    ok = np.isfinite(lm.points[:, 0])
    err = np.linalg.norm(lm.points[ok] - scene.points[ids[ok]], axis=1)
    assert np.median(err) < 0.01


def test_refine_and_bundle_adjust_beat_odometry(scene: Scene) -> None:
    n = scene.truth.shape[0]
    k = [CAM.matrix()] * n
    heads = np.tile(np.array(HEAD), (n, 1))
    refined = refine_poses(
        scene.odometry, heads, scene.xy, scene.desc, k, [0] * n, scene.histograms, True
    )
    assert refined.loops > 50
    assert 0.4 * BIAS < refined.heading_bias < 1.5 * BIAS
    odo_err = _errors(scene.odometry, scene.truth)
    graph_err = _errors(refined.poses, scene.truth)
    assert graph_err[0] < 0.3 * odo_err[0]
    cams = np.stack([camera_matrix_in_map(p, *HEAD, 0) for p in refined.poses])
    lm = triangulate(scene.xy, scene.desc, cams, k, True)
    kp_xy = np.concatenate(scene.xy)
    frame = np.repeat(np.arange(n), [len(a) for a in scene.xy])
    tracks = tracks_from_links(kp_xy.shape[0], lm.matches)
    odo_edges = [e for e in refined.edges if e.odometry]
    problem = BundleProblem(refined.poses, heads, [0] * n, k, kp_xy, frame, tracks, lm.points,
                            odo_edges)  # fmt: skip
    ba = bundle_adjust(problem, heading_bias=refined.heading_bias)
    assert ba.long_tracks > 50
    assert ba.rms_px < 1.0
    np.testing.assert_allclose(ba.poses[0], refined.poses[0], atol=1e-6)
    ba_err = _errors(ba.poses, scene.truth)
    # The odometry scale error (1 %) is not observable; the rest should mostly go.
    scaled = ba.poses.copy()
    scaled[:, :2] = scaled[0, :2] + (scaled[:, :2] - scaled[0, :2]) / 1.01
    assert ba_err[1] < graph_err[1]
    assert _errors(scaled, scene.truth)[0] < 0.6 * graph_err[0]


def test_long_tracks_count_only_tracks_that_tie_the_laps(scene: Scene) -> None:
    n = scene.truth.shape[0]
    k = [CAM.matrix()] * n
    heads = np.tile(np.array(HEAD), (n, 1))
    cams = np.stack([camera_matrix_in_map(p, *HEAD, 0) for p in scene.truth])
    lm = triangulate(scene.xy, scene.desc, cams, k, True)
    kp_xy = np.concatenate(scene.xy)
    frame = np.repeat(np.arange(n), [len(a) for a in scene.xy])
    lap = frame // 80
    same_lap = lm.matches[lap[lm.matches[:, 0]] == lap[lm.matches[:, 1]]]
    edges = odometry_edges(scene.truth)
    both = bundle_adjust(BundleProblem(scene.truth, heads, [0] * n, k, kp_xy, frame,
                                       tracks_from_links(kp_xy.shape[0], lm.matches),
                                       lm.points, edges), iterations=1, long_gap=40)  # fmt: skip
    within = bundle_adjust(BundleProblem(scene.truth, heads, [0] * n, k, kp_xy, frame,
                                         tracks_from_links(kp_xy.shape[0], same_lap),
                                         lm.points, edges), iterations=1, long_gap=40)  # fmt: skip
    assert both.long_tracks > 100
    assert within.long_tracks < 0.1 * both.long_tracks


def _small_problem(scene: Scene, n: int = 12) -> tuple[BundleProblem, np.ndarray]:
    """Bundle problem of the first ``n`` keyframes with true-pose landmarks, and a jitter."""
    k = [CAM.matrix()] * n
    heads = np.tile(np.array(HEAD), (n, 1))
    cams = np.stack([camera_matrix_in_map(p, *HEAD, 0) for p in scene.truth[:n]])
    lm = triangulate(scene.xy[:n], scene.desc[:n], cams, k, True)
    kp_xy = np.concatenate(scene.xy[:n])
    frame = np.repeat(np.arange(n), [len(a) for a in scene.xy[:n]])
    tracks = tracks_from_links(kp_xy.shape[0], lm.matches)
    problem = BundleProblem(scene.truth[:n], heads, [0] * n, k, kp_xy, frame, tracks,
                            lm.points, odometry_edges(scene.truth[:n]))  # fmt: skip
    rng = np.random.default_rng(3)
    return problem, rng.normal(0, [0.02, 0.02, 0.01], (n, 3))


def test_bundle_reprojection_jacobians_match_finite_differences(scene: Scene) -> None:
    from naoloc.config import BundleTuning
    from naoloc.mapping.bundle import camera_models, initial_points, observations, reprojection

    problem, jitter = _small_problem(scene)
    obs = observations(problem, BundleTuning())
    assert obs.n_pts > 100
    cams = camera_models(problem)
    x = problem.poses + jitter
    pts = initial_points(obs, problem.points) + 0.01
    res, _z, j_pose, j_pt = reprojection(x, pts, obs.kf, obs.tr, obs.uv, cams, True)

    def residuals(xx: np.ndarray, pp: np.ndarray) -> np.ndarray:
        return reprojection(xx, pp, obs.kf, obs.tr, obs.uv, cams, False)[0]

    h = 1e-6
    for k in range(3):  # d residual of observation i / d pose of its keyframe, component k
        xp, xm = x.copy(), x.copy()
        xp[:, k] += h
        xm[:, k] -= h
        num = (residuals(xp, pts) - residuals(xm, pts)) / (2 * h)
        np.testing.assert_allclose(j_pose[:, :, k], num, rtol=1e-5, atol=1e-3)
    for k in range(3):  # d residual / d point coordinate k
        pp, pm = pts.copy(), pts.copy()
        pp[:, k] += h
        pm[:, k] -= h
        num = (residuals(x, pp) - residuals(x, pm)) / (2 * h)
        np.testing.assert_allclose(j_pt[:, :, k], num, rtol=1e-5, atol=1e-3)
    assert np.abs(j_pose).max() > 10 and np.abs(res).max() > 0.1  # not a vacuous check


def test_pose_graph_edge_jacobians_match_finite_differences(scene: Scene) -> None:
    from naoloc.mapping.posegraph import edge_terms

    rng = np.random.default_rng(4)
    x = scene.truth[:10] + rng.normal(0, [0.05, 0.05, 0.05], (10, 3))
    edges = [*odometry_edges(scene.odometry[:10]),
             Edge(1, 8, relative(scene.truth[1], scene.truth[8]), np.eye(3))]  # fmt: skip
    bias = 0.004
    _r, ja, jb, jbias = edge_terms(x, edges, bias)
    h = 1e-6
    for e_idx, e in enumerate(edges):
        for k in range(3):
            for node, jac in ((e.a, ja), (e.b, jb)):
                xp, xm = x.copy(), x.copy()
                xp[node, k] += h
                xm[node, k] -= h
                num = (edge_terms(xp, [e], bias)[0][0] - edge_terms(xm, [e], bias)[0][0]) / (2 * h)
                np.testing.assert_allclose(jac[e_idx, :, k], num, rtol=1e-5, atol=1e-6)
        # The bias enters the heading residual; it also rotates the position residual, which
        # the Gauss-Newton leaves out: that leaves the cost unchanged when the position
        # information is isotropic, as for odometry edges (checked by the gradient test).
        num_b = (edge_terms(x, [e], bias + h)[0][0] - edge_terms(x, [e], bias - h)[0][0]) / (2 * h)
        assert num_b[2] == pytest.approx(jbias[e_idx], abs=1e-6)


def test_mapping_modules_import_no_circle() -> None:
    """Every import between naoloc.mapping modules (also lazy and TYPE_CHECKING ones)."""
    import ast
    from pathlib import Path

    import naoloc.mapping

    folder = Path(naoloc.mapping.__file__).parent
    graph: dict[str, set[str]] = {}
    for path in folder.glob("*.py"):
        if path.stem == "__init__":
            continue
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                if name.startswith("naoloc.mapping."):
                    deps.add(name.split(".")[2])
                elif name == "naoloc.mapping":
                    deps.add("__init__")
        graph[path.stem] = deps & ({p.stem for p in folder.glob("*.py")} | {"__init__"})
    assert all("__init__" not in d for d in graph.values()), graph
    # The plain data imports only the data classes of the vocabulary and the network.
    assert graph["data"] <= {"gcs", "vocabulary"}, graph["data"]
    for low in ("gcs", "vocabulary"):
        assert not graph[low] & {"builder", "localizer", "mapfile", "map", "data"}
    seen: dict[str, int] = {}

    def visit(mod: str, stack: tuple[str, ...]) -> None:
        if seen.get(mod) == 2:
            return
        assert seen.get(mod) != 1, f"import circle: {' -> '.join((*stack, mod))}"
        seen[mod] = 1
        for dep in sorted(graph.get(mod, ())):
            visit(dep, (*stack, mod))
        seen[mod] = 2

    for mod in sorted(graph):
        visit(mod, ())


def test_wall_pose_priors_hold_the_adjustment(scene: Scene) -> None:
    """Edges that carry a bend (odometry bent 0.004 rad per keyframe) bend the adjusted
    poses; priors at the wall-referenced (here: true) poses pull them back."""
    n = 30
    k = [CAM.matrix()] * n
    heads = np.tile(np.array(HEAD), (n, 1))
    bent = scene.truth[:n].copy()
    for i in range(1, n):  # each step turned a little more than truly: the path bends
        z = relative(scene.truth[i - 1], scene.truth[i])
        c, s = math.cos(bent[i - 1, 2]), math.sin(bent[i - 1, 2])
        bent[i] = [bent[i - 1, 0] + c * z[0] - s * z[1], bent[i - 1, 1] + s * z[0] + c * z[1],
                   bent[i - 1, 2] + z[2] + 0.004]  # fmt: skip
    cams = np.stack([camera_matrix_in_map(p, *HEAD, 0) for p in bent])
    lm = triangulate(scene.xy[:n], scene.desc[:n], cams, k, True)
    kp_xy = np.concatenate(scene.xy[:n])
    frame = np.repeat(np.arange(n), [len(a) for a in scene.xy[:n]])
    tracks = tracks_from_links(kp_xy.shape[0], lm.matches)
    free = BundleProblem(bent, heads, [0] * n, k, kp_xy, frame, tracks, lm.points,
                         odometry_edges(bent))  # fmt: skip
    held = dataclasses.replace(free, priors=scene.truth[:n].copy(), prior_sigma=(0.05, 0.005))
    err_free = _errors(bundle_adjust(free).poses, scene.truth[:n])
    err_held = _errors(bundle_adjust(held).poses, scene.truth[:n])
    assert err_held[1] < 0.5 * err_free[1]
    assert err_held[0] < err_free[0]


def test_far_pictures_pair_with_far_pictures_far_apart() -> None:
    """Wall pictures pair with their nearest wall pictures, as without far pictures; a far
    picture (walls 2-7 m away) pairs only with far pictures 0.6-2 m off, spread over that
    range, so its points are triangulated over long baselines."""
    from naoloc.mapping.landmarks import FAR_BASELINE_M, select_pairs

    # A walk along +x: a wall picture every 0.2 m (head right), a far picture every 0.4 m
    # (head left, across the room), appended after the wall pictures.
    walls = [camera_matrix_in_map((0.2 * i, 0.0, 0.0), -1.2, -0.6) for i in range(20)]
    far = [camera_matrix_in_map((0.4 * i, 0.0, 0.0), 1.3, -0.3) for i in range(10)]
    cams = np.stack(walls + far)
    alone = select_pairs(np.stack(walls))
    pairs = select_pairs(cams, far_from=20)
    assert [p for p in pairs if p[1] < 20] == alone
    far_pairs = [p for p in pairs if p[0] >= 20]
    assert len(far_pairs) == len(pairs) - len(alone)  # no wall-far pair
    lengths = [0.4 * abs(i - j) for i, j in far_pairs]
    assert min(lengths) >= FAR_BASELINE_M[0] - 1e-9 and max(lengths) <= FAR_BASELINE_M[1] + 1e-9
    assert max(lengths) >= 1.6  # spread: not only the nearest allowed ones
    assert select_pairs(cams, far_from=None) != pairs  # as one kind, nearest first
