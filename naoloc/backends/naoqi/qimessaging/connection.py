"""One QiMessaging socket: framed sends from any thread, and a reader thread.

The reader validates each header before it trusts the size it claims (magic,
version, type, flags, payload limit), then reads the payload into a buffer of its
own, so decoded raw buffers can be zero-copy views of it. Payloads over 4 MiB are
read in growing steps, so a peer that announces a huge message and stalls costs
nothing. A malformed header closes the connection with a one-line reason (there is
no way to find the next message); the owner's ``on_close`` gets it once.

A server's connection (``queued=True``) never lets a slow reader hold up the thread
that sends: messages go to an outgoing queue that a writer thread of its own drains.
The queue has a byte budget: over it, droppable messages (events) are dropped and
counted, and anything else closes the connection ("slow reader").
"""

from __future__ import annotations

import contextlib
import itertools
import socket
import ssl
import struct
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Final
from urllib.parse import urlsplit

from naoloc.backends.naoqi.qimessaging import tls
from naoloc.backends.naoqi.qimessaging.message import (
    HEADER_SIZE,
    MAX_PAYLOAD,
    Header,
    pack_header,
    unpack_header,
)
from naoloc.backends.naoqi.qimessaging.trust import Trust, check, context, parse_trust
from naoloc.errors import BackendError, ConnectionLost, ProtocolError

_PREALLOCATE: Final = 4 * 1024 * 1024
_STEP: Final = 1024 * 1024
MAX_QUEUED: Final = 32 * 1024 * 1024  # bytes a queued connection holds for a slow reader

Buffer = bytes | bytearray | memoryview
OnMessage = Callable[["Connection", Header, memoryview], None]
OnClose = Callable[["Connection", str], None]


def normalize_url(url: str) -> str:
    """libqi's URL defaults: ``nao.local`` -> ``tcp://nao.local:9559``; tcps:// port 9503."""
    text = url.strip()
    if "://" not in text:
        text = "tcp://" + text
    scheme, _, rest = text.partition("://")
    host_part = rest.split("/", 1)[0]
    if host_part and ":" not in host_part.rsplit("]", 1)[-1]:
        text = f"{scheme}://{host_part}:{9503 if scheme == 'tcps' else 9559}"
    return text


def parse_url(url: str) -> tuple[str, str, int]:
    """``tcp://host:port`` or ``tcps://host:port`` -> (scheme, host, port).

    Raises:
        BackendError: Another scheme, or no host or port.
    """
    parts = urlsplit(url)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme not in ("tcp", "tcps") or not parts.hostname or port is None:
        raise BackendError(f"transport qimessaging needs tcp://HOST:PORT or tcps://, got {url!r}")
    return parts.scheme, parts.hostname, port


def keepalive(sock: socket.socket, idle_s: int = 5, interval_s: int = 2, probes: int = 3) -> None:
    """TCP keep-alive probes, so a peer that vanished (cable, power) is noticed in ~11 s.

    The naoloc Link's heartbeat notices much sooner; this covers bare sessions.
    """
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        for name, value in (
            ("TCP_KEEPIDLE", idle_s),
            ("TCP_KEEPINTVL", interval_s),
            ("TCP_KEEPCNT", probes),
        ):
            option = getattr(socket, name, None)
            if option is not None:
                sock.setsockopt(socket.IPPROTO_TCP, option, value)


def open_socket(
    url: str, timeout_s: float, trust: Trust | None = None
) -> socket.socket | tls.TlsSocket:
    """Connect to ``url``; for ``tcps://`` check the robot's certificate with ``trust``.

    NAOqi 2.9 robots present self-signed certificates, which libqi accepts without a
    look; naoloc pins them on first use by default (see :mod:`.trust`).

    Raises:
        ConnectionLost: Nothing accepts the connection within ``timeout_s``, the TLS
            handshake fails, or the certificate is not the trusted one.
        BackendError: A bad ``tls_trust`` setting.
    """
    scheme, host, port = parse_url(url)
    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except OSError as err:
        raise ConnectionLost(f"no NAOqi answers at {url} ({err.strerror or err})") from None
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    keepalive(sock)
    if scheme == "tcps":
        checked = trust if trust is not None else parse_trust(None)
        try:
            wrapped = tls.client(sock, context(checked), host)
            check(checked, f"{host}:{port}", wrapped.peer_certificate())
        except (OSError, ssl.SSLError) as err:
            sock.close()
            raise ConnectionLost(f"TLS handshake with {url} failed ({err})") from None
        except ConnectionLost:
            sock.close()
            raise
        sock.settimeout(None)
        return wrapped
    sock.settimeout(None)
    return sock


