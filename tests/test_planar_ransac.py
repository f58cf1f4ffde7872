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
