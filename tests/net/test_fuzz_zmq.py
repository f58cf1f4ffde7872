"""The zmq virtual NAOqi under fire: malformed messages never kill, hang or bloat the server.

A real ``naoloc serve --transport zmq`` on loopback gets 10,000 seeded random messages
(garbage, type-confused, mutated, oversized, deeply nested); it must still be running,
answer a valid call afterwards (watchdog check), print no traceback and grow by less
than 50 MB.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import msgpack
import pytest
import zmq

import naoloc
from naoloc.backends.naoqi import wire
from naoloc.backends.naoqi.testing import served
from naoloc.errors import BackendError, ConnectionLost
from tests.fuzz.proc import rss_mb
from tests.fuzz.zmq_fuzzer import fuzz_zmq, zmq_hello

pytestmark = pytest.mark.net

FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
MESSAGES = 10_000
MAX_GROWTH_MB = 50.0


def _send(url: str, frames: list[bytes], timeout_ms: int = 2000) -> list[bytes] | None:
    ctx = zmq.Context()
    try:
        sock = ctx.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(url)
        sock.send_multipart(frames)
        return sock.recv_multipart() if sock.poll(timeout_ms) else None
    finally:
        ctx.destroy(linger=0)


def test_a_kind_of_the_wrong_type_gets_an_error_reply_and_the_port_still_answers() -> None:
    with served(FAKE, "zmq") as server:
        for ident, kind in enumerate([[], {}, {"a": [1]}, 2.5, None], start=40):
            reply = _send(server.url, [msgpack.packb({"k": kind, "i": ident})])
            assert reply is not None, server.stderr()
            decoded = wire.decode_reply(reply)
            assert decoded["k"] == "err" and decoded["i"] == ident
            assert decoded["e"][0] == "ProtocolError"
            assert "ALMotion" in zmq_hello(server.url)
        assert server.process.poll() is None
        err = server.stderr()
        assert "Traceback" not in err and "unknown message kind" in err


def test_fuzzed_server_survives_answers_and_stays_small() -> None:
    with served(FAKE, "zmq") as server:
        pid = server.process.pid
        fuzz_zmq(server.url, 300, seed=1)  # warm up allocator and caches first
        before = rss_mb(pid)
        report = fuzz_zmq(server.url, MESSAGES, seed=2)
        time.sleep(0.3)
        after = rss_mb(pid)
        assert report.sent == MESSAGES
        assert server.process.poll() is None, server.stderr()[-2000:]
        assert "ALMotion" in zmq_hello(server.url)  # the watchdog check
        with naoloc.connect(server.client_config()) as robot:
            assert len(robot.motion.getRobotPosition(True)) == 3
        err = server.stderr()
        assert "Traceback" not in err, err[-3000:]
        assert all(line.startswith("naoloc serve: ") for line in err.splitlines()), err[-2000:]
        assert after - before < MAX_GROWTH_MB, (before, after)


def test_a_malformed_reply_is_a_one_line_connection_lost_naming_the_server() -> None:
    ctx = zmq.Context()
    try:
        router = ctx.socket(zmq.ROUTER)
        router.setsockopt(zmq.LINGER, 0)
        port = router.bind_to_random_port("tcp://127.0.0.1")
        url = f"tcp://127.0.0.1:{port}"
        from naoloc.backends.naoqi.zmq_transport import ZmqSession

        session = ZmqSession(connect_timeout_s=3.0)
        future = None
        import threading

        def answer() -> None:
            if router.poll(3000):
                peer, *_ = router.recv_multipart()
                router.send_multipart([peer, msgpack.packb({"k": "welcome", "i": 1, "v": 5})])

        thread = threading.Thread(target=answer)
        thread.start()
        with pytest.raises(ConnectionLost) as info:
            future = session.connect(url)
        thread.join()
        session.close()
        message = str(info.value)
        assert "\n" not in message and url in message and "welcome" in message
        assert future is None
    finally:
        ctx.destroy(linger=0)


def _run(*args: str, timeout_s: float = 30.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", *args],
        capture_output=True, text=True, timeout=timeout_s,
    )  # fmt: skip


def test_missing_curve_keys_are_one_line_and_nothing_hangs(tmp_path: Path) -> None:
    server_cfg = tmp_path / "s.yaml"
    server_cfg.write_text(
        "robot: {backend: fake, curve_keys: /nonexistent}\nworld: {room: {size_m: [4.0, 4.0]}}\n"
    )
    done = _run("serve", "-c", str(server_cfg), "--transport", "zmq", "--listen",
                "tcp://127.0.0.1:0")  # fmt: skip
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and len(lines) == 1, done.stderr
    assert "/nonexistent" in lines[0] and "curve_keys" in lines[0]
    client_cfg = tmp_path / "c.yaml"
    client_cfg.write_text(
        "robot: {backend: naoqi, transport: zmq, url: 'tcp://127.0.0.1:9', "
        "curve_keys: /nonexistent}\nsurvey: {side_m: [2.0, 2.0]}\n"
    )
    done = _run("survey", "-c", str(client_cfg), "-o", str(tmp_path / "x.mcap"))
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and len(lines) == 1, done.stderr
    assert "/nonexistent" in lines[0]


def test_a_curve_folder_without_the_client_key_is_one_line(tmp_path: Path) -> None:
    from naoloc.backends.naoqi.zmq_transport import ZmqSession, make_curve_keys

    keys = make_curve_keys(tmp_path / "keys")
    (keys / "client.key_secret").unlink()
    session = ZmqSession(curve_keys=str(keys))
    with pytest.raises(BackendError, match="client.key_secret"):
        session.connect("tcp://127.0.0.1:9")
    session.close()  # returns at once: no socket was left open
