"""Issue 33, item 4: one picture style: poses with heading arrows, 95 % ellipses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.geometry import Pose2D
from naoloc.viz.plots import ELLIPSE_CHI2, STYLE, ellipse, new_figure, pose_mark


def test_a_pose_is_a_dot_an_arrow_along_its_heading_and_its_ellipse() -> None:
    ax = new_figure(4, 4).add_subplot(1, 1, 1)
    cov = np.diag([0.04, 0.01, 0.001])
    pose_mark(ax, Pose2D(1.0, 2.0, math.pi / 2), "estimate", "estimate", cov=cov, length=0.5)
    (dot,) = ax.lines
    assert dot.get_color() == STYLE["estimate"][0] and dot.get_label() == "estimate"
    (arrow,) = ax.texts
    assert arrow.xy == pytest.approx((1.0, 2.5))  # the heading, 0.5 m long
    (patch,) = ax.patches
    assert patch.width == pytest.approx(2 * math.sqrt(ELLIPSE_CHI2 * 0.04))
    assert patch.height == pytest.approx(2 * math.sqrt(ELLIPSE_CHI2 * 0.01))
    assert patch.angle % 180 == pytest.approx(0.0, abs=1e-6)  # the long axis along x


def test_an_ellipse_follows_the_covariance_axes() -> None:
    ax = new_figure(4, 4).add_subplot(1, 1, 1)
    c = np.array([[0.025, 0.015], [0.015, 0.025]])  # long axis at 45 degrees
    ellipse(ax, Pose2D(0.0, 0.0, 0.0), c, "black")
    (patch,) = ax.patches
    assert patch.angle % 180 == pytest.approx(45.0)
    ellipse(ax, Pose2D(0.0, 0.0, 0.0), np.full((3, 3), np.nan), "black")  # unknown: nothing
    assert len(ax.patches) == 1


def test_truth_and_estimate_keep_their_colours_everywhere() -> None:
    assert STYLE["truth"][0] == "black" and STYLE["estimate"][0] == "tab:green"
    assert len({color for color, _ in STYLE.values()} - {"tab:green"}) == len(STYLE) - 2
