"""``evaluate --executor ray``: the same tasks on a local Ray cluster give the same summary.

Skipped when Ray is not installed (it is the optional extra ``ray``). Everything but the
measured wall times (``*_s``, ``*_ms*``, ``timings``) and the output folder is compared.
The Ray run is a child process: ``ray.init`` replaces the process's fatal-signal handlers,
and a test runner without faulthandler dies of a native crash without a word.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.errors import ConfigError
from naoloc.evaluation.runner import make_executor

TINY = {
    "robot": {"backend": "fake"},
    "world": {
        "room": {"size_m": [3.2, 3.2], "seed": 5, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },  # the pre-issue-11 world: not about realism
    "survey": {"laps": 1, "step_m": 0.3, "wall_offset_m": 0.9},
    "map": {"neurons": 12, "epochs": 12, "vocabulary_size": 48},
}


def _timeless(value: Any, outdir: str) -> Any:
    """``value`` without measured times, with the output folder replaced by a placeholder."""
    if isinstance(value, dict):
        return {
            k: _timeless(v, outdir)
            for k, v in value.items()
            if not (k.endswith("_s") or "_ms" in k or k == "timings")
        }
    if isinstance(value, list):
        return [_timeless(v, outdir) for v in value]
    if isinstance(value, str):
        return value.replace(outdir, "OUT")
    return value


@pytest.mark.slow
def test_ray_gives_the_local_pools_summary(tmp_path: Path) -> None:
    pytest.importorskip("ray", reason="ray is not installed (pip install 'naoloc[ray]')")
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(TINY))
    common = ["evaluate", "-c", str(cfg), "--protocol", "random", "-n", "3", "--seed", "4"]
    common += ["--workers", "2"]
    assert main([*common, "-o", str(tmp_path / "local")]) == 0
    child = subprocess.run(
        [sys.executable, "-c", _RAY_RUN, *common, "--executor", "ray", "-o", str(tmp_path / "ray")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    # The child ends by aborting itself: faulthandler must still report it.
    assert child.returncode == -signal.SIGABRT, child.stderr[-2000:]
    assert "Fatal Python error: Aborted" in child.stderr, child.stderr[-2000:]
    line = json.loads(child.stdout.strip().splitlines()[-1])
    assert line["executor"] == "ray" and line["n"] == 3
    local = json.loads((tmp_path / "local" / "summary.json").read_text())
    ray = json.loads((tmp_path / "ray" / "summary.json").read_text())
    assert local["positions"] == ray["positions"]  # estimates, bit for bit
    assert _timeless(local, str(tmp_path / "local")) == _timeless(ray, str(tmp_path / "ray"))


# The CLI in a process that checks, after it, that the local cluster was shut down and that
# the process's SIGTERM handler survived Ray, then aborts to show faulthandler still works.
_RAY_RUN = """
import faulthandler, signal, sys
import ray
from naoloc.app.cli import main

faulthandler.enable()
def mine(signum, frame):
    raise SystemExit(99)
signal.signal(signal.SIGTERM, mine)
code = main(sys.argv[1:])
assert code == 0, code
assert not ray.is_initialized(), "the local cluster is still up"
assert signal.getsignal(signal.SIGTERM) is mine, signal.getsignal(signal.SIGTERM)
sys.stdout.flush()
faulthandler._sigabrt()
"""


def test_executor_names_are_checked() -> None:
    assert make_executor("local").name == "local"
    with pytest.raises(ConfigError, match="valid: local, ray"):
        make_executor("dask")
    with pytest.raises(ConfigError, match="--ray-address needs --executor ray"):
        make_executor("local", "ray://127.0.0.1:10001")


def test_local_pool_workers_share_the_cores() -> None:
    """Each worker of the local pool runs OpenCV on its share of the cores (not all of
    them), so two workers on two cores do not oversubscribe them."""
    import operator
    import os

    import cv2

    from naoloc.evaluation.runner import run_tasks

    got = run_tasks(operator.call, [cv2.getNumThreads] * 2, 2, "threads", progress=False)
    assert got == [max(1, (os.cpu_count() or 1) // 2)] * 2
