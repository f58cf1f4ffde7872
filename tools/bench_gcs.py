"""Benchmark of GCS training on one core, old and current implementation in the same run.

Usage::

    .venv/bin/python tools/bench_gcs.py [--repeats 5] [--map MAP.npz] [--old-rev REV]

Trains on 164 x 256-d L2-normalised histograms (by default a seeded synthetic survey:
TF-IDF-like word counts drifting along a closed path; ``--map`` takes a map file's
histograms instead, padded or cut to 164 rows) for 100/200/300 neurons and epochs, and
prints best-of-N times and microseconds per adaptation step. When ``--old-rev`` names a
git revision (default: the implementation before the speed-up), its ``gcs.py`` is loaded
from git and timed in the same run, and the two networks are compared.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from types import ModuleType  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from naoloc.mapping import gcs  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OLD_REV = "a8242abb4e022fadd7084946e26e66820baf1536"  # last gcs.py before the speed-up
IMAGES, WORDS = 164, 256


def synthetic_histograms(seed: int, n: int = IMAGES, words: int = WORDS) -> np.ndarray:
    """``(n, words)`` L2-normalised TF-IDF-like histograms of a survey along a closed path.

    Each image sees about 60 keypoints drawn from a word distribution that drifts slowly
    along the path (neighbouring images share most words), like a room survey.
    """
    rng = np.random.default_rng(seed)
    anchors = rng.gamma(0.3, 1.0, (8, words))  # word preferences at 8 places on the loop
    out = np.zeros((n, words))
    for j in range(n):
        pos = 8.0 * j / n
        a, frac = int(pos) % 8, pos - int(pos)
        p = (1.0 - frac) * anchors[a] + frac * anchors[(a + 1) % 8]
        out[j] = rng.multinomial(60, p / p.sum())
    idf = np.log(n / np.maximum((out > 0).sum(axis=0), 1))
    out = out / out.sum(axis=1, keepdims=True) * idf
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-300)


def map_histograms(path: Path, seed: int) -> np.ndarray:
    """A map file's histograms, cut or padded (jittered repeats) to 164 rows."""
    with np.load(path, allow_pickle=False) as z:
        h = np.asarray(z["histograms"], dtype=np.float64)
    rng = np.random.default_rng(seed)
    while h.shape[0] < IMAGES:
        extra = h[rng.choice(h.shape[0], IMAGES - h.shape[0])]
        h = np.concatenate([h, extra + 1e-3 * rng.random(extra.shape)])
    return h[:IMAGES]


def load_old(rev: str) -> ModuleType:
    """The ``naoloc/mapping/gcs.py`` of git revision ``rev`` as a module."""
    text = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:naoloc/mapping/gcs.py"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    path = Path(tempfile.mkdtemp()) / "gcs_old.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("gcs_old", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["gcs_old"] = module  # dataclasses look their module up while decorating
    spec.loader.exec_module(module)
    return module


def best_time(train: Any, x: np.ndarray, size: int, seed: int, repeats: int) -> tuple[float, Any]:
    """Best process CPU time (s) of ``repeats`` trainings, and the last network.

    CPU time, not wall time: the machine is shared, and a descheduled process is not slow.
    """
    best, out = float("inf"), None
    for _ in range(repeats):
        t = time.process_time()
        out = train(x, size, size, seed)
        best = min(best, time.process_time() - t)
    return best, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per size (best)")
    parser.add_argument("--seed", type=int, default=0, help="data and GCS seed")
    parser.add_argument("--map", type=Path, default=None, help="take histograms from a map")
    parser.add_argument("--old-rev", default=OLD_REV, help="git revision to compare ('' = none)")
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 300])
    args = parser.parse_args()
    x = map_histograms(args.map, args.seed) if args.map else synthetic_histograms(args.seed)
    old = load_old(args.old_rev) if args.old_rev else None
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; data {x.shape}")
    print("CPU time, best of N runs (us per step):")
    print("neurons/epochs  steps   current               old                  speed-up  same net")
    for size in args.sizes:
        steps = size * x.shape[0]
        t_new, net = best_time(gcs.train_gcs, x, size, args.seed, args.repeats)
        again = gcs.train_gcs(x, size, size, args.seed)
        if not np.array_equal(net.weights, again.weights):
            sys.exit("current implementation is not deterministic")
        line = f"  {size:3d}/{size:3d}     {steps:6d}  {t_new:6.3f} s ({t_new / steps * 1e6:5.2f})"
        if old is not None:
            t_old, ref = best_time(old.train_gcs, x, size, args.seed, min(args.repeats, 3))
            same = (
                net.size == ref.size
                and np.array_equal(net.triangles, ref.triangles)
                and (net.inserted, net.removed) == (ref.inserted, ref.removed)
            )
            diff = float(np.abs(net.weights - ref.weights).max()) if same else float("nan")
            line += (
                f"  {t_old:6.3f} s ({t_old / steps * 1e6:5.2f})  {t_old / t_new:5.1f}x"
                f"  {'yes' if same else 'NO'} (max |dw| {diff:.1e})"
            )
        print(line)
    print(f"load average {os.getloadavg()[0]:.2f}; target: 300/300 in <= 0.5 s on one core")


if __name__ == "__main__":
    main()
