"""Pose2D against almath's formulas (as the NAOqi 2.x almath reference defines them)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse, relative_pose, wrap_angles

finite = st.floats(min_value=-50.0, max_value=50.0, allow_nan=False)
angle = st.floats(min_value=-20.0, max_value=20.0, allow_nan=False)
poses = st.builds(Pose2D, finite, finite, angle)


def test_compose_matches_almath_formula() -> None:
    p1, p2 = Pose2D(1.0, 2.0, 0.5), Pose2D(-0.3, 0.7, 1.2)
    p = p1 * p2
    assert p.x == pytest.approx(1.0 + math.cos(0.5) * -0.3 - math.sin(0.5) * 0.7)
    assert p.y == pytest.approx(2.0 + math.sin(0.5) * -0.3 + math.cos(0.5) * 0.7)
    assert p.theta == pytest.approx(1.7)  # not normalised


def test_inverse_matches_almath_formula() -> None:
    p = Pose2D(1.0, -2.0, 2.5)
    inv = pose2DInverse(p)
    t = -2.5
    assert inv.theta == pytest.approx(t)
    assert inv.x == pytest.approx(-(1.0 * math.cos(t) - -2.0 * math.sin(t)))
    assert inv.y == pytest.approx(-(-2.0 * math.cos(t) + 1.0 * math.sin(t)))


@given(poses)
def test_inverse_composes_to_identity(p: Pose2D) -> None:
    ident = p * pose2DInverse(p)
    assert ident.x == pytest.approx(0.0, abs=1e-9)
    assert ident.y == pytest.approx(0.0, abs=1e-9)
    assert modulo2PI(ident.theta) == pytest.approx(0.0, abs=1e-9)


@given(poses, poses)
def test_relative_pose_recovers_the_move(start: Pose2D, move: Pose2D) -> None:
    end = start * move
    rel = relative_pose(start, end)
    assert rel.x == pytest.approx(move.x, abs=1e-7)
    assert rel.y == pytest.approx(move.y, abs=1e-7)
    assert math.cos(rel.theta - move.theta) == pytest.approx(1.0, abs=1e-9)
    assert -math.pi < rel.theta <= math.pi


@pytest.mark.parametrize(
    ("angle_in", "expected"),
    [(0.0, 0.0), (math.pi, math.pi), (-math.pi, math.pi), (3 * math.pi, math.pi),
     (2 * math.pi, 0.0), (-0.5, -0.5), (7.0, 7.0 - 2 * math.pi)],
)  # fmt: skip
def test_modulo2pi_range(angle_in: float, expected: float) -> None:
    assert modulo2PI(angle_in) == pytest.approx(expected)


@given(st.floats(min_value=-1e3, max_value=1e3, allow_nan=False))
def test_modulo2pi_is_half_open_and_same_direction(a: float) -> None:
    w = modulo2PI(a)
    assert -math.pi < w <= math.pi + 1e-12
    assert math.cos(w) == pytest.approx(math.cos(a), abs=1e-9)
    assert math.sin(w) == pytest.approx(math.sin(a), abs=1e-9)


def test_wrap_angles_matches_scalar() -> None:
    a = np.linspace(-20, 20, 101)
    np.testing.assert_allclose(wrap_angles(a), [modulo2PI(v) for v in a], atol=1e-12)


def test_list_round_trip_and_distance() -> None:
    p = Pose2D.from_list([1, 2, 3])
    assert p.to_list() == [1.0, 2.0, 3.0]
    assert list(p) == [1.0, 2.0, 3.0]
    assert p.distance(Pose2D(4.0, 6.0, 0.0)) == pytest.approx(5.0)


def test_midpose_and_mid_transform_halve_a_motion() -> None:
    from naoloc.geometry import mid_transform, midpose

    a, b = Pose2D(1.0, 2.0, 3.1), Pose2D(1.2, 1.8, -3.1)  # across the +-pi seam
    mid = midpose(a, b)
    assert (mid.x, mid.y) == pytest.approx((1.1, 1.9))
    assert abs(math.remainder(mid.theta - math.pi, 2 * math.pi)) < 1e-9

    def rz(t: float, x: float) -> list[float]:
        c, s = math.cos(t), math.sin(t)
        return [c, -s, 0, x, s, c, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1]

    m = np.array(mid_transform(rz(0.1, 0.0), rz(0.3, 0.2))).reshape(4, 4)
    assert m == pytest.approx(np.array(rz(0.2, 0.1)).reshape(4, 4), abs=2e-3)
    assert np.linalg.det(m[:3, :3]) == pytest.approx(1.0)
