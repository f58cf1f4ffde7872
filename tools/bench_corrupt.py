"""Time and peak memory of ``naoloc build-map`` rejecting each corrupt dataset.

Usage::

    .venv/bin/python tools/bench_corrupt.py [--only png-bomb,zstd-bomb] [--keep DIR]

Generates the corpus of tests/corrupt_datasets.py (bombs included: a PNG whose header
declares 30000 x 30000 px, 2.7 GB of pixels; a JPEG declaring 60000 x 60000; a zstd chunk
that inflates to 256 MiB; a chunk declaring 1 GiB...), runs the real CLI on each file in a
fresh process and prints its exit code, wall time (s, process start included), peak
resident memory (MB, ``wait4``; this script stays small, so the fork adds little) and the
one stderr line. The acceptance bound is 2 s and 500 MB per bomb.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

from corrupt_datasets import corpus  # noqa: E402


def run_one(path: Path, cfg: Path, out: Path) -> tuple[int, float, float, str]:
    """Exit code, wall seconds, peak MB and stderr of one ``build-map`` process."""
    argv = [sys.executable, "-m", "naoloc.app.cli", "build-map", "-c", str(cfg), "-d", str(path),
            "-o", str(out)]  # fmt: skip
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    assert proc.stderr is not None
    err = proc.stderr.read().decode(errors="replace")
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, wall, usage.ru_maxrss / 1024.0, err.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="comma list of case names")
    parser.add_argument("--keep", type=Path, default=None, help="write the corpus here")
    args = parser.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="naoloc-corpus-"))
    cases = corpus(folder)
    wanted = {n for n in args.only.split(",") if n}
    cfg = folder / "cfg.yaml"
    cfg.write_text("robot: {backend: fake}\nmap: {neurons: 40, epochs: 5}\n")
    print(f"{'case':<22} {'exit':>4} {'wall s':>7} {'peak MB':>8}  stderr")
    worst_wall = worst_mb = 0.0
    for name, path, _expected in cases:
        if wanted and name not in wanted:
            continue
        code, wall, peak, err = run_one(path, cfg, folder / "m.npz")
        worst_wall, worst_mb = max(worst_wall, wall), max(worst_mb, peak)
        line = err.replace(str(folder) + "/", "")
        print(f"{name:<22} {code:>4} {wall:7.2f} {peak:8.0f}  {line[:110]}")
    print(f"worst: {worst_wall:.2f} s, {worst_mb:.0f} MB over {len(wanted) or len(cases)} files")


if __name__ == "__main__":
    main()
