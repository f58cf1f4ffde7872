"""naoloc's QiMessaging against the real qi package on loopback, both directions.

1. Our client against a libqi server (a subprocess) exposing methods of every signature.
2. Real libqi clients against our server: a test service, and ``naoloc serve``.
Skipped, with the reason, where the qi package is not installed.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

import naoloc.qi as nqi
from naoloc.backends.naoqi.qimessaging.client import QiSession
from naoloc.backends.naoqi.testing import served
from naoloc.errors import ConnectionLost, RobotError

pytestmark = [
    pytest.mark.net,
    pytest.mark.skipif(
        importlib.util.find_spec("qi") is None,
        reason="the qi package (libqi) is not installed: no libqi peer to test against",
    ),
]

# (signature, value sent, value expected back)
ECHOES: list[tuple[str, Any, Any]] = [
    ("b", True, True), ("c", -5, -5), ("C", 200, 200), ("w", -300, -300), ("W", 60000, 60000),
    ("i", -(2**31), -(2**31)), ("I", 2**32 - 1, 2**32 - 1), ("l", -(2**62), -(2**62)),
    ("L", 2**40, 2**40), ("f", 1.5, 1.5), ("d", 0.1, 0.1), ("s", "héllo", "héllo"),
    ("[d]", [0.5, -1.0], [0.5, -1.0]), ("{si}", {"a": 1, "b": 2}, {"a": 1, "b": 2}),
    ("(isd)", (1, "x", 2.5), (1, "x", 2.5)), ("[{s[i]}]", [{"k": [1, 2]}], [{"k": [1, 2]}]),
    ("m", [1, "a", 2.5, {"k": True}], [1, "a", 2.5, {"k": True}]), ("+i", 4, 4),
]  # fmt: skip

LIBQI_SERVICE = r"""
import sys, time, qi
qi.logging.setLevel(qi.logging.ERROR)
SIGS = sys.argv[1].split("|")

class Child:
    @qi.bind(qi.Int32, [])
    def val(self):
        return 7

class Service:
    def __init__(self):
        self.tick = qi.Signal("(is)")
        self.level = qi.Property("i")
        self.kids = []
    @qi.bind(qi.Object, [])
    def child(self):
        self.kids.append(Child())
        return self.kids[-1]
    @qi.bind(qi.Void, [qi.Int32])
    def fire(self, n):
        self.tick(n, "x")
    @qi.bind(qi.Int32, [])
    def fail(self):
        raise RuntimeError("boom")
    @qi.bind(qi.Int32, [qi.Int32])
    def slow(self, ms):
        time.sleep(ms / 1000.0)
        return ms
    @qi.bind("r", [qi.Int32])
    def image(self, n):
        return bytearray(i % 251 for i in range(n))

for k, sig in enumerate(SIGS):
    setattr(Service, "echo%d" % k, qi.bind(sig, [sig], methodName="echo%d" % k)(lambda self, v: v))

