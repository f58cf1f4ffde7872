"""Hostile peers: fuzzed frames against our server and our client.

The server (``naoloc serve --transport qimessaging``) takes 10,000+ seeded random
messages (random bytes, truncated and lying headers, huge sizes, wrong signatures,
calls to anything) without dying, without a traceback, with bounded memory, and
still answers a proper client afterwards. The client facing a hostile server fails
``connect`` with one line, in bounded time.
"""

from __future__ import annotations

import contextlib
import random
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from naoloc.backends.naoqi.qimessaging import capability, codec, message
from naoloc.backends.naoqi.qimessaging.client import QiSession
from naoloc.backends.naoqi.testing import served
from naoloc.errors import NaolocError

pytestmark = pytest.mark.net

FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}
MESSAGES = 10_000


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def _frame(rng: random.Random) -> tuple[bytes, bool]:
    """One hostile frame; True when it is expected to end the connection."""
    pick = rng.random()
    if pick < 0.05:
        return rng.randbytes(rng.randint(1, 64)), True  # noise
    if pick < 0.08:
        return message.pack_header(1, 0, 1, 0, 1, 1, 100)[: rng.randint(1, 27)], True
    if pick < 0.10:  # a lying size beyond the server's limit
        return message.MAGIC_BYTES + struct.pack("<IIHBBIII", 1, 2**31, 0, 1, 0, 1, 1, 101), True
    mtype = rng.choice([1, 1, 1, 2, 3, 4, 5, 6, 7, 8])
    service = rng.choice([0, 1, 1, 2, 3, 4, 5, 6, 7, 99])
    obj = rng.choice([0, 1, 1, 1, 2])
    action = rng.choice([0, 1, 2, 3, 5, 6, 7, 8, 100, 101, 102, 103, 104, 105, 108, 109, 150])
    if rng.random() < 0.5:
        payload = rng.randbytes(rng.randint(0, 80))
    else:  # well-formed values of the wrong type
        sig = rng.choice(["s", "i", "(ddd)", "[m]", "m", "{sm}", "(s)", "(I)", "(IIL)", "(iiiii)"])
        value = {"s": "x", "i": 7, "(ddd)": (1.0, 2.0, 3.0), "[m]": [1, "a"], "m": [None],
                 "{sm}": {"a": 1}, "(s)": ("ALMotion",), "(I)": (2,), "(IIL)": (2, 100, 5),
                 "(iiiii)": (0, 1, 11, 30, 1)}[sig]  # fmt: skip
        payload = codec.encode_bytes(sig, value)
    flags = rng.choice([0, 0, 0, message.FLAG_DYNAMIC_PAYLOAD, message.FLAG_RETURN_TYPE])
    if flags == message.FLAG_DYNAMIC_PAYLOAD and rng.random() < 0.5:  # dynamic arguments
        payload = codec.encode_bytes("m", rng.choice([(None, "x", 3), (1, 2, 3), ("a",), [2.0]]))
    mid = rng.randint(0, 2**32 - 1)
    header = message.pack_header(mid, len(payload), mtype, flags, service, obj, action)
    return header + payload, False


def _drain(sock: socket.socket) -> None:
    with contextlib.suppress(OSError):
        while sock.recv(65536):
            pass


_DRAINS: dict[socket.socket, threading.Thread] = {}


def _close(sock: socket.socket) -> None:
    """Shut the connection, wait for its drain thread to see it, then close it.

    Closing first would leave the thread in ``recv`` until its 5 s timeout: hundreds of
    threads alive at once in the test runner.
    """
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_RDWR)  # wakes the drain thread, sends FIN
    drain = _DRAINS.pop(sock, None)
    if drain is not None:
        drain.join(timeout=5)
    sock.close()


def _connect(url: str, authenticate: bool) -> socket.socket:
    host, port = url[len("tcp://") :].rsplit(":", 1)
    sock = socket.create_connection((host, int(port)), timeout=5)
    drain = threading.Thread(target=_drain, args=(sock,), daemon=True)
    drain.start()
    _DRAINS[sock] = drain
    if authenticate:
        payload = codec.encode_bytes("{sm}", capability.client_request())
        sock.sendall(message.pack_header(1, len(payload), 1, 0, 0, 0, 8) + payload)
    return sock


