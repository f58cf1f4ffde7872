"""The naoqi backend against a real virtual NAOqi on loopback: safety, security, libqi clients."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

import naoloc
from naoloc.backends.naoqi.server import VirtualNaoqi
from naoloc.backends.naoqi.testing import ServedProcess, served
from naoloc.data.dataset import read_dataset
from naoloc.errors import ConnectionLost
from naoloc.robot import Robot

pytestmark = pytest.mark.net

FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
TRANSPORTS = [
    "zmq",
    pytest.param(
        "libqi",
        marks=pytest.mark.skipif(
            __import__("importlib.util").util.find_spec("qi") is None, reason="qi not installed"
        ),
    ),
]


def _wait_for(predicate: object, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():  # type: ignore[operator]
            return True
        time.sleep(0.02)
    return False


def test_libqi_own_client_gets_typed_binary_frames() -> None:
    qi = pytest.importorskip("qi")
    with served(FAKE, "libqi") as server:
        session = qi.Session()
        session.connect(server.url)
        try:
            motion = session.service("ALMotion")
            video = session.service("ALVideoDevice")
            assert motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
            for resolution, (width, height) in [(1, (320, 240)), (2, (640, 480))]:
                handle = video.subscribeCamera("native", 0, resolution, 11, 30)
                frame = video.getImageRemote(handle)
                assert isinstance(frame[6], bytearray)  # binary, not str or repr text
                assert (frame[0], frame[1], frame[2], len(frame[6])) == (
                    width, height, 3, width * height * 3,
                )  # fmt: skip
                assert video.unsubscribe(handle) is True
            with pytest.raises(RuntimeError, match="HandleError"):
                video.getImageRemote("no-such-handle")
        finally:
            session.close()


def _client_config(server: ServedProcess, tmp_path: Path, **survey: object) -> Path:
    cfg = dict(FAKE)
    cfg["robot"] = server.client_config(sim_service=True)["robot"]
    cfg["survey"] = {"laps": 3, "step_m": 0.2, "head_yaw_rad": -1.5707963267948966, **survey}
    path = tmp_path / "client.yaml"
    path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
    return path


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_server_killed_mid_survey_ends_the_client_with_one_line_within_2s(
    transport: str, tmp_path: Path
) -> None:
    dataset = tmp_path / "survey.mcap"
    with served(FAKE, transport) as server:
        cfg = _client_config(server, tmp_path)
        client = subprocess.Popen(
            [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", str(cfg), "-o", str(dataset)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            part = tmp_path / "survey.partial.mcap"  # written until the survey completes
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
    assert f"kept in {part}" in lines[0]
    assert read_dataset(part).keyframes  # the frames taken before the loss are kept


_DRIVER = """
import sys, time, naoloc
with naoloc.connect({"robot": {"backend": "naoqi", "url": sys.argv[1],
                               "transport": sys.argv[2]}}) as robot:
    robot.motion.wakeUp()
    robot.motion.move(0.08, 0.0, 0.0)
    print("moving", flush=True)
    time.sleep(120)
"""


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_client_killed_mid_move_gets_the_robot_stopped_by_the_server(transport: str) -> None:
    with served(FAKE, transport) as server:
        driver = subprocess.Popen(
            [sys.executable, "-c", _DRIVER, server.url, transport],
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
            walked = observer.sim.true_pose()[0] - 1.0  # type: ignore[union-attr]
            assert walked > 0.0  # it did walk before the stop


@pytest.fixture
def fake_robot() -> Iterator[Robot]:
    with naoloc.connect(FAKE) as robot:
        yield robot


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_reads_reconnect_after_a_restart_and_motion_commands_do_not(fake_robot: Robot) -> None:
    url = f"tcp://127.0.0.1:{_free_port()}"
    client_cfg = {"robot": {"backend": "naoqi", "url": url, "transport": "zmq"}}
    server = VirtualNaoqi(fake_robot, url, "zmq")
    with naoloc.connect(client_cfg) as client:
        assert client.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
        server.close()
        server = VirtualNaoqi(fake_robot, url, "zmq")
        time.sleep(0.3)  # the client notices the restart
        assert client.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
        server.close()
        time.sleep(0.3)
        with pytest.raises(ConnectionLost, match="lost"):
            client.motion.move(0.1, 0.0, 0.0)
        with pytest.raises(ConnectionLost):
            client.motion.getRobotPosition(True)


def test_curve_keys_admit_only_clients_that_hold_them(fake_robot: Robot, tmp_path: Path) -> None:
    from naoloc.backends.naoqi.zmq_transport import make_curve_keys

    keys = str(make_curve_keys(tmp_path / "keys"))
    url = f"tcp://127.0.0.1:{_free_port()}"
    with VirtualNaoqi(fake_robot, url, "zmq", curve_keys=keys):
        cfg = {"robot": {"backend": "naoqi", "url": url, "transport": "zmq", "curve_keys": keys}}
        with naoloc.connect(cfg) as client:
            assert client.motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
        plain = {"robot": {"backend": "naoqi", "url": url, "transport": "zmq"}}
        with pytest.raises(ConnectionLost, match="no virtual NAOqi"):
            naoloc.connect(plain)


@pytest.mark.sim
def test_mujoco_robot_served_over_zmq_walks_and_sees() -> None:
    pytest.importorskip("mujoco")
    cfg = {"robot": {"backend": "mujoco"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
    with (
        served(cfg, "zmq") as server,
        naoloc.connect(server.client_config(sim_service=True)) as robot,
    ):
        robot.motion.wakeUp()
        assert robot.posture.goToPosture("StandInit", 0.5) is True
        start = robot.sim.true_pose()  # type: ignore[union-attr]
        assert robot.motion.moveTo(0.3, 0.0, 0.0) is True
        end = robot.sim.true_pose()  # type: ignore[union-attr]
        assert abs((end[0] - start[0]) - 0.3) < 0.05
        assert abs(robot.motion.getRobotPosition(True)[0] - 0.3) < 0.05
        handle = robot.video.subscribeCamera("smoke", 0, 1, 11, 30)
        frame = robot.video.getImageRemote(handle)
        assert (frame[0], frame[1], len(frame[6])) == (320, 240, 320 * 240 * 3)
        assert len(set(frame[6][::97])) > 10  # a rendered room, not a blank buffer