class Connection:
    """A framed, thread-safe QiMessaging connection.

    Args:
        sock: A connected socket, plain or :class:`tls.TlsSocket` (never an
            ``ssl.SSLSocket``: the reader and the senders would share its SSL state).
        on_message: Called on the reader thread for every valid message.
        on_close: Called once with the reason when the connection ends.
        max_payload: Largest payload accepted, bytes (``max_payload`` can be changed
            later, e.g. raised once the peer authenticated).
        name: For thread names and messages.
        queued: Sends go through an outgoing queue and a writer thread (servers), instead
            of being written by the sending thread (clients).
        max_queued: Byte budget of the outgoing queue (``queued`` only).
    """

    def __init__(
        self,
        sock: socket.socket | tls.TlsSocket,
        on_message: OnMessage,
        on_close: OnClose,
        *,
        max_payload: int = MAX_PAYLOAD,
        name: str = "qimessaging",
        queued: bool = False,
        max_queued: int = MAX_QUEUED,
    ) -> None:
        self.sock = sock
        self.name = name
        self.max_payload = max_payload
        self._on_message = on_message
        self._on_close = on_close
        self._send_lock = threading.Lock()
        self._state_lock = threading.Lock()
        self._ids = itertools.count(1)
        self._closed = threading.Event()
        self._reason = ""
        self._scatter = isinstance(sock, socket.socket)
        self._thread = threading.Thread(target=self._read_loop, name=name, daemon=True)
        self._queued = queued
        self._max_queued = max_queued
        self._out: deque[tuple[list[Buffer], int]] = deque()
        self._out_bytes = 0
        self._out_cond = threading.Condition()
        self._writer: threading.Thread | None = None
        if queued:
            self._writer = threading.Thread(
                target=self._write_loop, name=f"{name}-send", daemon=True
            )
        self.dropped = 0  # droppable messages not sent (slow reader)

    def start(self) -> None:
        """Start the reader thread (and the writer of a queued connection)."""
        if self._writer is not None:
            self._writer.start()
        self._thread.start()

    @property
    def closed(self) -> bool:
        """True once the connection ended."""
        return self._closed.is_set()

    @property
    def reason(self) -> str:
        """Why it ended ("" while open)."""
        return self._reason

    @property
    def queued_bytes(self) -> int:
        """Bytes waiting in the outgoing queue (0 for an unqueued connection)."""
        return self._out_bytes

    def next_id(self) -> int:
        """A fresh message id."""
        return next(self._ids) & 0xFFFFFFFF

    def send(
        self,
        mid: int,
        mtype: int,
        service: int,
        obj: int,
        action: int,
        parts: Sequence[Buffer] = (),
        size: int | None = None,
        flags: int = 0,
        *,
        droppable: bool = False,
    ) -> bool:
        """Send one message whose payload is ``parts`` (concatenated).

        Args:
            droppable: A queued connection over its budget drops this message (an
                event) instead of closing.

        Returns:
            False when a droppable message was dropped.

        Raises:
            ConnectionLost: The connection is closed, the send failed, or (queued) the
                peer reads too slowly for a message that cannot be dropped.
            ProtocolError: The payload is over the limit.
        """
        total = sum(len(p) for p in parts) if size is None else size
        header = pack_header(mid, total, mtype, flags, service, obj, action)
        if self._closed.is_set():
            raise ConnectionLost(self._reason or "connection closed")
        if self._queued:
            return self._enqueue([header, *parts], len(header) + total, droppable)
        try:
            with self._send_lock:
                self._write([header, *parts])
        except OSError as err:
            self.close(f"send failed: {err.strerror or err}")
            raise ConnectionLost(self._reason) from None
        return True

    def _enqueue(self, buffers: list[Buffer], size: int, droppable: bool) -> bool:
        with self._out_cond:
            over = self._out_bytes > 0 and self._out_bytes + size > self._max_queued
            if not over:
                self._out.append((buffers, size))
                self._out_bytes += size
                self._out_cond.notify()
                return True
            if droppable:
                self.dropped += 1
                return False
            unread = self._out_bytes
        self.close(f"slow reader: {unread} bytes unread (budget {self._max_queued})")
        raise ConnectionLost(self._reason)

    def _write(self, buffers: list[Buffer]) -> None:
        if self._scatter:
            self._sendmsg(buffers)
        elif len(buffers) <= 2:
            self.sock.sendall(bytes(buffers[0]) + bytes(buffers[1]) if len(buffers) == 2
                              else bytes(buffers[0]))  # fmt: skip
        else:
            self.sock.sendall(b"".join(buffers))

    def _write_loop(self) -> None:
        while True:
            with self._out_cond:
                while not self._out and not self._closed.is_set():
                    self._out_cond.wait()
                if not self._out:
                    return
                buffers, size = self._out.popleft()
            try:
                self._write(buffers)
            except OSError as err:
                self.close(f"send failed: {err.strerror or err}")
                return
            finally:
                with self._out_cond:
                    self._out_bytes -= size
                    self._out_cond.notify_all()
            if self._closed.is_set():
                return

    def flush(self, timeout_s: float) -> bool:
        """Wait until the outgoing queue is empty (at most ``timeout_s``); True when it is."""
        deadline = time.monotonic() + timeout_s
        with self._out_cond:
            while self._out_bytes and not self._closed.is_set():
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._out_cond.wait(left)
            return not self._out_bytes

    def _sendmsg(self, buffers: list[Buffer]) -> None:
        sock = self.sock
        assert isinstance(sock, socket.socket), "scatter writes only on a plain socket"
        views = [memoryview(b).cast("B") for b in buffers if len(b)]
        while views:
            sent = sock.sendmsg(views[:512])
            while views and sent >= len(views[0]):
                sent -= len(views[0])
                views.pop(0)
            if sent and views:
                views[0] = views[0][sent:]

    def _recv_exact(self, size: int) -> bytearray | None:
        if size <= _PREALLOCATE:
            buf = bytearray(size)
            view = memoryview(buf)
            got = 0
            while got < size:
                n = self.sock.recv_into(view[got:], size - got)
                if n == 0:
                    return None
                got += n
            return buf
        grown = bytearray()
        while len(grown) < size:
            chunk = self.sock.recv(min(_STEP, size - len(grown)))
            if not chunk:
                return None
            grown += chunk
        return grown

    def _read_loop(self) -> None:
        reason = "peer closed the connection"
        try:
            while not self._closed.is_set():
                head = self._recv_exact(HEADER_SIZE)
                if head is None:
                    break
                header = unpack_header(head, self.max_payload)
                payload = self._recv_exact(header.size) if header.size else bytearray()
                if payload is None:
                    reason = "peer closed the connection mid-message"
                    break
                self._on_message(self, header, memoryview(payload))
        except ProtocolError as err:
            reason = f"protocol error: {err}"
        except (OSError, ValueError) as err:
            reason = f"socket error: {getattr(err, 'strerror', None) or err}"
        except Exception as err:  # a handler bug ends this connection, in one line
            reason = f"internal error: {type(err).__name__}: {err}".splitlines()[0]
        self.close(reason)

    def close(self, reason: str = "closed") -> None:
        """End the connection (idempotent); ``on_close`` runs once."""
        with self._state_lock:
            if self._closed.is_set():
                return
            self._reason = reason
            self._closed.set()
        with self._out_cond:
            self._out_bytes -= sum(size for _, size in self._out)
            self._out.clear()
            self._out_cond.notify_all()
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            self.sock.close()
        self._on_close(self, reason)

    def join(self, timeout_s: float = 2.0) -> None:
        """Wait for the reader thread (not from itself)."""
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)


def send_timeout(sock: socket.socket, seconds: float) -> None:
    """Make blocking sends give up after ``seconds`` (a client that never reads)."""
    whole = int(seconds)
    value = struct.pack("ll", whole, int((seconds - whole) * 1e6))
    if sys.platform == "win32":
        value = struct.pack("L", int(seconds * 1000))
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, value)