def test_ten_thousand_hostile_messages_do_not_hurt_the_server() -> None:
    rng = random.Random(1234)
    with served(FAKE, "qimessaging") as server:
        pid = server.process.pid
        before = _rss_mb(pid)
        sock = _connect(server.url, True)
        sent = reconnects = 0
        try:
            while sent < MESSAGES:
                data, ends = _frame(rng)
                try:
                    sock.sendall(data)
                except OSError:
                    ends = True
                sent += 1
                if ends:
                    _close(sock)
                    sock = _connect(server.url, rng.random() < 0.8)
                    reconnects += 1
        finally:
            _close(sock)
        assert reconnects > 100
        time.sleep(0.5)
        assert server.process.poll() is None, "the server died"
        grown = _rss_mb(pid) - before
        assert grown < 50, f"server memory grew by {grown:.1f} MB"
        session = QiSession(connect_timeout_s=5)
        session.connect(server.url)
        try:
            pose = session.service("ALMotion").getRobotPosition(True)  # fuzzed calls may move it
            assert len(pose) == 3 and all(isinstance(v, float) for v in pose)
        finally:
            session.close()
        assert "Traceback" not in server.stderr(), server.stderr()[-2000:]


@contextlib.contextmanager
def _hostile_server(respond: Callable[[socket.socket], None]) -> Iterator[str]:
    listener = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                return
            with contextlib.suppress(OSError):
                conn.settimeout(3)
                respond(conn)
                time.sleep(0.05)
            conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    finally:
        stop.set()
        listener.close()
        thread.join(2)


def _reply_to_auth(payload: bytes, mtype: int = message.REPLY) -> Callable[[socket.socket], None]:
    def respond(conn: socket.socket) -> None:
        head = conn.recv(28)
        mid = struct.unpack_from("<I", head, 4)[0] if len(head) >= 8 else 1
        conn.sendall(message.pack_header(mid, len(payload), mtype, 0, 0, 0, 8) + payload)

    return respond


