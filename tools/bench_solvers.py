"""Planar least-squares solvers compared on the two problems naoloc solves with them.

Usage::

    .venv/bin/python tools/bench_solvers.py [--trials 300] [--old-rev REV]

Problems (seeded, synthetic, QVGA camera on the NAO head at the survey's head angles):

* ``localizer``: a robot pose (x, y, theta) in the map from 60 landmarks seen by one query,
  0.5 px noise, start 5 cm / 2 deg off (``naoloc.mapping.localizer._refine``);
* ``loop closure``: the same with 40 points in another keyframe's frame, 10 % outliers
  gated at 3 px each iteration, start 1 cm / 0.3 deg off as after the RANSAC PnP that
  precedes it (``posegraph.planar_pnp``).

Solvers: the current one (``naoloc.mapping.planar.solve_planar``), the two Gauss-Newton
loops it replaced (loaded from git revision ``--old-rev``; they must agree bit for bit),
and ``scipy.optimize.least_squares`` (``lm`` and ``trf``, 2-point Jacobian) on the same
residuals when scipy is installed. Prints the median time per solve and the median and 95th
percentile position (mm) and heading (mrad) errors against the truth.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import math  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from types import ModuleType  # noqa: E402

import numpy as np  # noqa: E402

from naoloc.geometry import robot_matrix  # noqa: E402
from naoloc.mapping import localizer, posegraph  # noqa: E402
from naoloc.robot.keyframe import CameraInfo, camera_in_robot  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OLD_REV = "670fda5d215446d16c5736d5a718c3f651a35f44"  # the two solvers before the merge
CAM = CameraInfo(320, 240, math.radians(56.3), math.radians(43.7), 0)
HEAD = (-math.pi / 2, -0.2)


def load_old(rev: str, name: str) -> ModuleType:
    """``naoloc/mapping/<name>.py`` of git revision ``rev`` as a stand-alone module."""
    text = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:naoloc/mapping/{name}.py"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    path = Path(tempfile.mkdtemp()) / f"{name}_old.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location(f"{name}_old", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[f"{name}_old"] = module
    spec.loader.exec_module(module)
    return module


def _points_in_view(rng: np.random.Generator, t_cam: np.ndarray, n: int) -> np.ndarray:
    """``n`` points 1-5 m in front of a camera (``T_frame_cam``), in the frame."""
    k = CAM.matrix()
    out = []
    while len(out) < n:
        u, v, d = rng.uniform(5, 315), rng.uniform(5, 235), rng.uniform(1.0, 5.0)
        ray = np.linalg.solve(k, np.array([u, v, 1.0])) * d
        out.append(t_cam[:3, :3] @ ray + t_cam[:3, 3])
    return np.array(out)


def localizer_problem(rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Truth, start, ``mats`` (n, 3, 4), map points (n, 3) and pixels (n, 2)."""
    truth = np.array([rng.uniform(0.5, 3.5), rng.uniform(0.5, 3.5), rng.uniform(-3, 3)])
    c_q = camera_in_robot(*HEAD, 0)
    pts = _points_in_view(rng, robot_matrix(*truth) @ c_q, 60)
    m_q = CAM.matrix() @ np.linalg.inv(c_q)[:3, :]
    mats = np.repeat(m_q[None], len(pts), axis=0)
    uv, _ = localizer._project(truth, mats, pts)
    px = uv + rng.normal(0, 0.5, uv.shape)
    start = truth + rng.normal(0, [0.05, 0.05, 0.035])
    return truth, start, mats, pts, px


def loop_problem(rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Truth, start, points (n, 3) in keyframe i's frame, pixels (n, 2), c_j."""
    truth = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.5, 0.5)])
    c_j = camera_in_robot(*HEAD, 0)
    obj = _points_in_view(rng, robot_matrix(*truth) @ c_j, 40)
    uv, _ = posegraph._project_planar(truth, obj, CAM.matrix(), c_j)
    img = uv + rng.normal(0, 0.5, uv.shape)
    bad = rng.random(len(img)) < 0.1
    img[bad] += rng.uniform(-40, 40, (int(bad.sum()), 2))
    start = truth + rng.normal(0, [0.01, 0.01, 0.005])  # as a RANSAC PnP start
    return truth, start, obj, img, c_j


def _scipy_localizer(method: str) -> Callable[..., np.ndarray]:
    from scipy.optimize import least_squares

    def solve(start: np.ndarray, mats: np.ndarray, pts: np.ndarray, px: np.ndarray) -> np.ndarray:
        def fun(p: np.ndarray) -> np.ndarray:
            return (localizer._project(p, mats, pts)[0] - px).ravel()

        return np.asarray(least_squares(fun, start, method=method, jac="2-point").x)

    return solve


