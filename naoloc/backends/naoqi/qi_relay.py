"""A TCP relay in front of the libqi server: per-client identity, liveness and policy.

libqi-python does not tell a service which connection called it, and lets any client
(un)register services. The virtual NAOqi therefore listens through this relay: libqi
itself listens on a private loopback port, and each client connection is relayed to it
message by message (QiMessaging's 28-byte header: magic 0x42dead42 big-endian, then
little-endian id, payload size, version (u16), type (u8), flags (u8), service, object,
action). The relay

- names each connection (``qi-<n>``) and tells the core who is alive (every message)
  and who is gone (EOF), so the dead-man acts per client;
- records which connection called which (service, action), so the service learns
  its caller (:meth:`QiRelay.caller_of`);
- lets clients register services of their own (as on a NAO: libqi refuses a name
  already taken), at most :data:`MAX_REGISTRATIONS` per connection, and answers
  ``unregisterService`` of the served NAOqi's own services with an error instead of
  forwarding it;
- drops replies to a client that stopped reading once :data:`MAX_UNREAD_BYTES` wait
  for it, so a slow reader cannot make the server hold unbounded memory.
"""

from __future__ import annotations

import contextlib
import itertools
import selectors
import socket
import struct
import sys
import threading
from collections import deque
from collections.abc import Callable
from typing import Final

MAGIC: Final = 0x42DEAD42
HEADER: Final = struct.Struct("<IIIHBBIII")
HEADER_SIZE: Final = 28
MAX_PAYLOAD: Final = 50 << 20  # libqi's default limit
MAX_UNREAD_BYTES: Final = 32 << 20  # replies waiting for one client before new ones are dropped
TYPE_CALL, TYPE_REPLY, TYPE_ERROR, TYPE_POST = 1, 2, 3, 4
_REFUSED: Final = "clients of naoloc serve cannot unregister its own services"
MAX_REGISTRATIONS: Final = 16  # registerService calls per client connection
SERVICE_DIRECTORY: Final = 1
SD_REGISTER, SD_UNREGISTER = 102, 103  # ServiceDirectory action ids in libqi


def _error_payload(text: str) -> bytes:
    data = text.encode("utf-8")
    return struct.pack("<I", 1) + b"s" + struct.pack("<I", len(data)) + data


def _header(ident: int, size: int, kind: int, service: int, obj: int, action: int) -> bytes:
    raw = HEADER.pack(0, ident, size, 0, kind, 0, service, obj, action)
    return struct.pack(">I", MAGIC) + raw[4:]


class _Conn:
    def __init__(self, name: str, client: socket.socket, upstream: socket.socket) -> None:
        self.name = name
        self.client = client
        self.upstream = upstream
        self.from_client = bytearray()
        self.from_upstream = bytearray()
        self.to_client = bytearray()
        self.to_upstream = bytearray()
        self.closed = False
        self.registrations = 0


