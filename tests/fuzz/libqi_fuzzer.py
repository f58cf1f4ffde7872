"""A bounded, seeded random fuzzer for the libqi virtual NAOqi (``naoloc serve --transport libqi``).

Raw TCP sockets send QiMessaging frames (28-byte header: magic ``0x42dead42`` big-endian,
then little-endian id, size, version, type, flags, service, object, action) that are
garbage, truncated, oversized or well-framed with random addresses and payloads. Most
connections first pass libqi's authentication (an empty capability map), so the fuzz
reaches the service dispatch, not only the handshake. The service directory's
``registerService``/``unregisterService`` (actions 102, 103) are left out: refusing them
is access control, tested with the server's own tests.
"""

from __future__ import annotations

import contextlib
import random
import socket
import struct
from dataclasses import dataclass
from urllib.parse import urlsplit

MAGIC = bytes.fromhex("42dead42")
_REST = struct.Struct("<IIHBBIII")
CALL, SERVICE_SERVER, SERVICE_DIRECTORY, ACTION_AUTHENTICATE = 1, 0, 1, 8
_SD_WRITES = (102, 103)  # registerService, unregisterService


def header(
    mid: int, size: int, mtype: int, flags: int, service: int, obj: int, action: int
) -> bytes:
    """A QiMessaging header (version 0)."""
    return MAGIC + _REST.pack(mid, size, 0, mtype, flags, service, obj, action)


def _raw(rng: random.Random) -> bytes:
    """A message libqi answers by closing the connection (sent before authenticating)."""
    pick = rng.randrange(4)
    mid = rng.randrange(1 << 32)
    if pick == 0:  # garbage
        return rng.randbytes(rng.randrange(1, 64))
    if pick == 1:  # bad magic, plausible rest
        return rng.randbytes(4) + _REST.pack(mid, 0, 0, CALL, 0, 1, 1, 101)
    if pick == 2:  # truncated header
        return header(mid, 0, CALL, 0, 1, 1, 101)[: rng.randrange(1, 28)]
    # declared payload larger than sent (up to 4 GB), then the connection ends
    return header(mid, rng.randrange(8, 1 << 32), CALL, 0, 1, 1, 100) + rng.randbytes(4)


def _in_session(rng: random.Random) -> bytes:
    """A well-framed message with random fields, for an authenticated connection."""
    pick = rng.randrange(6)
    mid = rng.randrange(1 << 32)
    if pick == 0:  # bad version / type / flags
        raw = bytearray(header(mid, 0, rng.randrange(256), rng.randrange(256), 1, 1, 101))
        raw[12:14] = rng.randbytes(2)
        return bytes(raw)
    if pick == 1:  # a valid call to the service directory (services())
        return header(mid, 0, CALL, 0, SERVICE_DIRECTORY, 1, 101)
    service = rng.randrange(0, 10)
    action = rng.choice([rng.randrange(0, 10), rng.randrange(80, 140), rng.randrange(1 << 32)])
    if service == SERVICE_DIRECTORY and action in _SD_WRITES:
        action = 101
    payload = rng.choice([b"", rng.randbytes(rng.randrange(1, 48)), b"\xff\xff\xff\xff" * 2])
    mtype = rng.choice([CALL, CALL, CALL, 2, 3, 4, 5, 6, 7, 8, 0, 200])
    obj = rng.choice([0, 1, 1, 2, rng.randrange(1 << 32)])
    return header(mid, len(payload), mtype, rng.randrange(4), service, obj, action) + payload


@dataclass
class FuzzReport:
    """What one fuzz run did.

    Attributes:
        sent: Messages sent.
        bytes_sent: Bytes sent.
        connections: TCP connections opened.
        closed_by_server: Connections the server closed (or reset).
        bytes_received: Bytes the server answered with.
        connect_retries: Connections that needed a second try (a loaded machine: libqi's
            accept loop fell behind the listen backlog).
        sessions: Authenticated connections opened (each one the server closes on a fuzzed
            message is replaced by a new one).
    """

    sent: int = 0
    bytes_sent: int = 0
    sessions: int = 0
    connections: int = 0
    closed_by_server: int = 0
    bytes_received: int = 0
    connect_retries: int = 0


