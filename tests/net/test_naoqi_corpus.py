"""The NAOqi corpus: NAO-style scripts against ``naoloc serve`` over every transport.

Each script in ``naoqi_corpus/`` runs as its own process against a server on loopback,
as a NAO programmer would run it; it exits 0 and prints ``OK`` when every NAOqi
behaviour it relies on holds. Scripts written with ``qi`` run with the real ``qi`` and
with ``naoloc.qi`` (``NAOLOC_QI_MODULE``); ``oldsdk_*.py`` scripts (``from naoqi import
ALProxy``) run under ``python -m naoloc.run`` on Python 3. Servers: libqi, qimessaging
(naoloc's own libqi protocol) and zmq (naoloc.qi only; no objects or client services
there, see ``ZMQ_CANNOT``), at ``--speed 4``; ``walk_sleep.py`` also runs at a real NAO's
pace and ``localization_service.py`` in a small room at ``--speed 20``.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from naoloc.backends.naoqi.testing import ServedProcess, served

HAS_QI = importlib.util.find_spec("qi") is not None
pytestmark = [pytest.mark.net]

CORPUS = Path(__file__).parent / "naoqi_corpus"
SCRIPTS = sorted(p.name for p in CORPUS.glob("*.py") if not p.name.startswith("_"))
FAST = 4.0
CONFIG = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [8.0, 8.0], "seed": 1}}}
SMALL_ROOM = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 3.0], "seed": 1}}}
OWN_SERVER = {"localization_service.py"}  # a survey: its own small room, fast clock
# zmq has no remote objects (ALMemory.subscriber) and serves no client's services.
ZMQ_CANNOT = {"memory_events.py", "oldsdk_served_module.py"}


def combos() -> list[tuple[str, str, str]]:
    """(script, transport, client) pairs that the transports allow."""
    out = []
    for name in SCRIPTS:
        if name in OWN_SERVER:
            continue
        old = name.startswith("oldsdk_")
        for transport in ("libqi", "qimessaging", "zmq"):
            if transport == "zmq" and name in ZMQ_CANNOT:
                continue
            clients = ["naoqi"] if old else ["qi", "naoloc.qi"]
            for client in clients:
                if client == "qi" and transport == "zmq":
                    continue
                out.append((name, transport, client))
    return out


def put_back(server: ServedProcess) -> None:
    """Stop the robot and put it at the scripts' start: (1, 1) facing +x, true and odometry.

    Scripts walk; without this the robot would reach a wall after a few dozen of them.
    """
    import math

    import naoloc.qi as nqi

    session = nqi.Session()
    session.connect(server.url)
    try:
        motion, sim = session.service("ALMotion"), session.service("NaolocSim")
        motion.stopMove()
        motion.wakeUp()
        turn = -motion.getRobotPosition(False)[2]
        turn = math.atan2(math.sin(turn), math.cos(turn))
        if abs(turn) > 0.01:
            motion.moveTo(0.0, 0.0, turn)
        sim.teleport(1.0, 1.0, 0.0)
    finally:
        session.close()


def run_script(
    name: str, server: ServedProcess, speed: float, client: str
) -> subprocess.CompletedProcess[str]:
    """Run one corpus script against ``server`` with ``client`` (qi, naoloc.qi or naoqi)."""
    put_back(server)
    env = dict(os.environ, NAOLOC_SPEED=str(speed))
    env["NAOLOC_QI_MODULE"] = "naoloc.qi" if client == "naoqi" else client
    launcher = ["-m", "naoloc.run"] if client == "naoqi" else []
    return subprocess.run(
        [sys.executable, *launcher, str(CORPUS / name), server.url],
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
        cwd=CORPUS,
        check=False,
    )


@pytest.fixture(scope="module", params=["libqi", "qimessaging", "zmq"])
def server(request: pytest.FixtureRequest) -> Iterator[ServedProcess]:
    if request.param == "libqi" and not HAS_QI:
        pytest.skip("libqi serving needs the qi package")
    with served(CONFIG, request.param, speed=FAST) as process:
        yield process


@pytest.mark.parametrize(("name", "client"), sorted({(n, c) for n, _, c in combos()}))
def test_corpus_script(name: str, client: str, server: ServedProcess) -> None:
    if (name, server.transport, client) not in combos():
        pytest.skip(f"{server.transport} cannot serve {name} to {client}")
    if client == "qi" and not HAS_QI:
        pytest.skip("the qi package is not installed")
    result = run_script(name, server, FAST, client)
    assert result.returncode == 0, (
        f"{name} ({client} over {server.transport}):\n{result.stdout}\n{result.stderr}\n"
        f"{server.stderr()[-2000:]}"
    )
    assert "OK" in result.stdout
    assert "Traceback" not in server.stderr()


def test_walk_sleep_at_real_time() -> None:
    transport, client = ("libqi", "qi") if HAS_QI else ("qimessaging", "naoloc.qi")
    with served(CONFIG, transport, speed=1.0) as process:
        result = run_script("walk_sleep.py", process, 1.0, client)
    assert result.returncode == 0, f"{result.stdout}\n{result.stderr}"


@pytest.mark.slow
@pytest.mark.parametrize(
    ("transport", "client"), [("libqi", "qi"), ("qimessaging", "naoloc.qi"), ("zmq", "naoloc.qi")]
)
def test_naoloc_localization_service(transport: str, client: str) -> None:
    if "qi" in (transport, client) and not HAS_QI:
        pytest.skip("the qi package is not installed")
    with served(SMALL_ROOM, transport, speed=20.0) as process:
        result = run_script("localization_service.py", process, 20.0, client)
    assert result.returncode == 0, f"{result.stdout}\n{result.stderr}\n{process.stderr()[-2000:]}"
    assert "OK" in result.stdout
