"""The naoqi backend over naoloc's QiMessaging: the same safety as the other transports.

A dead server ends a survey with one line within 2 s (frames kept); a dead client's walk
is stopped by the server's dead-man; reads reconnect after a restart, motion commands do
not; ``transport: auto`` finds a zmq server by its greeting.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import yaml

import naoloc
from naoloc.backends.naoqi.server import VirtualNaoqi
from naoloc.backends.naoqi.testing import served
from naoloc.data.dataset import read_dataset
from naoloc.errors import ConnectionLost, RobotError
from naoloc.robot import Robot

pytestmark = pytest.mark.net

# The pre-issue-11 world: these tests are about the network, not realism.
FAKE = {
    "robot": {"backend": "fake"},
    "world": {
        "room": {"size_m": [4.0, 4.0], "seed": 3, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
    },
}


def _wait_for(predicate: Callable[[], bool], timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def test_server_killed_mid_survey_ends_the_client_with_one_line_within_2s(tmp_path: Path) -> None:
    dataset = tmp_path / "survey.mcap"
    with served(FAKE, "qimessaging") as server:
        cfg = dict(FAKE)
        cfg["robot"] = server.client_config(sim_service=True)["robot"]
        cfg["survey"] = {"laps": 3, "step_m": 0.2, "head_yaw_rad": -1.5707963267948966}
        path = tmp_path / "client.yaml"
        path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
        client = subprocess.Popen(
            [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", str(path), "-o", str(dataset)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            part = dataset.with_name(dataset.stem + ".partial.mcap")  # frames go there first
            started = _wait_for(lambda: part.exists() and part.stat().st_size > 20_000, 60)
            assert started, "the survey did not start writing frames"
            server.process.send_signal(signal.SIGKILL)
            killed = time.monotonic()
            _, err = client.communicate(timeout=30)
            ended_after = time.monotonic() - killed
        finally:
            if client.poll() is None:
                client.kill()
                client.wait()
    lines = err.strip().splitlines()
    assert client.returncode == 1, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "connection to NAOqi" in lines[0] and "lost" in lines[0]
    assert ended_after < 2.0, f"client noticed the dead server only after {ended_after:.2f} s"
    assert read_dataset(part).keyframes  # the frames taken before the loss are kept


_DRIVER = """
import sys, time, naoloc
with naoloc.connect({"robot": {"backend": "naoqi", "url": sys.argv[1],
                               "transport": "qimessaging"}}) as robot:
    robot.motion.wakeUp()
    robot.motion.move(0.08, 0.0, 0.0)
    print("moving", flush=True)
    time.sleep(120)
