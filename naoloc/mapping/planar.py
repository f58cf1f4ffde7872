"""The one planar least-squares solver: Gauss-Newton on a pose (x, y, theta).

Used by the localizer (a robot pose from 3-D to 2-D matches of several queries) and by the
pose graph's loop closures (naoloc.mapping.posegraph.planar_pnp). The residuals are pixel
errors whose Jacobian by the three pose unknowns is taken by forward differences (three
extra projections per iteration, cheap next to the matching that found the points).
``tools/bench_solvers.py`` compares it with ``scipy.optimize.least_squares`` on the same
problems.

Frames: the pose is whatever the caller's residuals take (a robot pose in the map frame
or in another keyframe's frame), metres and radians.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: ``linearise(x)`` returns the residuals at ``x`` and a function giving them at nearby
#: poses (the same observations), or None to give up (e.g. too few inliers at ``x``).
Linearise = Callable[[np.ndarray], "tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]] | None"]
#: ``retract(x, d)``: the pose ``x`` moved by the step ``d``.
Retract = Callable[[np.ndarray, np.ndarray], np.ndarray]


def add(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The additive retraction ``x + d`` (a step in the pose's own coordinates)."""
    return x + d


@dataclass(frozen=True)
class PlanarFit:
    """Result of :func:`solve_planar`.

    Attributes:
        x: ``(3,)`` the solved pose.
        residuals: ``(m,)`` residuals of the last linearisation (before its step).
        jacobian: ``(m, 3)`` their Jacobian by the step ``d`` of ``retract(x, d)``.
        iterations: Iterations run.
    """

    x: np.ndarray
    residuals: np.ndarray
    jacobian: np.ndarray
    iterations: int


def solve_planar(
    linearise: Linearise,
    x0: np.ndarray,
    *,
    iterations: int,
    fd_step: float,
    tol: float,
    retract: Retract = add,
    stop_on_nonfinite: bool = False,
) -> PlanarFit | None:
    """Gauss-Newton on a 3-vector with a forward-difference Jacobian.

    Args:
        linearise: Residuals at a pose and a function of nearby poses (see ``Linearise``).
        x0: ``(3,)`` initial pose.
        iterations: Iterations at most.
        fd_step: Finite-difference step of each unknown (in the retraction's coordinates).
        tol: Stop when no component of a step exceeds this.
        retract: How a step moves the pose (:func:`add`, or a composition in the pose's
            own frame).
        stop_on_nonfinite: Stop (keeping the current pose) when residuals or Jacobian are
            not finite, instead of taking the step.

    Returns:
        The fit; None when ``linearise`` gave up.
    """
    x = x0.astype(np.float64).copy()
    res = np.zeros(0)
    jac = np.zeros((0, 3))
    done = 0
    for done in range(1, iterations + 1):  # noqa: B007 - the count is returned
        lin = linearise(x)
        if lin is None:
            return None
        res, at = lin
        jac = np.empty((res.size, 3))
        for k in range(3):
            d = np.zeros(3)
            d[k] = fd_step
            jac[:, k] = (at(retract(x, d)) - res) / fd_step
        if stop_on_nonfinite and not (np.isfinite(jac).all() and np.isfinite(res).all()):
            break
        step, *_ = np.linalg.lstsq(jac, -res, rcond=None)
        x = retract(x, step)
        if np.abs(step).max() < tol:
            break
    return PlanarFit(x, res, jac, done)
