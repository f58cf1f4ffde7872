"""Attacks on a served NAOqi (``naoloc serve``), shared by tools/bench_attack.py and tests.

Each attack is a context manager that starts the attack against a running server and
undoes it on exit (the attacker leaves); meanwhile the caller measures a victim with
:func:`victim_stop` (a fresh client in its own process: the real ``qi`` package when
installed, for the QiMessaging servers) or the server's cost with :func:`cpu_s` and
:func:`rss_mb`. Raw QiMessaging frames come from :class:`RawQi`; raw zmq requests from
:class:`RawZmq`.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from naoloc.backends.naoqi.qimessaging import capability, codec, message
from naoloc.backends.naoqi.qimessaging.client import QiSession
from naoloc.backends.naoqi.qimessaging.signature import parse
from naoloc.backends.naoqi.testing import ServedProcess
from tests.fuzz.proc import rss_mb

__all__ = ["rss_mb"]

FAKE: dict[str, Any] = {
    "robot": {"backend": "fake"},
    "world": {"room": {"size_m": [8.0, 8.0], "seed": 3}},
}
HAS_QI = importlib.util.find_spec("qi") is not None
LONG_S = 600.0  # a blocking call that outlives any attack


def cpu_s(pid: int) -> float:
    """CPU seconds (user + system) process ``pid`` used so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def threads(pid: int) -> int:
    """Threads of process ``pid``."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    return 0


def _address(url: str) -> tuple[str, int]:
    parts = urlsplit(url)
    return str(parts.hostname), int(parts.port or 0)


# ---------------------------------------------------------------------------- raw QiMessaging
class RawQi:
    """A QiMessaging connection that sends what it is told and reads only when asked.

    Args:
        url: ``tcp://host:port`` of the server.
        login: ``(user, password)`` to authenticate with; None = an empty capability
            map; False = do not authenticate.
        rcvbuf: Receive buffer (bytes; small = a slow reader), None = the default.
    """

    def __init__(self, url: str, login: tuple[str, str] | bool | None = None,
                 rcvbuf: int | None = None) -> None:  # fmt: skip
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(10.0)
        self.sock.connect(_address(url))
        self._mid = 100
        if login is not False:
            user, token = login if isinstance(login, tuple) else (None, None)
            self.call(0, 0, 8, codec.encode_bytes("{sm}", capability.client_request(user, token)))

    def call(self, service: int, obj: int, action: int, payload: bytes, mtype: int = 1) -> int:
        """Send one message; returns its id."""
        self._mid += 1
        head = message.pack_header(self._mid, len(payload), mtype, 0, service, obj, action)
        self.sock.sendall(head + payload)
        return self._mid

    def read(self, timeout_s: float = 5.0) -> tuple[message.Header, bytes]:
        """The next message (raises TimeoutError or ConnectionError)."""
        self.sock.settimeout(timeout_s)
        head = self._exact(message.HEADER_SIZE)
        header = message.unpack_header(head)
        return header, self._exact(header.size)

    def _exact(self, size: int) -> bytes:
        data = b""
        while len(data) < size:
            chunk = self.sock.recv(size - len(data))
            if not chunk:
                raise ConnectionError("closed by the server")
            data += chunk
        return data

    def close(self) -> None:
        """Close the connection."""
        with contextlib.suppress(OSError):
            self.sock.close()


def method_address(
    url: str, service: str, method: str, password: str | None = None
) -> tuple[int, int, str]:
    """``(service id, action, params signature)`` of ``service.method`` at ``url``."""
    session = QiSession(connect_timeout_s=10.0)
    if password is not None:
        session.set_login("nao", password)
    try:
        session.connect(url)
        proxy = session.service(service)
        meta = proxy.metaObject()
        found = next(m for m in meta.methods.values() if m.name == method)
        return proxy._service_id, found.uid, str(found.params)
    finally:
        session.close()


def moved(url: str, password: str | None = None) -> bool:
    """True when the robot at ``url`` walks or has left its start (odometry)."""
    session = QiSession(connect_timeout_s=10.0)
    if password is not None:
        session.set_login("nao", password)
    try:
        session.connect(url)
        motion = session.service("ALMotion")
        position = motion.getRobotPosition(True)
        return bool(motion.moveIsActive()) or any(abs(v) > 1e-6 for v in position)
    finally:
        session.close()


def encode_args(params: str, *args: Any) -> bytes:
    """Arguments encoded as the method's parameter tuple."""
    return codec.encode_bytes(parse(params), tuple(args))