def _address(url: str) -> tuple[str, int]:
    parts = urlsplit(url)
    assert parts.hostname is not None and parts.port is not None, url
    return parts.hostname, parts.port


def _authenticate(sock: socket.socket) -> None:
    """libqi's handshake with an empty capability map (the server then accepts calls)."""
    sock.sendall(
        header(1, 4, CALL, 0, SERVICE_SERVER, 0, ACTION_AUTHENTICATE) + b"\x00\x00\x00\x00"
    )


def _drain(sock: socket.socket, report: FuzzReport) -> bool:
    """Read what is waiting; False when the server closed the connection."""
    while True:
        try:
            data = sock.recv(1 << 16)
        except BlockingIOError:
            return True
        except OSError:
            return False
        if not data:
            return False
        report.bytes_received += len(data)


CONNECT_TIMEOUTS_S = (2.0, 4.0, 8.0, 8.0)  # a server that accepts within ~22 s is alive


def _open(address: tuple[str, int], report: FuzzReport) -> socket.socket:
    """Connect, retrying on a timeout: on a loaded 2-core machine libqi can take over 2 s to
    accept (seen once in CI during 10,000 fuzz messages); a wedged server still fails."""
    for attempt, timeout in enumerate(CONNECT_TIMEOUTS_S):
        try:
            sock = socket.create_connection(address, timeout=timeout)
        except TimeoutError:
            if attempt == len(CONNECT_TIMEOUTS_S) - 1:
                raise
            report.connect_retries += 1
            continue
        report.connections += 1
        return sock
    raise AssertionError("unreachable")


def _send(sock: socket.socket, data: bytes, report: FuzzReport) -> bool:
    """Send and read what is waiting; False once the server closed the connection."""
    try:
        sock.settimeout(2.0)
        sock.sendall(data)
        sock.setblocking(False)
    except OSError:
        return False
    report.sent += 1
    report.bytes_sent += len(data)
    return _drain(sock, report)


def fuzz_libqi(
    url: str, messages: int, seed: int, raw_share: float = 0.05, per_session: int = 1000
) -> FuzzReport:
    """Send ``messages`` fuzz messages to the libqi server at ``url`` over raw sockets.

    A share ``raw_share`` of them each open a connection, send one frame libqi must refuse
    (garbage, bad magic, truncated, oversized) and close; the others go, well framed with
    random fields, over authenticated connections of ``per_session`` messages each. (Few
    authenticated connections on purpose: libqi 3.1.5 keeps the socket of every client
    that authenticates and then disconnects; see :func:`churn_authenticated`.)
    """
    rng = random.Random(seed)
    report = FuzzReport()
    address = _address(url)
    session: socket.socket | None = None
    in_session = 0
    try:
        while report.sent < messages:
            if rng.random() < raw_share:
                with contextlib.closing(_open(address, report)) as sock:
                    if not _send(sock, _raw(rng), report):
                        report.closed_by_server += 1
                continue
            if session is None:
                session = _open(address, report)
                _authenticate(session)
                report.sessions += 1
                in_session = 0
            alive = _send(session, _in_session(rng), report)
            in_session += 1
            if not alive or in_session >= per_session:
                report.closed_by_server += not alive
                with contextlib.suppress(OSError):
                    session.shutdown(socket.SHUT_RDWR)
                session.close()
                session = None
    finally:
        if session is not None:
            session.close()
    return report


def churn_authenticated(url: str, clients: int) -> None:
    """Open ``clients`` connections that authenticate and then close at once."""
    address = _address(url)
    for _ in range(clients):
        with contextlib.closing(socket.create_connection(address, timeout=2.0)) as sock:
            _authenticate(sock)
            sock.shutdown(socket.SHUT_RDWR)
