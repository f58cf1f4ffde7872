"""CI's short run of tools/bench_attack.py: no deaths, tracebacks or hangs, stops in time.

The full run (12,000 fuzzed messages, a 20,000-call flood, every transport, SIGTERM)
gives the figures of docs/RESULTS.md ("Server under attack"); this one runs the same
attacks smaller against the two servers naoloc implements itself.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = [pytest.mark.net, pytest.mark.slow]
ROOT = Path(__file__).resolve().parents[2]


def test_the_short_attack_benchmark_passes() -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "bench_attack.py"), "--short",
         "--transports", "qimessaging,zmq"],
        capture_output=True, text=True, env=env, timeout=600,
    )  # fmt: skip
    out = run.stdout
    assert run.returncode == 0, run.stderr[-2000:]
    assert out.strip().endswith("no deaths, tracebacks or hangs"), out[-2000:]
    stops = [float(ms) for ms in re.findall(r"stopMove +([\d.]+) ms", out)]
    assert len(stops) >= 10 and max(stops) < 500, out
    frozen = [float(ms) for ms in re.findall(r"robot stopped after +([\d.]+) ms", out)]
    assert len(frozen) == 2 and max(frozen) < 500, out
    growth = [float(mb) for mb in re.findall(r"RSS growth ([+-][\d.]+) MB", out)]
    assert len(growth) == 2 and max(growth) <= 50, out
    assert "robot moved: False" in out