HOSTILE = {
    "noise": lambda conn: conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n" * 3),
    "zmq greeting": lambda conn: conn.sendall(b"\xff" + b"\x00" * 8 + b"\x7f" * 3),
    "huge size": lambda conn: conn.sendall(
        message.MAGIC_BYTES + struct.pack("<IIHBBIII", 1, 2**32 - 1, 0, 2, 0, 0, 0, 8)
    ),
    "truncated": lambda conn: conn.sendall(message.pack_header(1, 0, 2, 0, 0, 0, 8)[:13]),
    "silent": lambda conn: time.sleep(2.5),
    "wrong reply type": _reply_to_auth(codec.encode_bytes("i", 3)),
    "refused login": _reply_to_auth(
        codec.encode_bytes("{sm}", capability.server_reply({}, capability.STATE_ERROR, "no"))
    ),
    "error reply": _reply_to_auth(codec.encode_bytes("m", "go away"), message.ERROR),
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_client_facing_a_hostile_server_fails_with_one_line(name: str) -> None:
    with _hostile_server(HOSTILE[name]) as url:
        session = QiSession(connect_timeout_s=1.5)
        started = time.monotonic()
        with pytest.raises(NaolocError) as info:
            session.connect(url)
        session.close()
    assert time.monotonic() - started < 3.0
    assert "\n" not in str(info.value) and str(info.value)


@settings(max_examples=60, deadline=None)
@given(payload=st.binary(max_size=200), flags=st.sampled_from([0, 1]))
def test_client_survives_random_authentication_replies(payload: bytes, flags: int) -> None:
    def respond(conn: socket.socket) -> None:
        head = conn.recv(28)
        mid = struct.unpack_from("<I", head, 4)[0] if len(head) >= 8 else 1
        conn.sendall(message.pack_header(mid, len(payload), 2, flags, 0, 0, 8) + payload)

    with _hostile_server(respond) as url:
        session = QiSession(connect_timeout_s=1.0)
        try:
            session.connect(url)
        except NaolocError as err:
            assert "\n" not in str(err)
        finally:
            session.close()


def _wait_for_count(predicate: Callable[[], bool], timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_a_flood_of_calls_is_bounded_not_queued_forever() -> None:
    from naoloc.backends.naoqi.qimessaging.server import MAX_IN_FLIGHT, QiServer

    release = threading.Event()

    class Slow:
        def wait(self) -> int:
            release.wait(5.0)
            return 1

    server = QiServer(workers=4)
    server.listen("tcp://127.0.0.1:0")
    server.register("Slow", Slow(), methods=[("wait", "()", "i")])
    session = QiSession()
    session.connect(server.url())
    try:
        slow = session.service("Slow")
        futures = [slow.wait(_async=True) for _ in range(MAX_IN_FLIGHT + 20)]
        assert _wait_for_count(lambda: sum(f.isFinished() for f in futures) >= 20, 5.0)
        refused = [f for f in futures if f.isFinished() and "too many calls" in f.error()]
        assert len(refused) >= 20
        release.set()
        answered = [f.value(5000) for f in futures if f not in refused]
        assert answered == [1] * len(answered) and len(answered) <= MAX_IN_FLIGHT
    finally:
        release.set()
        session.close()
        server.close()


class _Echo:
    def echo(self, value: object) -> object:
        return value

    def add(self, a: int, b: float) -> float:
        return a + b


@pytest.fixture(scope="module")
def echo_server() -> Iterator[str]:
    from naoloc.backends.naoqi.qimessaging.server import QiServer

    server = QiServer()
    server.listen("tcp://127.0.0.1:0")
    server.register("Echo", _Echo(), methods=[("echo", "(m)", "m"), ("add", "(id)", "d")])
    try:
        yield server.url()
    finally:
        server.close()


def _read_message(sock: socket.socket) -> tuple[message.Header, bytes]:
    head = b""
    while len(head) < message.HEADER_SIZE:
        chunk = sock.recv(message.HEADER_SIZE - len(head))
        assert chunk, "the server closed the connection"
        head += chunk
    header = message.unpack_header(head)
    payload = b""
    while len(payload) < header.size:
        payload += sock.recv(header.size - len(payload))
    return header, payload


_DYNAMIC_VALUES = st.recursive(
    st.none() | st.integers(-5, 5) | st.text(max_size=4), lambda c: st.lists(c, max_size=3)
)


@settings(max_examples=300, deadline=None)
@given(
    action=st.sampled_from([0, 1, 2, 3, 5, 6, 7, 8, 100, 101, 102, 150]),
    service=st.sampled_from([1, 2, 3]),
    flags=st.sampled_from([0, 1, 2]),
    payload=st.binary(max_size=120)
    | st.builds(lambda v: codec.encode_bytes("m", v), _DYNAMIC_VALUES),
)
def test_every_well_framed_call_gets_one_answer(
    echo_server: str, action: int, service: int, flags: int, payload: bytes
) -> None:
    with contextlib.closing(_connect_plain(echo_server)) as sock:
        mid = 77
        sock.sendall(message.pack_header(mid, len(payload), 1, flags, service, 1, action) + payload)
        header, body = _read_message(sock)
        assert header.id == mid and header.type in (message.REPLY, message.ERROR)
        if header.type == message.ERROR:
            text = codec.decode("m", body)
            assert isinstance(text, str) and "\n" not in text
        good = codec.encode_bytes("(id)", (2, 0.5))  # the connection still works
        sock.sendall(message.pack_header(78, len(good), 1, 0, 2, 1, 101) + good)
        header, body = _read_message(sock)
        assert header.id == 78 and codec.decode("d", body) == 2.5


def _connect_plain(url: str) -> socket.socket:
    host, port = url[len("tcp://") :].rsplit(":", 1)
    sock = socket.create_connection((host, int(port)), timeout=5)
    request = codec.encode_bytes("{sm}", capability.client_request())
    sock.sendall(message.pack_header(1, len(request), 1, 0, 0, 0, 8) + request)
    header, _ = _read_message(sock)
    assert header.type == message.REPLY
    return sock


def test_a_capability_message_is_taken_and_the_connection_goes_on(echo_server: str) -> None:
    with contextlib.closing(_connect_plain(echo_server)) as sock:
        caps = codec.encode_bytes("{sm}", {**capability.LOCAL, "ObjectPtrUID": False})
        sock.sendall(message.pack_header(5, len(caps), message.CAPABILITY, 0, 0, 0, 0) + caps)
        call = codec.encode_bytes("(I)", (0,))
        sock.sendall(message.pack_header(6, len(call), 1, 0, 2, 1, 2) + call)  # metaObject
        header, body = _read_message(sock)
        assert header.id == 6 and header.type == message.REPLY
        meta = codec.decode(codec.METAOBJECT_SIGNATURE, body, object_uid=False)
        assert any(entry[2] == "echo" for entry in meta[0].values())