class QiRelay:
    """Relay ``listen`` to libqi at ``upstream`` (both ``(host, port)``).

    Args:
        listen: Address to accept clients on.
        upstream: The private libqi endpoint.
        on_alive: ``on_alive(conn_name)`` for every message from a client.
        on_gone: ``on_gone(conn_name)`` when a client's connection closes.
        log: One-line notices.
        protected: Service ids clients may not unregister (the served NAOqi's own).
    """

    def __init__(
        self,
        listen: tuple[str, int],
        upstream: tuple[str, int],
        on_alive: Callable[[str], None],
        on_gone: Callable[[str], None],
        log: Callable[[str], None],
        protected: frozenset[int] = frozenset(),
    ) -> None:
        self._upstream = upstream
        self._protected = protected | {SERVICE_DIRECTORY}
        self._on_alive = on_alive
        self._on_gone = on_gone
        self._log = log
        self._names = itertools.count(1)
        self._sel = selectors.DefaultSelector()
        self._server = socket.create_server(listen, reuse_port=False)
        self._server.setblocking(False)
        self.address = self._server.getsockname()[:2]
        self._sel.register(self._server, selectors.EVENT_READ, None)
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._lock = threading.Lock()
        self._callers: dict[tuple[int, int], deque[tuple[str, int]]] = {}
        self._conns: set[_Conn] = set()
        self._stop = threading.Event()
        self.dropped_replies = 0
        self.refused = 0
        self._thread = threading.Thread(target=self._run, name="naoloc-qi-relay", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ callers
    def caller_of(self, service: int, action: int) -> str:
        """The connection that sent the oldest unanswered call to ``(service, action)``."""
        with self._lock:
            queue = self._callers.get((service, action))
            return queue.popleft()[0] if queue else "qi-unknown"

    def _note_call(self, conn: _Conn, ident: int, service: int, action: int) -> None:
        if service <= SERVICE_DIRECTORY:
            return
        with self._lock:
            queue = self._callers.setdefault((service, action), deque(maxlen=1024))
            queue.append((conn.name, ident))

    def _note_answer(self, conn: _Conn, ident: int, service: int, action: int) -> None:
        """A call was answered: forget it if the service never asked who made it."""
        with self._lock:
            queue = self._callers.get((service, action))
            if queue:
                with contextlib.suppress(ValueError):
                    queue.remove((conn.name, ident))

    # ------------------------------------------------------------------ loop
    def _run(self) -> None:
        while not self._stop.is_set():
            for key, events in self._sel.select(timeout=0.5):
                if key.data is None:
                    self._accept()
                elif key.data == "wake":
                    with contextlib.suppress(OSError):
                        self._wake_r.recv(4096)
                else:
                    conn, side = key.data
                    try:
                        self._service(conn, side, events)
                    except OSError:
                        self._close(conn)
                    except Exception as err:  # a relay bug closes one connection, never the relay
                        self._log(
                            f"naoloc serve: relay error on {conn.name}: {type(err).__name__}: {err}"
                        )
                        self._close(conn)

    def _accept(self) -> None:
        try:
            client, _ = self._server.accept()
        except OSError:
            return
        try:
            upstream = socket.create_connection(self._upstream, timeout=2.0)
        except OSError:
            client.close()
            return
        for sock in (client, upstream):
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        conn = _Conn(f"qi-{next(self._names)}", client, upstream)
        self._conns.add(conn)
        self._sel.register(client, selectors.EVENT_READ, (conn, "client"))
        self._sel.register(upstream, selectors.EVENT_READ, (conn, "upstream"))
        self._on_alive(conn.name)

    def _want(self, conn: _Conn) -> None:
        if conn.closed:
            return
        for sock, out, side in (
            (conn.client, conn.to_client, "client"),
            (conn.upstream, conn.to_upstream, "upstream"),
        ):
            mask = selectors.EVENT_READ | (selectors.EVENT_WRITE if out else 0)
            self._sel.modify(sock, mask, (conn, side))

    def _service(self, conn: _Conn, side: str, events: int) -> None:
        sock = conn.client if side == "client" else conn.upstream
        if events & selectors.EVENT_WRITE:
            out = conn.to_client if side == "client" else conn.to_upstream
            if out:
                sent = sock.send(out)
                del out[:sent]
        if events & selectors.EVENT_READ:
            data = sock.recv(1 << 20)
            if not data:
                self._close(conn)
                return
            if side == "client":
                conn.from_client += data
                self._on_alive(conn.name)
                self._parse_client(conn)
            else:
                conn.from_upstream += data
                self._parse_upstream(conn)
        self._flush(conn)

    def _flush(self, conn: _Conn) -> None:
        for sock, out in ((conn.client, conn.to_client), (conn.upstream, conn.to_upstream)):
            if out and not conn.closed:
                try:
                    sent = sock.send(out)
                except BlockingIOError:
                    sent = 0
                del out[:sent]
        self._want(conn)

    @staticmethod
    def _messages(buffer: bytearray) -> list[tuple[tuple[int, ...], bytes]]:
        out = []
        while len(buffer) >= HEADER_SIZE:
            if struct.unpack(">I", buffer[:4])[0] != MAGIC:
                raise OSError("not a QiMessaging stream")
            fields = HEADER.unpack(bytes(buffer[:HEADER_SIZE]))
            size = fields[2]
            if size > MAX_PAYLOAD:
                raise OSError(f"message of {size} bytes")
            if len(buffer) < HEADER_SIZE + size:
                break
            out.append((fields, bytes(buffer[: HEADER_SIZE + size])))
            del buffer[: HEADER_SIZE + size]
        return out

    def _parse_client(self, conn: _Conn) -> None:
        for fields, raw in self._messages(conn.from_client):
            _, ident, _, _, kind, _, service, obj, action = fields
            refusal = ""
            if service == SERVICE_DIRECTORY and action in (SD_REGISTER, SD_UNREGISTER):
                refusal = self._refusal(conn, kind, action, raw)
            if refusal:
                self.refused += 1
                what = "registerService" if action == SD_REGISTER else "unregisterService"
                text = f"ServiceDirectory.{what}: refused: {refusal}"
                payload = _error_payload(text)
                conn.to_client += (
                    _header(ident, len(payload), TYPE_ERROR, service, obj, action) + payload
                )
                self._log(f"naoloc serve: refused {what} from {conn.name}")
                continue
            if kind in (TYPE_CALL, TYPE_POST):
                self._note_call(conn, ident, service, action)
            conn.to_upstream += raw

    def _refusal(self, conn: _Conn, kind: int, action: int, raw: bytes) -> str:
        """Why a client's (un)registration is refused ("" = forward it)."""
        if kind != TYPE_CALL:
            return "post (un)registration as a call"
        if action == SD_REGISTER:
            conn.registrations += 1
            if conn.registrations > MAX_REGISTRATIONS:
                return f"at most {MAX_REGISTRATIONS} services per client"
            return ""
        body = raw[HEADER_SIZE:]
        if len(body) != 4 or struct.unpack("<I", body)[0] in self._protected:
            return _REFUSED
        return ""

    def _parse_upstream(self, conn: _Conn) -> None:
        for fields, raw in self._messages(conn.from_upstream):
            kind = fields[4]
            if kind in (TYPE_REPLY, TYPE_ERROR):
                self._note_answer(conn, fields[1], fields[6], fields[8])
            if kind in (TYPE_REPLY, TYPE_ERROR) and len(conn.to_client) > MAX_UNREAD_BYTES:
                self.dropped_replies += 1
                if self.dropped_replies == 1 or self.dropped_replies % 100 == 0:
                    self._log(
                        f"naoloc serve: {conn.name} does not read its replies: dropped "
                        f"{self.dropped_replies} (over {MAX_UNREAD_BYTES >> 20} MB waiting)"
                    )
                continue
            conn.to_client += raw

    def _close(self, conn: _Conn) -> None:
        if conn.closed:
            return
        conn.closed = True
        self._conns.discard(conn)
        for sock in (conn.client, conn.upstream):
            with contextlib.suppress(Exception):
                self._sel.unregister(sock)
            with contextlib.suppress(OSError):
                sock.close()
        conn.to_client.clear()
        conn.from_upstream.clear()
        try:
            self._on_gone(conn.name)
        except Exception as err:  # never let a callback kill the relay
            print(f"naoloc serve: {type(err).__name__}: {err}", file=sys.stderr)

    def close(self) -> None:
        """Stop relaying and close every connection."""
        self._stop.set()
        with contextlib.suppress(OSError):
            self._wake_w.send(b"x")
        if self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        for conn in list(self._conns):
            self._close(conn)
        for sock in (self._server, self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                sock.close()
        with contextlib.suppress(Exception):
            self._sel.close()