# ---------------------------------------------------------------------------- raw zmq
class RawZmq:
    """A zmq DEALER speaking naoloc's wire format, reading only when asked."""

    def __init__(self, url: str, rcvbuf: int | None = None) -> None:
        import zmq

        self._ctx = zmq.Context()
        self.sock = self._ctx.socket(zmq.DEALER)
        self.sock.setsockopt(zmq.LINGER, 0)
        if rcvbuf is not None:
            self.sock.setsockopt(zmq.RCVHWM, 1)
            self.sock.setsockopt(zmq.RCVBUF, rcvbuf)
        self.sock.connect(url)
        self._mid = 0

    def call(self, service: str, method: str, *args: Any) -> int:
        """Send a call; returns its id."""
        from naoloc.backends.naoqi import wire

        self._mid += 1
        header = {"k": "call", "i": self._mid, "s": service, "m": method, "a": list(args)}
        self.sock.send_multipart(wire.encode(header))
        return self._mid

    def value(self, timeout_s: float = 5.0) -> Any:
        """The next reply's value (raises TimeoutError)."""
        from naoloc.backends.naoqi import wire

        if not self.sock.poll(int(timeout_s * 1000)):
            raise TimeoutError("no reply")
        return wire.decode_reply(self.sock.recv_multipart()).get("v")

    def close(self) -> None:
        """Close the socket and its context."""
        self.sock.close(0)
        self._ctx.term()


# ---------------------------------------------------------------------------- victims
_VICTIM = r"""
import json, os, sys, time
url, transport = sys.argv[1], sys.argv[2]
user, password = os.environ.get("VICTIM_USER"), os.environ.get("VICTIM_PASSWORD")
if transport in ("qimessaging", "libqi") and os.environ.get("VICTIM_QI") == "1":
    import qi
    session = qi.Session()
    if user:
        class _A:
            def initialAuthData(self):
                return {"user": user, "token": password}
        class _F:
            def newAuthenticator(self):
                return _A()
        session.setClientAuthenticatorFactory(_F())
else:
    import naoloc.qi as qi
    session = qi.Session(transport="zmq" if transport == "zmq" else "qimessaging")
    if user:
        class _A:
            def initialAuthData(self):
                return {"user": user, "token": password}
        class _F:
            def newAuthenticator(self):
                return _A()
        session.setClientAuthenticatorFactory(_F())
t0 = time.monotonic()
session.connect(url)
motion = session.service("ALMotion")
t1 = time.monotonic()
motion.stopMove()
t2 = time.monotonic()
print(json.dumps({"connect_s": t1 - t0, "stop_s": t2 - t1}), flush=True)
os._exit(0)
"""