session = qi.Session()
session.listenStandalone("tcp://127.0.0.1:0")
session.registerService("QimTest", Service())
print(session.endpoints()[0], flush=True)
sys.stdin.read()
"""


@pytest.fixture(scope="module")
def libqi_url() -> Iterator[str]:
    sigs = "|".join(sig for sig, _, _ in ECHOES)
    cmd = [sys.executable, "-c", LIBQI_SERVICE, sigs]
    child = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        yield child.stdout.readline().strip()
    finally:
        assert child.stdin is not None
        child.stdin.close()
        child.wait(timeout=10)


@pytest.fixture
def ours(libqi_url: str) -> Iterator[Any]:
    session = QiSession()
    session.connect(libqi_url)
    try:
        yield session
    finally:
        session.close()


@pytest.mark.parametrize(("k", "case"), list(enumerate(ECHOES)), ids=[c[0] for c in ECHOES])
def test_our_client_calls_libqi_methods_of_every_signature(
    ours: Any, k: int, case: tuple[str, Any, Any]
) -> None:
    sig, sent, expected = case
    service = ours.service("QimTest")
    assert str(service.metaObject().overloads(f"echo{k}")[0].params) == f"({sig})"
    assert getattr(service, f"echo{k}")(sent) == expected


def test_our_client_gets_libqi_buffers_signals_properties_objects_errors(ours: Any) -> None:
    service = ours.service("QimTest")
    image = service.image(230400)
    assert isinstance(image, memoryview) and bytes(image[:3]) == b"\x00\x01\x02"
    assert len(image) == 230400
    got: list[tuple[Any, ...]] = []
    link = service.tick.connect(lambda *args: got.append(args))
    service.fire(4)
    deadline = time.monotonic() + 2
    while not got and time.monotonic() < deadline:
        time.sleep(0.01)
    assert got == [(4, "x")]
    assert service.tick.disconnect(link)
    service.fire(5)
    time.sleep(0.2)
    assert got == [(4, "x")]
    assert service.level.value() == 0
    service.level.setValue(9)
    assert service.level.value() == 9
    assert service.child().val() == 7  # an object returned by a method
    with pytest.raises(RobotError, match="boom") as info:
        service.fail()
    assert "\n" not in str(info.value)
    with pytest.raises(RobotError, match="do not match|takes 1 arguments"):
        service.echo0("not a bool", 2)
    with pytest.raises(RobotError, match="no service 'Nope'"):
        ours.service("Nope")
    names = [info["name"] for info in ours.services()]
    assert names == ["ServiceDirectory", "QimTest"]


def test_cancel_and_a_dying_libqi_server(libqi_url: str) -> None:
    # A server of its own, killed mid-call: the pending call and the disconnected
    # signal both report it within 2 s.
    cmd = [sys.executable, "-c", LIBQI_SERVICE, "i"]
    child = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    session = QiSession()
    try:
        assert child.stdout is not None
        session.connect(child.stdout.readline().strip())
        service = session.service("QimTest")
        future = service.slow(3000, _async=True)
        future.cancel()  # a Python libqi method cannot stop: it still answers or is cancelled
        lost = threading.Event()
        session.disconnected.connect(lambda *why: lost.set())
        pending = service.slow(5000, _async=True)
        child.kill()
        started = time.monotonic()
        with pytest.raises(ConnectionLost, match="lost") as info:
            pending.value(5000)
        assert time.monotonic() - started < 2.0 and "\n" not in str(info.value)
        assert lost.wait(2.0)
        assert not session.isConnected()
    finally:
        session.close()
        child.kill()
        child.wait(timeout=10)


# ---------------------------------------------------------------------------- libqi -> ours
class _Echoes:
    """A service served by our server (naoloc.qi.bind), one echo per signature."""

    def __init__(self) -> None:
        self.tick = nqi.Signal("(is)")

    @nqi.bind(nqi.Void, [nqi.Int32])
    def fire(self, n: int) -> None:
        self.tick(n, "y")

    @nqi.bind(nqi.Int32, [])
    def fail(self) -> int:
        raise RobotError("refused on purpose")

    @nqi.bind("r", [nqi.Int32])
    def image(self, n: int) -> bytes:
        return bytes(i % 251 for i in range(n))


for _k, (_sig, _, _) in enumerate(ECHOES):
    setattr(_Echoes, f"echo{_k}", nqi.bind(_sig, [_sig], methodName=f"echo{_k}")(lambda s, v: v))


@pytest.fixture
def our_server() -> Iterator[str]:
    server = nqi.Session()
    server.listenStandalone("tcp://127.0.0.1:0")
    server.registerService("Echoes", _Echoes())
    try:
        yield server.endpoints()[0]
    finally:
        server.close()


def test_libqi_client_calls_our_server_with_every_signature(our_server: str) -> None:
    qi = pytest.importorskip("qi")
    session = qi.Session()
    session.connect(our_server)
    try:
        echoes = session.service("Echoes")
        for k, (sig, sent, expected) in enumerate(ECHOES):
            back = getattr(echoes, f"echo{k}")(sent)
            if sig.startswith("("):
                back = tuple(back)
            assert back == expected, sig
        image = echoes.image(100000)
        assert isinstance(image, bytearray) and image[:3] == b"\x00\x01\x02"
        got: list[tuple[Any, ...]] = []
        echoes.tick.connect(lambda *args: got.append(args))
        echoes.fire(3)
        deadline = time.monotonic() + 2
        while not got and time.monotonic() < deadline:
            time.sleep(0.01)
        assert got == [(3, "y")]
        with pytest.raises(RuntimeError, match="RobotError: refused on purpose"):
            echoes.fail()
        assert [s["name"] for s in session.services()] == ["ServiceDirectory", "Echoes"]

        class Intruder:
            @qi.bind(qi.Int32, [])
            def x(self) -> int:
                return 1

        with pytest.raises(RuntimeError, match="already registered"):
            session.registerService("Echoes", Intruder())
        session.registerService("Intruder", Intruder())  # a client's own, served by the client
        assert session.service("Intruder").x() == 1
        with pytest.raises(RuntimeError, match="cannot be unregistered"):
            session.service("ServiceDirectory").unregisterService(2)
    finally:
        session.close()


FAKE = {"robot": {"backend": "fake"}, "world": {"room": {"size_m": [4.0, 4.0], "seed": 3}}}


def test_libqi_clients_use_naoloc_serve_over_qimessaging() -> None:
    qi = pytest.importorskip("qi")
    with served(FAKE, "qimessaging") as server:
        driver, watcher = qi.Session(), qi.Session()
        driver.connect(server.url)
        watcher.connect(server.url)
        try:
            motion, video = driver.service("ALMotion"), driver.service("ALVideoDevice")
            assert motion.getRobotPosition(True) == [0.0, 0.0, 0.0]
            handle = video.subscribeCamera("native", 0, 1, 11, 30)
            frame = video.getImageRemote(handle)
            assert isinstance(frame[6], bytearray) and len(frame[6]) == 320 * 240 * 3
            assert frame[:3] == (320, 240, 3) or list(frame[:3]) == [320, 240, 3]
            with pytest.raises(RuntimeError, match="HandleError"):
                video.getImageRemote("no-such-handle")
            assert motion.moveTo(0.1, 0.0, 0.0) is True  # overload (ddd) of (ddd)|(m)
            assert motion.moveTo([[0.1, 0.0, 0.0]]) is True  # overload (m)
            # Each connection is its own caller: the driver's walk stops (dead-man) once
            # the driver goes away, although the watcher keeps calling.
            motion.wakeUp()
            motion.move(0.05, 0.0, 0.0)
            driver.close()
            watch = watcher.service("ALMotion")
            deadline = time.monotonic() + 5.0  # 0.5 s dead-man; generous for a loaded CI
            while watch.moveIsActive() and time.monotonic() < deadline:
                watcher.service("NaolocWatchdog").ping()
                time.sleep(0.05)
            assert not watch.moveIsActive()
            assert "dead-man" in server.stderr()
        finally:
            driver.close()
            watcher.close()


class _Subscriber:
    """What ALMemory.subscriber(key) returns: an object with a signal."""

    def __init__(self) -> None:
        self.signal = nqi.Signal("(m)")

    @nqi.bind(nqi.String, [])
    def key(self) -> str:
        return "Touched"


class _Memory:
    def __init__(self) -> None:
        self.subscribers: list[_Subscriber] = []

    @nqi.bind(nqi.Object, [nqi.String])
    def subscriber(self, key: str) -> _Subscriber:
        self.subscribers.append(_Subscriber())
        return self.subscribers[-1]

    @nqi.bind(nqi.Void, [nqi.Dynamic])
    def raiseEvent(self, value: object) -> None:
        for sub in self.subscribers:
            sub.signal(value)


@pytest.mark.parametrize("client", ["libqi", "ours"])
def test_objects_returned_by_our_server_carry_signals(client: str) -> None:
    server = nqi.Session()
    server.listenStandalone("tcp://127.0.0.1:0")
    server.registerService("Memory", _Memory())
    qi = pytest.importorskip("qi") if client == "libqi" else nqi
    session = qi.Session()
    session.connect(server.endpoints()[0])
    try:
        memory = session.service("Memory")
        sub = memory.subscriber("Touched")
        assert sub.key() == "Touched"
        got: list[object] = []
        sub.signal.connect(got.append)
        memory.raiseEvent([1, "head"])
        deadline = time.monotonic() + 2
        while not got and time.monotonic() < deadline:
            time.sleep(0.01)
        assert got == [[1, "head"]]
    finally:
        session.close()
        server.close()


class _CoreMemory:
    """A served core's memory, as the virtual NAOqi's: listeners hear every event."""

    def __init__(self) -> None:
        self.listeners: list[Any] = []

    def add_listener(self, listener: Any) -> None:
        self.listeners.append(listener)

    def raiseEvent(self, key: str, value: object) -> None:
        for listener in self.listeners:
            listener(key, value)


class _Core:
    def __init__(self) -> None:
        self.memory = _CoreMemory()
        self.gone_callers: list[str] = []

    def gone(self, caller: str) -> None:
        self.gone_callers.append(caller)


class _MemoryEndpoint:
    def __init__(self, core: _Core) -> None:
        self._core = core

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        if method == "raiseEvent":
            self._core.memory.raiseEvent(*args)
            return None
        raise RobotError(f"ALMemory.{method}: not served here")


@pytest.mark.parametrize("client", ["libqi", "ours"])
def test_almemory_subscriber_signals_reach_libqi_and_our_clients(client: str) -> None:
    from naoloc.backends.naoqi.qimessaging.server import QiServer

    core = _Core()
    server = QiServer()
    server.listen("tcp://127.0.0.1:0")
    server.set_core(core)
    methods = [("subscriber", "(s)", "o"), ("raiseEvent", "(sm)", "v")]
    server.register("ALMemory", _MemoryEndpoint(core), methods=methods)
    qi = pytest.importorskip("qi") if client == "libqi" else nqi
    session = qi.Session()
    session.connect(server.endpoints()[0])
    try:
        memory = session.service("ALMemory")
        touched = memory.subscriber("FrontTactilTouched")
        other = memory.subscriber("Other")
        got: list[object] = []
        touched.signal.connect(got.append)
        other.signal.connect(lambda v: got.append(("other", v)))
        memory.raiseEvent("FrontTactilTouched", 1.0)
        deadline = time.monotonic() + 2
        while not got and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.1)
        assert got == [1.0]
        with pytest.raises(RuntimeError, match="key"):
            memory.subscriber("")
    finally:
        session.close()
    deadline = time.monotonic() + 2
    while not core.gone_callers and time.monotonic() < deadline:
        time.sleep(0.01)
    assert core.gone_callers and core.gone_callers[0].startswith("qim-")
    server.close()