"""


def test_client_killed_mid_move_gets_the_robot_stopped_by_the_server() -> None:
    with served(FAKE, "qimessaging") as server:
        driver = subprocess.Popen(
            [sys.executable, "-c", _DRIVER, server.url],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        try:
            assert driver.stdout is not None and driver.stdout.readline().strip() == "moving"
            time.sleep(1.0)  # alive and pinging: the dead-man must not fire
            assert "dead-man" not in server.stderr()
            os.kill(driver.pid, signal.SIGKILL)
            driver.wait()
            stopped = _wait_for(lambda: "dead-man" in server.stderr(), 5.0)
        finally:
            if driver.poll() is None:
                driver.kill()
                driver.wait()
            if driver.stdout is not None:
                driver.stdout.close()
        assert stopped, server.stderr()
        with naoloc.connect(server.client_config(sim_service=True)) as observer:
            assert observer.motion.moveIsActive() is False
            assert observer.motion.getRobotVelocity() == [0.0, 0.0, 0.0]


@pytest.fixture
def fake_robot() -> Iterator[Robot]:
    with naoloc.connect(FAKE) as robot:
        yield robot


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_reads_reconnect_after_a_restart_and_motion_commands_do_not(fake_robot: Robot) -> None:
    url = f"tcp://127.0.0.1:{_free_port()}"
    client_cfg = {"robot": {"backend": "naoqi", "url": url, "transport": "qimessaging"}}
    server = VirtualNaoqi(fake_robot, url, "qimessaging")
    with naoloc.connect(client_cfg) as client:
        assert client.info["transport"] == "qimessaging"
        assert client.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
        server.close()
        server = VirtualNaoqi(fake_robot, url, "qimessaging")
        time.sleep(0.3)  # the client notices the restart
        assert client.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
        server.close()
        time.sleep(0.3)
        with pytest.raises(ConnectionLost, match="lost"):
            client.motion.move(0.1, 0.0, 0.0)
        with pytest.raises(ConnectionLost):
            client.motion.getRobotPosition(True)


def test_auto_finds_a_zmq_server_by_its_greeting() -> None:
    with served(FAKE, "zmq") as server:
        cfg = {"robot": {"backend": "naoqi", "url": server.url, "transport": "auto"}}
        with naoloc.connect(cfg) as robot:
            assert robot.info["transport"] == "zmq"
            assert robot.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]


def test_nothing_listening_is_one_line() -> None:
    url = f"tcp://127.0.0.1:{_free_port()}"
    cfg = {"robot": {"backend": "naoqi", "url": url, "transport": "qimessaging"}}
    with pytest.raises(ConnectionLost, match="no NAOqi answers") as info:
        naoloc.connect(cfg)
    assert "\n" not in str(info.value)


def test_overloads_posts_and_typed_errors_through_our_client(fake_robot: Robot) -> None:
    from naoloc.backends.naoqi.qimessaging.client import QiSession
    from naoloc.errors import HandleError, RobotError

    with VirtualNaoqi(fake_robot, "tcp://127.0.0.1:0", "qimessaging") as server:
        session = QiSession()
        session.connect(server.endpoint)
        try:
            motion = session.service("ALMotion")
            assert [str(m.params) for m in motion.metaObject().overloads("moveTo")] == [
                "(ddd)",
                "(dddm)",
                "(m)",
                "(mm)",
            ]
            assert motion.moveTo(0.1, 0, 0) is True  # ints fit (ddd) better than (m)
            assert motion.moveTo([[0.1, 0.0, 0.0]]) is True  # only (m) takes one argument
            motion.post("move", 0.05, 0.0, 0.0)  # no answer: poll until it took effect
            assert _wait_for(lambda: motion.moveIsActive() is True, 2.0)
            motion.stopMove()
            with pytest.raises(HandleError, match="no camera subscriber"):  # the server's type
                session.service("ALVideoDevice").getImageRemote("nope")
            with pytest.raises(RobotError, match=r"moveTo takes \(x, y, theta"):
                motion.moveTo("a", "b")
        finally:
            session.close()


def test_services_listed_at_other_endpoints_are_reached(monkeypatch: pytest.MonkeyPatch) -> None:
    from naoloc.backends.naoqi.qimessaging.client import QiSession
    from naoloc.backends.naoqi.qimessaging.server import QiServer

    class Twice:
        def twice(self, x: int) -> int:
            return 2 * x

    server = QiServer()
    server.listen("tcp://127.0.0.1:0")
    server.register("Twice", Twice(), methods=[("twice", "(i)", "i")])
    port = int(server.url().rsplit(":", 1)[1])
    dead = _free_port()
    listed: list[list[str]] = [
        [f"tcp://127.0.0.1:{port}"],  # the directory's own address: same connection
        [f"tcp://127.0.0.1:{dead}", f"tcp://localhost:{port}"],  # first unreachable
    ]

    def info(served: object) -> tuple[object, ...]:
        name, sid = served.name, served.service_id  # type: ignore[attr-defined]
        return (name, sid, server.machine_id, 1, listed[0], "", b"")

    monkeypatch.setattr(server, "_info", info)
    try:
        for expected_channels in (1, 2):
            session = QiSession(connect_timeout_s=2)
            session.connect(server.url())
            try:
                assert session.service("Twice").twice(4) == 8
                assert len(session._channels) == expected_channels
            finally:
                session.close()
            listed.pop(0)
    finally:
        server.close()


def test_service_added_and_removed_reach_clients() -> None:
    from naoloc.backends.naoqi.qimessaging.client import QiSession
    from naoloc.backends.naoqi.qimessaging.server import QiServer

    class Twice:
        def twice(self, x: int) -> int:
            return 2 * x

    server = QiServer()
    server.listen("tcp://127.0.0.1:0")
    session = QiSession()
    session.connect(server.url())
    events: list[tuple[str, int, str]] = []
    session.serviceRegistered.connect(lambda sid, name: events.append(("added", sid, name)))
    session.serviceUnregistered.connect(lambda sid, name: events.append(("removed", sid, name)))
    try:
        sid = server.register("Twice", Twice(), methods=[("twice", "(i)", "i")])
        assert _wait_for(lambda: len(events) == 1, 2.0)
        assert session.service("Twice").twice(3) == 6
        server.unregister(sid)
        assert _wait_for(lambda: len(events) == 2, 2.0)
        assert events == [("added", sid, "Twice"), ("removed", sid, "Twice")]
        with pytest.raises(RobotError, match="no service 'Twice'"):
            session.service("Twice")  # the cached proxy was dropped
    finally:
        session.close()
        server.close()


def test_urls_get_libqi_defaults() -> None:
    from naoloc.backends.naoqi.qimessaging.connection import normalize_url

    assert normalize_url("nao.local") == "tcp://nao.local:9559"
    assert normalize_url("10.0.0.2:9600") == "tcp://10.0.0.2:9600"
    assert normalize_url("tcps://nao.local") == "tcps://nao.local:9503"
    assert normalize_url("tcp://[::1]") == "tcp://[::1]:9559"
    assert normalize_url("tcp://h:1") == "tcp://h:1"
