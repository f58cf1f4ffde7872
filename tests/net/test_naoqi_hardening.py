"""The served NAOqi under abuse: bad messages, rogue registrations, dead and slow clients.

Every test runs a real ``naoloc serve`` on loopback (fake robot) and attacks it the way
issue 15 describes; each failed before the server hardening and passes now.
"""

from __future__ import annotations

import importlib.util
import os
import signal
import socket
import subprocess
import sys
import time
from urllib.parse import urlsplit

import msgpack
import pytest
import zmq

import naoloc
from naoloc.backends.naoqi import wire
from naoloc.backends.naoqi.testing import ServedProcess, served

pytestmark = pytest.mark.net
HAS_QI = importlib.util.find_spec("qi") is not None
needs_qi = pytest.mark.skipif(not HAS_QI, reason="qi not installed")
FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [8.0, 8.0], "seed": 3}}}
SPEED = 2.0


def _answers(server: ServedProcess) -> bool:
    with naoloc.connect(server.client_config(sim_service=True)) as robot:
        return len(robot.motion.getRobotPosition(True)) == 3


def test_zmq_port_answers_after_malformed_and_bad_requests() -> None:
    with served(FAKE, "zmq") as server:
        ctx = zmq.Context()
        sock = ctx.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(server.url)
        try:
            garbage = [
                [b""], [b"\xff" * 40], [msgpack.packb({"k": [], "i": 1})],
                [msgpack.packb({"k": {}, "i": 1})], [msgpack.packb([1, 2, 3])],
                [msgpack.packb({"k": "call", "i": 1, "s": [], "m": "x", "a": []})],
            ]  # fmt: skip
            for frames in garbage:
                sock.send_multipart(frames)
            bad_calls = [
                ("NoSuch", "x", []), ("ALMotion", "noSuchMethod", []),
                ("ALMotion", "moveTo", ["far", 0, 0]), ("ALMotion", "setAngles", ["Tail", 0, 1]),
                ("ALMotion", "moveTo", [[[1e308, 1e308, "x"]]]),
                ("ALVideoDevice", "getImageRemote", [None]),
            ]  # fmt: skip
            for k, (service, method, args) in enumerate(bad_calls, start=10):
                call = {"k": "call", "i": k, "s": service, "m": method, "a": args}
                sock.send_multipart(wire.encode(call))
            errors = 0
            deadline = time.monotonic() + 10
            while errors < len(bad_calls) and time.monotonic() < deadline:
                if sock.poll(200):
                    reply = wire.decode_reply(sock.recv_multipart())
                    assert reply["k"] == "err", reply
                    assert "\n" not in reply["e"][1] and ".py" not in reply["e"][1], reply
                    errors += 1
            assert errors == len(bad_calls)
        finally:
            sock.close(0)
            ctx.term()
        assert _answers(server)
        assert server.process.poll() is None
        assert "Traceback" not in server.stderr()


@needs_qi
def test_libqi_port_answers_after_garbage_and_protects_its_services() -> None:
    import qi

    with served(FAKE, "libqi") as server:
        parts = urlsplit(server.url)
        for junk in (b"\x00" * 64, b"GET / HTTP/1.0\r\n\r\n", b"\x42\xde\xad\x42" + b"\xff" * 24):
            with socket.create_connection((parts.hostname, parts.port), timeout=2) as raw:
                raw.sendall(junk)
        session = qi.Session()
        session.connect(server.url)
        try:
            motion = session.service("ALMotion")
            before = motion.getRobotPosition(False)
            with pytest.raises(RuntimeError, match="refused"):
                session.service("ServiceDirectory").unregisterService(2)

            class Rogue:
                @qi.bind("[d]", ["b"])
                def getRobotPosition(self, use_sensors: bool) -> list[float]:
                    return [42.0, 42.0, 0.0]

            with pytest.raises(RuntimeError, match="already registered"):
                session.registerService("ALMotion", Rogue())
            session.registerService("ALMotion2", Rogue())  # a client's own service, as on a NAO
            assert "ALMotion2" in [s["name"] for s in session.services()]
            assert session.service("ALMotion").getRobotPosition(False) == before
            with pytest.raises(RuntimeError, match="ALMotion.setAngles"):
                motion.setAngles("Tail", 0.0, 0.5)
        finally:
            session.close()
        assert _answers(server)
        assert server.process.poll() is None
        assert "Traceback" not in server.stderr()


_NAOLOC_DRIVER = """
import sys, naoloc
with naoloc.connect({"robot": {"backend": "naoqi", "url": sys.argv[1],
                               "transport": sys.argv[2]}}) as robot:
    robot.motion.wakeUp()
    if sys.argv[3] == "move":
        robot.motion.move(0.1, 0.0, 0.0)
        print("walking", flush=True)
        import time; time.sleep(120)
    print("walking", flush=True)
    robot.motion.moveTo(3.0, 0.0, 0.0)
"""