def victim_stop(
    url: str, transport: str, timeout_s: float = 15.0, login: tuple[str, str] | None = None
) -> tuple[float, float]:
    """A fresh client connects and calls ALMotion.stopMove: ``(connect_s, stop_s)``.

    The real ``qi`` package is the victim of QiMessaging servers when installed, naoloc's
    own client otherwise (and for zmq). ``inf`` marks what did not finish in time.
    """
    env = dict(os.environ, VICTIM_QI="1" if HAS_QI else "0")
    if login:
        env.update(VICTIM_USER=login[0], VICTIM_PASSWORD=login[1])
    process = subprocess.Popen(
        [sys.executable, "-c", _VICTIM, url, transport], stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL, text=True, env=env,
    )  # fmt: skip
    try:
        out, _ = process.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        return float("inf"), float("inf")
    try:
        figures = json.loads(out.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return float("inf"), float("inf")
    return float(figures["connect_s"]), float(figures["stop_s"])


# ---------------------------------------------------------------------------- attacks
@contextlib.contextmanager
def worker_flood(server: ServedProcess, calls: int = 20, conns: int = 1) -> Iterator[None]:
    """``conns`` clients with ``calls`` blocking calls each in flight (wbGoToBalance)."""
    held: list[Any] = []
    if server.transport != "zmq":
        sid, action, params = method_address(server.url, "ALMotion", "wbGoToBalance")
    try:
        for _ in range(conns):
            if server.transport == "zmq":
                raw = RawZmq(server.url)
                for _ in range(calls):
                    raw.call("ALMotion", "wbGoToBalance", "Legs", LONG_S)
            else:
                raw = RawQi(server.url)
                for _ in range(calls):
                    raw.call(sid, 1, action, encode_args(params, "Legs", LONG_S))
            held.append(raw)
        time.sleep(0.5)
        yield
    finally:
        for raw in held:
            raw.close()


@contextlib.contextmanager
def slow_reader(server: ServedProcess, frames: int = 200) -> Iterator[None]:
    """A client that asks for ``frames`` kVGA images and never reads them."""
    if server.transport == "zmq":
        rawz = RawZmq(server.url, rcvbuf=4096)
        try:
            rawz.call("ALVideoDevice", "subscribeCamera", "slow", 0, 2, 11, 30)
            handle = rawz.value()
            for _ in range(frames):
                rawz.call("ALVideoDevice", "getImageRemote", handle)
            yield
        finally:
            rawz.close()
        return
    sid, sub, sub_params = method_address(server.url, "ALVideoDevice", "subscribeCamera")
    _, get, get_params = method_address(server.url, "ALVideoDevice", "getImageRemote")
    raw = RawQi(server.url, rcvbuf=4096)
    raw.sock.settimeout(10.0)
    try:
        raw.read()  # the login answer
        raw.call(sid, 1, sub, encode_args(sub_params, "slow", 0, 2, 11, 30))
        _, body = raw.read()
        handle = codec.decode("s", body)
        raw.sock.settimeout(0.5)
        for _ in range(frames):
            try:
                raw.call(sid, 1, get, encode_args(get_params, handle))
            except OSError:  # the server closed the slow reader
                break
        yield
    finally:
        raw.close()


@contextlib.contextmanager
def idle_connections(server: ServedProcess, count: int = 64) -> Iterator[None]:
    """``count`` TCP connections that never say anything (no login)."""
    socks = []
    try:
        for _ in range(count):
            with contextlib.suppress(OSError):
                socks.append(socket.create_connection(_address(server.url), timeout=2.0))
        time.sleep(0.3)
        yield
    finally:
        for sock in socks:
            sock.close()


@contextlib.contextmanager
def call_flood(server: ServedProcess, calls: int = 20_000) -> Iterator[None]:
    """A client that sends ``calls`` calls and never reads a reply."""
    if server.transport == "zmq":
        rawz = RawZmq(server.url, rcvbuf=4096)
        try:
            for _ in range(calls):
                rawz.call("ALMotion", "getRobotPosition", True)
            yield
        finally:
            rawz.close()
        return
    sid, action, params = method_address(server.url, "ALMotion", "getRobotPosition")
    raw = RawQi(server.url, rcvbuf=4096)
    payload = encode_args(params, True)
    raw.sock.settimeout(2.0)
    try:
        for _ in range(calls):
            try:
                raw.call(sid, 1, action, payload)
            except OSError:  # the server closed the flooder, or stopped reading it
                break
        yield
    finally:
        raw.close()


def nested_map(size: int) -> bytes:
    """A capability map of about ``size`` bytes whose one value is a dynamic ``[[()]]``.

    Each inner list claims 65,536 zero-size elements: without an element budget a 4 KB
    map asks the decoder for about 65 million tuples.
    """
    sig = b"[[()]]"
    inner = max(1, (size - 32) // 4)
    value = struct.pack("<I", len(sig)) + sig + struct.pack("<I", inner)
    value += struct.pack("<I", 65_536) * inner
    return struct.pack("<I", 1) + struct.pack("<I", 1) + b"x" + value


def preauth_cost(server: ServedProcess, size: int, messages: int = 5) -> tuple[float, float]:
    """Server CPU seconds and RSS growth (MB) per unauthenticated nested-map message."""
    pid = server.process.pid
    payload = nested_map(size)
    cpu0, rss0 = cpu_s(pid), rss_mb(pid)
    for _ in range(messages):
        raw = RawQi(server.url, login=False)
        try:
            raw.call(0, 0, 8, payload)
            with contextlib.suppress(OSError, ConnectionError, TimeoutError):
                raw.read(timeout_s=30.0)
        finally:
            raw.close()
    time.sleep(0.3)
    return (cpu_s(pid) - cpu0) / messages, (rss_mb(pid) - rss0) / messages


_DRIVER = r"""
import os, sys, time
url, transport = sys.argv[1], sys.argv[2]
if transport in ("qimessaging", "libqi") and os.environ.get("VICTIM_QI") == "1":
    import qi
else:
    import naoloc.qi as qi
session = qi.Session() if qi.__name__ == "qi" else qi.Session(
    transport="zmq" if transport == "zmq" else "qimessaging")
session.connect(url)
motion = session.service("ALMotion")
motion.wakeUp()
motion.move(0.3, 0.0, 0.0)
print("moving", flush=True)
time.sleep(120)
"""


def frozen_client_stop_s(server: ServedProcess, timeout_s: float = 10.0) -> float:
    """Seconds from SIGSTOP of a client that started a velocity walk to the robot's stop."""
    env = dict(os.environ, VICTIM_QI="1" if HAS_QI else "0")
    driver = subprocess.Popen(
        [sys.executable, "-c", _DRIVER, server.url, server.transport], stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL, text=True, env=env,
    )  # fmt: skip
    watcher = QiSession() if server.transport != "zmq" else None
    try:
        assert driver.stdout is not None
        for line in driver.stdout:  # libqi may print a notice on stdout first
            if line.strip() == "moving":
                break
        else:
            return float("inf")
        active = _watch(server, watcher)
        driver.send_signal(signal.SIGSTOP)
        stopped = time.monotonic()
        deadline = stopped + timeout_s
        while time.monotonic() < deadline:
            if not active():
                return time.monotonic() - stopped
            time.sleep(0.02)
        return float("inf")
    finally:
        driver.kill()
        driver.wait()
        if watcher is not None:
            watcher.close()


def _watch(server: ServedProcess, watcher: QiSession | None) -> Any:
    if watcher is not None:
        watcher.connect(server.url)
        motion = watcher.service("ALMotion")
        return lambda: bool(motion.moveIsActive())
    from naoloc.backends.naoqi.zmq_transport import ZmqSession

    zmq_session = ZmqSession()
    zmq_session.connect(server.url)
    proxy = zmq_session.service("ALMotion")
    return lambda: bool(proxy.moveIsActive())
