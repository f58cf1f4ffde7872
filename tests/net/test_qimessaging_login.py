"""NAOqi 2.9's way in: TLS (``tcps://``) and a user/password login, ours and libqi's.

Our server (a self-signed certificate made with the ``openssl`` command, as a NAO's
is self-signed) with a login; our client and, where installed, libqi's client with
``setClientAuthenticatorFactory`` log in; a wrong password is refused in one line.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import naoloc.qi as nqi
from naoloc.backends.naoqi.qimessaging.client import QiSession
from naoloc.backends.naoqi.qimessaging.server import QiServer
from naoloc.errors import BackendError, ConnectionLost, RobotError

pytestmark = pytest.mark.net


class _Twice:
    def twice(self, x: int) -> int:
        return 2 * x


class _Auth:
    def __init__(self, user: str, token: str) -> None:
        self.data = {"user": user, "token": token}

    def initialAuthData(self) -> dict[str, str]:
        return self.data


class _Factory:
    def __init__(self, user: str, token: str) -> None:
        self.auth = _Auth(user, token)

    def newAuthenticator(self) -> _Auth:
        return self.auth


@pytest.fixture
def tls_url(tmp_path: Path) -> Iterator[str]:
    if shutil.which("openssl") is None:
        pytest.skip("no openssl command to make a test certificate")
    key, cert = tmp_path / "key.pem", tmp_path / "cert.pem"
    made = subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(key),
         "-out", str(cert), "-days", "1", "-subj", "/CN=localhost"],
        capture_output=True,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    server = QiServer(users={"nao": "s3cret"}, certfile=str(cert), keyfile=str(key))
    server.listen("tcps://127.0.0.1:0")
    server.register("Twice", _Twice(), methods=[("twice", "(i)", "i")])
    try:
        yield server.endpoints()[0]
    finally:
        server.close()


def test_our_client_logs_in_over_tls(tls_url: str) -> None:
    session = QiSession()
    session.set_login("nao", "s3cret")
    session.connect(tls_url)
    try:
        assert session.service("Twice").twice(21) == 42
    finally:
        session.close()
    for user, password in [("nao", "wrong"), ("root", "s3cret")]:
        session = QiSession()
        session.set_login(user, password)
        with pytest.raises(ConnectionLost, match="refused: wrong user or password") as info:
            session.connect(tls_url)
        assert "\n" not in str(info.value)
    with pytest.raises(ConnectionLost, match="refused"):
        QiSession().connect(tls_url)  # no login at all


def test_naoloc_qi_login_like_a_naoqi_29_script(tls_url: str) -> None:
    session = nqi.Session()
    session.setClientAuthenticatorFactory(_Factory("nao", "s3cret"))
    session.connect(tls_url)
    try:
        assert session.service("Twice").twice(2) == 4
    finally:
        session.close()


@pytest.mark.skipif(importlib.util.find_spec("qi") is None, reason="qi not installed")
def test_libqi_client_logs_in_to_our_tls_server(tls_url: str) -> None:
    import qi

    session = qi.Session()
    session.setClientAuthenticatorFactory(_Factory("nao", "s3cret"))
    session.connect(tls_url)
    try:
        assert session.service("Twice").twice(5) == 10
    finally:
        session.close()


def test_tls_needs_a_certificate() -> None:
    with pytest.raises(BackendError, match="certificate"):
        QiServer().listen("tcps://127.0.0.1:0")


def test_the_naoloc_link_logs_in_over_qimessaging(tls_url: str) -> None:
    from naoloc.backends.naoqi.client import Link

    link = Link(tls_url, "qimessaging", user="nao", password="s3cret")
    link.open()
    try:
        assert link.has_service("Twice")
        assert link.call("Twice", "twice", 8, timeout_s=5.0) == 16
    finally:
        link.close()
    refused = Link(tls_url, "qimessaging", user="nao", password="nope")
    with pytest.raises(ConnectionLost, match="wrong user or password") as info:
        refused.open()
    assert "\n" not in str(info.value)


def test_tls_survives_concurrent_callers(tls_url: str) -> None:
    """Calls from several threads while the reader waits: one SSL state, never shared."""
    from concurrent.futures import ThreadPoolExecutor

    session = QiSession()
    session.set_login("nao", "s3cret")
    session.connect(tls_url)
    try:
        twice = session.service("Twice")
        with ThreadPoolExecutor(4) as pool:
            got = list(pool.map(lambda x: twice.twice(x), range(400)))
        assert got == [2 * x for x in range(400)]
    finally:
        session.close()


class _Greeter:
    def greet(self, name: str) -> str:
        return f"hello {name}"


def _names(session: QiSession) -> set[str]:
    return {s["name"] for s in session.services()}


def test_client_services_need_the_login_and_go_with_their_client() -> None:
    """Clients may register services of their own (as on a NAO), only once logged in, at
    most MAX_SERVICES_PER_CLIENT each; the directory drops them when their client leaves."""
    import socket

    from naoloc.backends.naoqi.qimessaging import codec, message
    from naoloc.backends.naoqi.qimessaging.directory import MAX_SERVICES_PER_CLIENT
    from naoloc.backends.naoqi.qimessaging.meta import SERVICE_INFO_SIGNATURE

    server = QiServer(users={"nao": "s3cret"})
    server.listen("tcp://127.0.0.1:0")  # a login over plain TCP is allowed on loopback
    url = server.endpoints()[0]
    owner, caller = QiSession(), QiSession()
    try:
        host, port = url.split("//")[1].rsplit(":", 1)
        with socket.create_connection((host, int(port))) as sock:
            info = ("Intruder", 0, "m", 1, ["tcp://127.0.0.1:1"], "", b"")
            payload = codec.encode_bytes(f"({SERVICE_INFO_SIGNATURE})", (info,))
            sock.sendall(message.pack_header(1, len(payload), message.CALL, 0, 1, 1, 102) + payload)
            sock.settimeout(5)
            answer = message.unpack_header(sock.recv(message.HEADER_SIZE))
            assert answer.type == message.ERROR  # before the login: refused, not listed
        owner.set_login("nao", "s3cret")
        owner.connect(url)
        caller.set_login("nao", "s3cret")
        caller.connect(url)
        assert "Intruder" not in _names(caller)
        owner.registerService("Greeter", _Greeter(), methods=[("greet", "(s)", "s")])
        assert caller.service("Greeter").greet("nao") == "hello nao"
        for i in range(1, MAX_SERVICES_PER_CLIENT):
            owner.registerService(f"Greeter{i}", _Greeter(), methods=[("greet", "(s)", "s")])
        with pytest.raises(RobotError, match=f"at most {MAX_SERVICES_PER_CLIENT} services"):
            owner.registerService("OneTooMany", _Greeter(), methods=[("greet", "(s)", "s")])
        assert server.refused.get("services") == 1
        owner.close()
        deadline = time.monotonic() + 5
        while "Greeter" in _names(caller) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not {n for n in _names(caller) if n.startswith("Greeter")}
    finally:
        owner.close()
        caller.close()
        server.close()
