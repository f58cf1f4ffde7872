"""Issue 34, item 7: the naoloc client defends itself as the server does.

Over ``tcps://`` the robot's certificate is checked before the password goes out:
pinned on first use (a later, different certificate is refused), a ``sha256:`` pin, a
CA/certificate PEM, or ``insecure`` with a warning. A password never goes over plain TCP
off loopback, nor from a ``tcps://`` directory to a ``tcp://`` endpoint it lists. A
hostile server's answer cannot make the client decode billions of elements.
"""

from __future__ import annotations

import shutil
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from naoloc.backends.naoqi.qimessaging import message
from naoloc.backends.naoqi.qimessaging.client import QiSession, _may_send_password
from naoloc.backends.naoqi.qimessaging.server import QiServer
from naoloc.backends.naoqi.qimessaging.trust import fingerprint, parse_trust
from naoloc.errors import BackendError, ConnectionLost
from tests.fuzz.attacks import nested_map

pytestmark = pytest.mark.net


class _Twice:
    def twice(self, x: int) -> int:
        return 2 * x


def _certificate(folder: Path, name: str) -> tuple[Path, Path]:
    if shutil.which("openssl") is None:
        pytest.skip("no openssl command to make a test certificate")
    key, cert = folder / f"{name}.key", folder / f"{name}.pem"
    made = subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(key),
         "-out", str(cert), "-days", "1", "-subj", "/CN=nao"],
        capture_output=True,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    return cert, key


def _serve(cert: Path, key: Path, url: str = "tcps://127.0.0.1:0") -> QiServer:
    server = QiServer(users={"nao": "pw"}, certfile=str(cert), keyfile=str(key))
    server.listen(url)
    server.register("Twice", _Twice(), methods=[("twice", "(i)", "i")])
    return server


def _login(url: str, trust: str | None) -> int:
    session = QiSession(connect_timeout_s=5.0, tls_trust=trust)
    session.set_login("nao", "pw")
    try:
        session.connect(url)
        return int(session.service("Twice").twice(21))
    finally:
        session.close()


@pytest.fixture
def certs(tmp_path: Path) -> Iterator[tuple[tuple[Path, Path], tuple[Path, Path]]]:
    yield _certificate(tmp_path, "robot"), _certificate(tmp_path, "impostor")


def test_trust_on_first_use_refuses_a_changed_certificate(
    certs: tuple[tuple[Path, Path], tuple[Path, Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    server = _serve(*certs[0])
    url = server.url()
    try:
        assert _login(url, None) == 42  # pinned now (XDG_CONFIG_HOME is the tests' own)
        assert "pinned the TLS certificate" in capsys.readouterr().err
        assert _login(url, None) == 42
    finally:
        server.close()
    impostor = _serve(*certs[1], url=url)  # the same address, another certificate
    try:
        with pytest.raises(ConnectionLost, match="certificate of .* changed"):
            _login(url, None)
        assert not any(c.authenticated for c in impostor._clients.values())
    finally:
        impostor.close()


def test_a_pin_a_pem_or_insecure(
    certs: tuple[tuple[Path, Path], tuple[Path, Path]], capsys: pytest.CaptureFixture[str]
) -> None:
    (cert, key), (other, _) = certs
    import ssl

    der = ssl.PEM_cert_to_DER_cert(cert.read_text())
    server = _serve(cert, key)
    try:
        url = server.url()
        assert _login(url, f"sha256:{fingerprint(der)}") == 42
        with pytest.raises(ConnectionLost, match="not the pinned"):
            _login(url, "sha256:" + "0" * 64)
        assert _login(url, str(cert)) == 42  # the robot's own certificate as the CA
        with pytest.raises(ConnectionLost, match="TLS handshake"):
            _login(url, str(other))
        assert _login(url, "insecure") == 42
        assert "NOT verified" in capsys.readouterr().err
        with pytest.raises(BackendError, match="sha256"):
            parse_trust("sha256:xyz")
    finally:
        server.close()


def test_a_password_never_goes_to_a_weaker_endpoint(
    certs: tuple[tuple[Path, Path], tuple[Path, Path]],
) -> None:
    plain = QiServer(users={"nao": "pw"})
    plain.listen("tcp://127.0.0.1:0")
    plain.register("Twice", _Twice(), methods=[("twice", "(i)", "i")])
    secure = _serve(*certs[0])
    weaker = plain.url()
    original = secure._info

    def lists_the_plain_one(served: object) -> tuple[object, ...]:
        info = original(served)  # type: ignore[arg-type]
        if info[0] == "Twice":  # the directory sends this service to plain TCP
            return (*info[:4], [weaker], *info[5:])
        return info

    secure._info = lists_the_plain_one  # type: ignore[method-assign]
    session = QiSession(connect_timeout_s=3.0, tls_trust="insecure")
    session.set_login("nao", "pw")
    try:
        session.connect(secure.url())
        with pytest.raises(ConnectionLost, match="cannot reach any endpoint"):
            session.service("Twice")
        time.sleep(0.2)
        assert not plain._clients, "a connection (with the password) went to plain TCP"
    finally:
        session.close()
        secure.close()
        plain.close()
    assert _may_send_password("tcp://127.0.0.1:9559")
    assert _may_send_password("tcps://10.0.0.2:9503")
    assert not _may_send_password("tcp://10.0.0.2:9559")


def test_plain_tcp_off_loopback_gets_no_password() -> None:
    session = QiSession(connect_timeout_s=1.0)
    session.set_login("nao", "pw")
    listener = socket.create_server(("0.0.0.0", 0))
    port = listener.getsockname()[1]
    host = _an_address_not_loopback()
    if host is None:
        listener.close()
        pytest.skip("no non-loopback address on this machine")
    try:
        with pytest.raises(ConnectionLost, match="in clear"):
            session.connect(f"tcp://{host}:{port}")
    finally:
        session.close()
        listener.close()


def _an_address_not_loopback() -> str | None:
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect(("10.255.255.255", 1))  # no packet is sent
        address = str(probe.getsockname()[0])
    except OSError:
        return None
    finally:
        probe.close()
    return None if address.startswith("127.") else address


def test_a_nested_bomb_in_the_login_answer_fails_fast() -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    port = listener.getsockname()[1]

    def hostile() -> None:
        conn, _ = listener.accept()
        with conn:
            head = conn.recv(message.HEADER_SIZE)
            header = message.unpack_header(head)
            conn.recv(header.size)
            body = nested_map(4096)
            conn.sendall(message.pack_header(header.id, len(body), 2, 0, 0, 0, 8) + body)
            time.sleep(2)

    thread = threading.Thread(target=hostile, daemon=True)
    thread.start()
    started = time.monotonic()
    session = QiSession(connect_timeout_s=5.0)
    try:
        with pytest.raises(ConnectionLost, match="more elements"):
            session.connect(f"tcp://127.0.0.1:{port}")
    finally:
        session.close()
        listener.close()
    assert time.monotonic() - started < 1.0
