"""A client session serves services of its own through the robot's directory, as on a NAO.

naoloc.qi's connected ``Session.registerService`` registers with the remote service
directory and serves the calls itself (libqi's behaviour): against a real libqi
directory (standing in for a NAO) and against ``naoloc serve`` on both libqi
transports. Other clients, real qi and naoloc.qi, call it; it goes when its session
closes; the served NAOqi's own services cannot be taken over.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import pytest

import naoloc.qi as nqi
from naoloc.backends.naoqi.testing import served

pytestmark = [
    pytest.mark.net,
    pytest.mark.skipif(importlib.util.find_spec("qi") is None, reason="qi not installed"),
]

DIRECTORY = r"""
import sys, qi
qi.logging.setLevel(qi.logging.ERROR)
session = qi.Session()
session.listenStandalone("tcp://127.0.0.1:0")
print(session.endpoints()[0], flush=True)
sys.stdin.read()
"""
FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}


class Greeter:
    """A user service with a typed and a dynamic method."""

    @nqi.bind(nqi.String, [nqi.String])
    def greet(self, name: str) -> str:
        return f"hello {name}"

    @nqi.bind(nqi.Dynamic, [nqi.Dynamic])
    def twice(self, value: Any) -> Any:
        return [value, value]


@pytest.fixture(scope="module")
def libqi_directory() -> Iterator[str]:
    child = subprocess.Popen(
        [sys.executable, "-c", DIRECTORY], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout is not None
        yield child.stdout.readline().strip()
    finally:
        assert child.stdin is not None
        child.stdin.close()
        child.wait(timeout=10)


def _names(session: Any) -> list[str]:
    return [s["name"] for s in session.services()]


def _check_round_trip(url: str, name: str) -> None:
    import qi

    owner = nqi.Session()
    owner.connect(url)
    service_id = owner.registerService(name, Greeter())
    assert service_id > 1
    theirs, ours = qi.Session(), nqi.Session()
    theirs.connect(url)
    ours.connect(url)
    try:
        assert theirs.service(name).greet("nao") == "hello nao"
        assert ours.service(name).twice({"a": 1}) == [{"a": 1}, {"a": 1}]
        with pytest.raises(RuntimeError, match="already registered"):
            ours.registerService(name, Greeter())
        owner.close()  # its services go with it
        deadline = time.monotonic() + 5
        while name in _names(theirs) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert name not in _names(theirs)
    finally:
        owner.close()
        theirs.close()
        ours.close()


def test_naoloc_qi_registers_with_a_libqi_directory(libqi_directory: str) -> None:
    _check_round_trip(libqi_directory, "Greeter")


@pytest.mark.parametrize("transport", ["libqi", "qimessaging"])
def test_naoloc_qi_registers_with_naoloc_serve(transport: str) -> None:
    with served(FAKE, transport) as server:
        _check_round_trip(server.url, "Greeter")
        client = nqi.Session()
        client.connect(server.url)
        try:
            with pytest.raises(RuntimeError, match="already registered"):
                client.registerService("ALMotion", Greeter())
            motion_id = next(s["serviceId"] for s in client.services() if s["name"] == "ALMotion")
            with pytest.raises(RuntimeError, match="cannot"):
                client.service("ServiceDirectory").unregisterService(motion_id)
            assert client.service("ALMotion").ping() is True
        finally:
            client.close()
        assert "Traceback" not in server.stderr()


def test_naoloc_localization_registers_on_a_robots_session(tmp_path: Any) -> None:
    """A naoloc process offers NaolocLocalization on a NAO's session (``naoloc serve``
    stands in for the NAO; it serves a NaolocLocalization of its own, so this one takes
    another name)."""
    import qi

    from naoloc.backends.naoqi.home import register
    from naoloc.config import load_config
    from naoloc.robot.registry import connect

    with served(FAKE, "libqi") as nao:
        cfg = load_config(nao.client_config())
        robot = connect(cfg)
        session = nqi.Session()
        session.connect(nao.url)
        client = qi.Session()
        try:
            register(session, robot, cfg, tmp_path, name="NaolocLocalizationHere")
            client.connect(nao.url)
            service = client.service("NaolocLocalizationHere")
            assert service.isDataAvailable() is False
            with pytest.raises(RuntimeError, match="learnHome first"):
                service.localize()
            with pytest.raises(RuntimeError, match="not localized yet"):
                service.getRobotPosition()
        finally:
            client.close()
            session.close()
            robot.close()