_QI_DRIVER = """
import sys, qi
s = qi.Session(); s.connect(sys.argv[1])
m = s.service("ALMotion"); m.wakeUp()
print("walking", flush=True)
m.moveTo(3.0, 0.0, 0.0)
"""


def _kill_driver_and_time_the_stop(server: ServedProcess, code: str, *args: str) -> float:
    """Start a driver, let it walk, SIGKILL it; seconds until the robot stops.

    Another client polls moveIsActive all the while: its traffic must not keep the
    dead driver's walk alive.
    """
    cmd = [sys.executable, "-c", code, server.url, *args]
    driver = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        with naoloc.connect(server.client_config(sim_service=True)) as observer:
            assert driver.stdout is not None
            while (line := driver.stdout.readline()) and line.strip() != "walking":
                pass  # qi may log a warning on stdout first
            assert line.strip() == "walking", "the driver did not start"
            deadline = time.monotonic() + 10
            while not observer.motion.moveIsActive():
                assert time.monotonic() < deadline, "the driver never walked"
            time.sleep(0.6)
            assert observer.motion.moveIsActive(), "stopped while the driver was alive"
            os.kill(driver.pid, signal.SIGKILL)
            killed = time.monotonic()
            while observer.motion.moveIsActive():
                assert time.monotonic() - killed < 5, "the robot kept walking"
            return time.monotonic() - killed
    finally:
        if driver.poll() is None:
            driver.kill()
        driver.wait()
        if driver.stdout is not None:
            driver.stdout.close()


@pytest.mark.parametrize(
    ("transport", "mode"),
    [
        ("zmq", "move"),
        ("zmq", "moveTo"),
        pytest.param("libqi", "move", marks=needs_qi),
        pytest.param("libqi", "moveTo", marks=needs_qi),
    ],
)
def test_a_killed_naoloc_client_stops_the_robot_within_half_a_second(
    transport: str, mode: str
) -> None:
    with served(FAKE, transport, speed=SPEED) as server:
        stopped_after = _kill_driver_and_time_the_stop(server, _NAOLOC_DRIVER, transport, mode)
        assert stopped_after < 0.6, f"stopped {stopped_after:.2f} s after the client died"
        assert "dead-man" in server.stderr()


@needs_qi
def test_a_killed_plain_qi_client_in_a_blocking_move_to_stops_the_robot() -> None:
    with served(FAKE, "libqi", speed=SPEED) as server:
        stopped_after = _kill_driver_and_time_the_stop(server, _QI_DRIVER)
        assert stopped_after < 0.5, f"stopped {stopped_after:.2f} s after the client died"
        assert "disconnected: robot stopped (dead-man)" in server.stderr()


def _rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return 0.0


def test_zmq_unread_replies_are_bounded_and_do_not_stall_others() -> None:
    with served(FAKE, "zmq") as server:
        ctx = zmq.Context()
        sock = ctx.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVHWM, 1)
        sock.setsockopt(zmq.RCVBUF, 4096)
        sock.connect(server.url)
        try:
            hello = {"k": "call", "i": 1, "s": "ALVideoDevice", "m": "subscribeCamera"}
            sock.send_multipart(wire.encode({**hello, "a": ["flood", 0, 2, 11, 30]}))  # kVGA
            assert sock.poll(5000)
            handle = wire.decode_reply(sock.recv_multipart())["v"]
            before = _rss_mb(server.process.pid)
            with naoloc.connect(server.client_config()) as other:
                for k in range(2, 400):  # 0.9 MB each, never read
                    call = {"k": "call", "i": k, "s": "ALVideoDevice", "m": "getImageRemote"}
                    sock.send_multipart(wire.encode({**call, "a": [handle]}))
                worst = 0.0
                for _ in range(20):
                    t0 = time.monotonic()
                    other.motion.getRobotPosition(True)
                    worst = max(worst, time.monotonic() - t0)
                    time.sleep(0.05)
                time.sleep(1.0)
            growth = _rss_mb(server.process.pid) - before
        finally:
            sock.close(0)
            ctx.term()
        # A server that blocks on the unread replies makes the other client wait for its
        # call timeout (5 s); a served one answers in milliseconds. The bound leaves room for
        # a loaded CI machine (0.64 s seen once with two evaluations on the same two cores).
        assert worst < 2.0, f"another client waited {worst:.2f} s behind the flood"
        assert growth < 100, f"the server grew by {growth:.0f} MB holding unread replies"
        assert _answers(server)