def _scipy_loop(method: str) -> Callable[..., np.ndarray | None]:
    from scipy.optimize import least_squares

    k = CAM.matrix()

    def solve(
        start: np.ndarray, obj: np.ndarray, img: np.ndarray, c_j: np.ndarray
    ) -> np.ndarray | None:
        z = start
        for _ in range(2):  # gate at the start, solve, gate again, solve
            uv, depth = posegraph._project_planar(z, obj, k, c_j)
            keep = (np.linalg.norm(uv - img, axis=1) < 3.0) & (depth > 0.05)
            if keep.sum() < 15:
                return None
            o, i = obj[keep], img[keep]

            def fun(zz: np.ndarray, o: np.ndarray = o, i: np.ndarray = i) -> np.ndarray:
                return (posegraph._project_planar(zz, o, k, c_j)[0] - i).ravel()

            z = np.asarray(least_squares(fun, z, method=method, jac="2-point").x)
        return z

    return solve


def _report(label: str, times: list[float], errs: list[np.ndarray], fails: int) -> None:
    e = np.array(errs) if errs else np.zeros((1, 3))
    pos = 1000 * np.hypot(e[:, 0], e[:, 1])
    th = 1000 * np.abs(np.remainder(e[:, 2] + np.pi, 2 * np.pi) - np.pi)
    print(
        f"  {label:34s} {1e6 * float(np.median(times)):8.0f} us   "
        f"pos {np.median(pos):6.2f} / {np.percentile(pos, 95):6.2f} mm   "
        f"heading {np.median(th):5.2f} / {np.percentile(th, 95):5.2f} mrad   failed {fails}"
    )


def run(trials: int, old_rev: str) -> None:
    old_loc, old_pg = load_old(old_rev, "localizer"), load_old(old_rev, "posegraph")
    rng = np.random.default_rng(0)
    loc_problems = [localizer_problem(rng) for _ in range(trials)]
    loop_problems = [loop_problem(rng) for _ in range(trials)]
    kmat = CAM.matrix()

    loc_solvers: dict[str, Callable[..., np.ndarray | None]] = {
        "naoloc.mapping.planar (current)": localizer._refine,
        f"old localizer._refine ({old_rev[:7]})": old_loc._refine,
    }
    loop_solvers: dict[str, Callable[..., np.ndarray | None]] = {
        "naoloc.mapping.planar (current)": lambda s, o, i, c: _first(
            posegraph.planar_pnp(s, o, i, kmat, c)
        ),
        f"old posegraph.planar_pnp ({old_rev[:7]})": lambda s, o, i, c: _first(
            old_pg.planar_pnp(s, o, i, kmat, c)
        ),
    }
    try:
        import scipy

        for method in ("lm", "trf"):
            loc_solvers[f"scipy {scipy.__version__} least_squares {method}"] = _scipy_localizer(
                method
            )
            loop_solvers[f"scipy {scipy.__version__} least_squares {method}"] = _scipy_loop(method)
    except ImportError:
        print("(scipy is not installed: its rows are left out)")

    for title, solvers, problems in (
        ("localizer: 60 landmarks, 0.5 px noise", loc_solvers, loc_problems),
        ("loop closure: 40 points, 10 % outliers", loop_solvers, loop_problems),
    ):
        print(f"\n{title} ({trials} problems): median time, median / p95 errors")
        answers: dict[str, list[np.ndarray | None]] = {}
        for label, solve in solvers.items():
            times, errs, fails, out = [], [], 0, []
            for truth, start, *rest in problems:
                t = time.perf_counter()
                got = solve(start, *rest)
                times.append(time.perf_counter() - t)
                out.append(got)
                if got is None:
                    fails += 1
                else:
                    errs.append(got - truth)
            answers[label] = out
            _report(label, times, errs, fails)
        cur, old = list(answers.values())[:2]
        same = all(
            (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))
            for a, b in zip(cur, old, strict=True)
        )
        print(f"  current == old, bit for bit, on every problem: {same}")


def _first(fit: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray | None:
    return None if fit is None else fit[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=300, help="problems of each kind")
    parser.add_argument("--old-rev", default=OLD_REV, help="git revision of the old solvers")
    args = parser.parse_args()
    run(args.trials, args.old_rev)


if __name__ == "__main__":
    main()
