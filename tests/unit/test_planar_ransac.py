"""The two-point planar RANSAC over a whole scan's matches (naoloc.mapping.planar_ransac)."""

from __future__ import annotations

import math

import numpy as np

from naoloc.mapping.planar_ransac import lift, planar_hypotheses

K = np.array([[278.0, 0.0, 160.0], [0.0, 278.0, 120.0], [0.0, 0.0, 1.0]])


def _camera(yaw: float, pitch: float = 0.3, height: float = 0.5) -> np.ndarray:
    """3 x 4 projection of a camera on the robot (robot frame -> pixels), looking at
    ``yaw`` and ``pitch`` up (rad)."""
    fwd = np.array(
        [math.cos(yaw) * math.cos(pitch), math.sin(yaw) * math.cos(pitch), math.sin(pitch)]
    )
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.cross(fwd, right)
    rot = np.stack([right, down, fwd])  # rows: camera axes in the robot frame
    centre = np.array([0.0, 0.0, height])
    return K @ np.c_[rot, -rot @ centre]


def _scene(
    pose: tuple[float, float, float], inliers: int, outliers: int, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Matches of a 7-yaw scan at ``pose`` in a 6 x 6 m room: ``inliers`` true ones spread
    over the pictures, ``outliers`` with random map points."""
    rng = np.random.default_rng(seed)
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    mats, pts, px = [], [], []
    yaws = np.linspace(-2.0, 2.0, 7)
    while len(pts) < inliers:
        p = np.array([rng.uniform(0, 6), rng.uniform(0, 6), rng.uniform(0.8, 1.8)])
        pr = np.array([c * (p[0] - x) + s * (p[1] - y), -s * (p[0] - x) + c * (p[1] - y), p[2]])
        for yaw in rng.permutation(yaws):
            m = _camera(float(yaw))
            h = m[:, :3] @ pr + m[:, 3]
            if h[2] > 0.3:
                uv = h[:2] / h[2]
                if 0 <= uv[0] < 320 and 0 <= uv[1] < 240:
                    mats.append(m)
                    pts.append(p)
                    px.append(uv + rng.normal(0, 0.5, 2))
                    break
    for _ in range(outliers):
        mats.append(_camera(float(rng.choice(yaws))))
        pts.append(np.array([rng.uniform(0, 6), rng.uniform(0, 6), rng.uniform(0.8, 1.8)]))
        px.append(np.array([rng.uniform(0, 320), rng.uniform(0, 240)]))
    order = rng.permutation(len(pts))
    return np.array(mats)[order], np.array(pts)[order], np.array(px)[order]


def test_lift_puts_a_true_match_on_the_floor_where_it_is() -> None:
    mats, pts, px = _scene((0.0, 0.0, 0.0), 30, 0, seed=1)
    centres, _az, lifted, _r, valid = lift(mats, pts, px)
    assert valid.all()
    np.testing.assert_allclose(lifted, pts[:, :2], atol=0.15)  # 0.5 px noise, 5 m away
    np.testing.assert_allclose(centres, 0.0, atol=1e-9)


def test_finds_the_pose_from_few_inliers_among_many_outliers() -> None:
    truth = (2.3, 4.1, 1.1)
    # 20 inliers in 420 matches (about 3 per picture: no single picture could be solved)
    mats, pts, px = _scene(truth, 20, 400, seed=7)
    hyps = planar_hypotheses(mats, pts, px, bearing_tol_rad=4 / 278, samples=2000, keep=3, seed=0)
    assert hyps
    count, pose = hyps[0]
    assert count >= 15
    assert math.hypot(pose[0] - truth[0], pose[1] - truth[1]) < 0.05
    assert abs(math.remainder(pose[2] - truth[2], 2 * math.pi)) < 0.02


def test_same_seed_same_hypotheses_and_nothing_from_noise() -> None:
    mats, pts, px = _scene((1.0, 1.0, 0.0), 20, 300, seed=3)
    a = planar_hypotheses(mats, pts, px, bearing_tol_rad=0.015, samples=500, keep=3, seed=5)
    b = planar_hypotheses(mats, pts, px, bearing_tol_rad=0.015, samples=500, keep=3, seed=5)
    assert [n for n, _ in a] == [n for n, _ in b]
    assert all(np.array_equal(p, q) for (_, p), (_, q) in zip(a, b, strict=True))
    # Outliers only: whatever wins has few inliers (the caller's reprojection check and
    # min_pnp_inliers then reject it).
    mats, pts, px = _scene((1.0, 1.0, 0.0), 0, 300, seed=4)
    noise = planar_hypotheses(mats, pts, px, bearing_tol_rad=0.015, samples=2000, keep=1, seed=0)
    assert not noise or noise[0][0] < 12
    assert planar_hypotheses(mats[:1], pts[:1], px[:1], bearing_tol_rad=0.015, samples=10,
                             keep=1, seed=0) == []  # fmt: skip


def test_float32_scoring_counts_as_the_angles_do() -> None:
    """The float32 scoring without angles counts the inliers the bearing-angle formula
    counts (to one, where a point sits on a threshold)."""
    from naoloc.mapping.planar_ransac import _score

    rng = np.random.default_rng(3)
    n = 2000
    points = rng.uniform(0.0, 6.0, (n, 2))
    centres = rng.normal(0.0, 0.05, (n, 2))
    truth = np.array([2.0, 3.0, 0.7])
    c, s = math.cos(truth[2]), math.sin(truth[2])
    d = points - truth[:2]
    rx = c * d[:, 0] + s * d[:, 1] - centres[:, 0]
    ry = -s * d[:, 0] + c * d[:, 1] - centres[:, 1]
    azimuths = np.arctan2(ry, rx) + rng.normal(0.0, 0.02, n)
    ranges = np.hypot(rx, ry) * rng.uniform(0.5, 2.0, n)
    poses = np.vstack([truth, rng.uniform([0, 0, -3], [6, 6, 3], (300, 3))])
    tol = 0.02

    cp, sp = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    dx, dy = points[None, :, 0] - poses[:, 0, None], points[None, :, 1] - poses[:, 1, None]
    qx = cp * dx + sp * dy - centres[None, :, 0]
    qy = -sp * dx + cp * dy - centres[None, :, 1]
    err = np.abs((np.arctan2(qy, qx) - azimuths + np.pi) % (2 * np.pi) - np.pi)
    dist = np.hypot(qx, qy)
    near = (dist < 1.6 * ranges + 0.1) & (ranges < 1.6 * dist + 0.1)
    expected = ((err < tol) & near).sum(axis=1)

    got = _score(poses, centres, azimuths, ranges, points, tol)
    assert np.abs(got - expected).max() <= 1
    assert got[0] == expected[0] > 0.3 * n and int(np.argmax(got)) == 0
