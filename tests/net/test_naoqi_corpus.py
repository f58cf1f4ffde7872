"""The NAOqi corpus: NAO-style client scripts (``import qi``) against ``naoloc serve`` on libqi.

Each script in ``tests/naoqi_corpus/`` is run as its own process against a server on
loopback, as a NAO programmer would run it; it exits 0 and prints ``OK`` when every
NAOqi behaviour it relies on holds. Most run against one server at ``--speed 4``;
``walk_sleep.py`` also runs at ``--speed 1`` (a real NAO's pace). ``NAOLOC_QI_MODULE``
chooses the qi module (``qi`` here; ``naoloc.qi`` can run the same scripts). The servers
run with ``--command-timeout 0``: a NAOqi keeps a ``move`` going while its script sleeps,
where ``naoloc serve`` by default stops a walk whose client is silent for 0.5 s.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from naoloc.backends.naoqi.testing import ServedProcess, served

pytestmark = [
    pytest.mark.net,
    pytest.mark.skipif(
        __import__("importlib.util").util.find_spec("qi") is None, reason="qi not installed"
    ),
]

CORPUS = Path(__file__).parent / "naoqi_corpus"
SCRIPTS = sorted(p.name for p in CORPUS.glob("*.py") if not p.name.startswith("_"))
FAST = 4.0
NAOQI_MODE = ["--command-timeout", "0"]  # NAOqi's own behaviour: no command timeout
CONFIG = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [8.0, 8.0], "seed": 1}}}


def run_script(
    name: str, server: ServedProcess, speed: float, extra: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """Run one corpus script against ``server``."""
    env = dict(os.environ, NAOLOC_SPEED=str(speed), **(extra or {}))
    env.setdefault("NAOLOC_QI_MODULE", "qi")
    return subprocess.run(
        [sys.executable, str(CORPUS / name), server.url],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=CORPUS,
        check=False,
    )


@pytest.fixture(scope="module")
def fast_server() -> Iterator[ServedProcess]:
    with served(CONFIG, "libqi", speed=FAST, args=NAOQI_MODE) as server:
        yield server


@pytest.mark.parametrize("name", SCRIPTS)
def test_corpus_script(name: str, fast_server: ServedProcess) -> None:
    result = run_script(name, fast_server, FAST)
    assert result.returncode == 0, (
        f"{name}:\n{result.stdout}\n{result.stderr}\n{fast_server.stderr()}"
    )
    assert "OK" in result.stdout
    assert "Traceback" not in fast_server.stderr()


HAS_NAOLOC_QI = __import__("importlib.util").util.find_spec("naoloc.qi") is not None
NEEDS_OBJECTS = {"memory_events.py"}  # ALMemory.subscriber returns an object: not over zmq


@pytest.fixture(scope="module")
def zmq_server() -> Iterator[ServedProcess]:
    with served(CONFIG, "zmq", speed=FAST, args=NAOQI_MODE) as server:
        yield server


@pytest.mark.skipif(not HAS_NAOLOC_QI, reason="naoloc.qi is not in this tree")
@pytest.mark.parametrize("name", [s for s in SCRIPTS if s not in NEEDS_OBJECTS])
def test_corpus_script_through_naoloc_qi_over_zmq(name: str, zmq_server: ServedProcess) -> None:
    env = {"NAOLOC_QI_MODULE": "naoloc.qi"}
    result = run_script(name, zmq_server, FAST, env)
    assert result.returncode == 0, f"{name}:\n{result.stdout}\n{result.stderr}"


def test_walk_sleep_at_real_time() -> None:
    with served(CONFIG, "libqi", speed=1.0, args=NAOQI_MODE) as server:
        result = run_script("walk_sleep.py", server, 1.0)
    assert result.returncode == 0, f"{result.stdout}\n{result.stderr}"
