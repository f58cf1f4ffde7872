"""Hardening figures: how fast and how small bad input is refused, and fuzz throughput.

Prints, for each bomb config, the wall time and peak memory of ``naoloc survey -c BOMB``
(each in its own process), then the messages per second and the memory growth of the
zmq and libqi virtual NAOqi under 10,000 fuzz messages each.

Run: ``PYTHONPATH=. .venv/bin/python tools/bench_hardening.py``
"""

from __future__ import annotations

import importlib.util
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from naoloc.backends.naoqi.testing import served  # noqa: E402
from tests.fuzz.libqi_fuzzer import fuzz_libqi  # noqa: E402
from tests.fuzz.proc import rss_mb  # noqa: E402
from tests.fuzz.zmq_fuzzer import fuzz_zmq  # noqa: E402
from tests.integration.test_fuzz_config import BOMBS, CORPUS  # noqa: E402
from tests.integration.test_fuzz_config import _run as run_cli  # noqa: E402

FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
MESSAGES = 10_000


def bomb_figures() -> None:
    """Wall time and peak RSS (VmHWM) of the CLI refusing each bomb, and of a missing file."""
    with tempfile.TemporaryDirectory() as tmp:
        for name in ["missing_file", *BOMBS]:
            path = Path(tmp) / f"{name}.yaml"
            if name != "missing_file":
                path.write_bytes(CORPUS[name])
            started = time.perf_counter()
            code, err, peak_mb = run_cli(["survey", "-c", str(path), "-o", f"{tmp}/x.mcap"])
            wall = time.perf_counter() - started
            lines = err.strip().splitlines()
            print(
                f"bomb {name:14s} exit {code}  {wall:5.2f} s  peak {peak_mb:6.1f} MB  "
                f"{len(lines)} line(s): {err.strip()[-70:]}"
            )


def fuzz_figures() -> None:
    """Fuzz throughput and server memory growth for each transport."""
    transports = ["zmq"] + (["libqi"] if importlib.util.find_spec("qi") else [])
    for transport in transports:
        fuzz = fuzz_zmq if transport == "zmq" else fuzz_libqi
        with served(FAKE, transport) as server:
            fuzz(server.url, 300, 1)
            before = rss_mb(server.process.pid)
            started = time.perf_counter()
            report = fuzz(server.url, MESSAGES, 2)
            wall = time.perf_counter() - started
            time.sleep(0.5)
            growth = rss_mb(server.process.pid) - before
            alive = server.process.poll() is None
            print(
                f"fuzz {transport:6s} {report.sent} messages in {wall:5.2f} s "
                f"({report.sent / wall:7.0f}/s)  server RSS {before:6.1f} MB, growth "
                f"{growth:+5.1f} MB, alive {alive}"
            )


if __name__ == "__main__":
    bomb_figures()
    fuzz_figures()
