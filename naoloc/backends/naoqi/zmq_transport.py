"""ZmqSession: the qi.Session call shapes over pyzmq, in pure Python, on any OS.

Client side: a DEALER socket owned by one I/O thread; callers hand requests over
through a queue and a wake-up pipe, and wait on :class:`~.session.Future` objects.
The I/O thread also pings the server whenever it has sent nothing for
:data:`PING_EVERY_S`, and declares the connection lost when nothing arrived for
:data:`LOST_AFTER_S` or the socket monitor reports a disconnection. Then every pending
call fails with :class:`~naoloc.errors.ConnectionLost` and ``disconnected`` fires.

Server side: a ROUTER socket owned by one I/O thread that answers ``hello`` and
``ping`` itself and hands each ``call`` to a fixed pool of daemon workers, fair across
clients (:class:`~.qimessaging.workers.CallPool`: at most a quarter of the workers per
client; stops and heartbeats on a path of their own). The I/O thread takes at most
:data:`TURN_MESSAGES` requests before it sends the answers waiting, so a client that
floods the server delays another's ``pong`` by one turn, not by the whole flood. A
client silent for :data:`GONE_AFTER_S` (naoloc's clients ping every 0.2 s) counts as
gone: what it held is released. Wire format: :mod:`.wire` (msgpack + raw frames, no
pickle).

Neither I/O thread dies of a message: a malformed request is answered with an error
reply when its id can be read, and logged as one line (at most one line a second, with
a count of the ones left out); a malformed reply ends the client's connection with a
one-line :class:`~naoloc.errors.ConnectionLost` naming the server. Every error path
closes its sockets and destroys its context with linger 0, so nothing hangs on exit.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import sys
import threading
import time
from collections import deque
from pathlib import Path
from typing import Any, Final, Protocol, runtime_checkable

import zmq
import zmq.auth

from naoloc.backends.naoqi import wire
from naoloc.backends.naoqi.qimessaging.workers import CallPool
from naoloc.backends.naoqi.session import Future, Promise, Signal, error_from_text
from naoloc.backends.naoqi.urls import parse_url
from naoloc.errors import BackendError, ConnectionLost, NaolocError, ProtocolError, RobotError

PING_EVERY_S: Final = 0.2
LOST_AFTER_S: Final = 0.9
_POLL_MS: Final = 50
# How long close() waits for the I/O thread (it sees the stop within _POLL_MS).
CLOSE_WAIT_S: Final = 10.0
REPLY_HWM: Final = 16  # unread replies kept per client before new ones are dropped
MAX_PENDING_CALLS: Final = 64  # calls one client may have queued at once
WORKERS: Final = 16  # threads that run calls (a fixed pool: fuzzing cannot grow it)
TURN_MESSAGES: Final = 64  # requests read before the waiting answers are sent
GONE_AFTER_S: Final = 3.0  # a client silent this long has left (its holdings released)


_LOG_EVERY_S: Final = 1.0


class _OneLineLog:
    """One-line notices on stderr, at most one every :data:`_LOG_EVERY_S` (a flood is counted)."""

    def __init__(self, prefix: str) -> None:
        self._prefix = prefix
        self._last = -float("inf")
        self._skipped = 0

    def __call__(self, message: str) -> None:
        now = time.monotonic()
        if now - self._last < _LOG_EVERY_S:
            self._skipped += 1
            return
        more = f" (+{self._skipped} more like it since the last notice)" if self._skipped else ""
        self._last, self._skipped = now, 0
        line = " ".join(message.split())[:300]
        print(f"{self._prefix}{line}{more}", file=sys.stderr, flush=True)


@runtime_checkable
class Invokable(Protocol):
    """A served object that wants to know its caller (for the dead-man check)."""

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        """Run ``method(*args)`` for the client ``caller``."""
        ...


def make_curve_keys(folder: str | Path) -> Path:
    """Create CURVE certificates for a server and one client in ``folder``.

    Writes ``server.key`` / ``server.key_secret`` and ``client.key`` /
    ``client.key_secret`` (zmq.auth format). Point ``robot.curve_keys`` of both the
    server's and the client's config at this folder; copy only ``server.key`` and the
    client's pair to the client machine.
    """
    path = Path(folder)
    path.mkdir(parents=True, exist_ok=True)
    zmq.auth.create_certificates(str(path), "server")
    zmq.auth.create_certificates(str(path), "client")
    return path


def _load_key(folder: Path, name: str, secret: bool) -> tuple[bytes, bytes | None]:
    """Read one certificate of the CURVE folder ``folder`` (``robot.curve_keys``).

    Raises:
        BackendError: One line naming the folder and the missing or bad file.
    """
    if not folder.is_dir():
        raise BackendError(
            f"robot.curve_keys: {folder} is not a folder of CURVE certificates "
            "(create one with naoloc.backends.naoqi.zmq_transport.make_curve_keys)"
        )
    path = folder / name
    if not path.is_file():
        raise BackendError(f"robot.curve_keys: {folder} has no {name}")
    try:
        public, secret_key = zmq.auth.load_certificate(str(path))
    except (OSError, ValueError, UnicodeDecodeError) as err:
        reason = " ".join(str(err).split())[:120]
        raise BackendError(f"robot.curve_keys: {folder}: cannot read {name}: {reason}") from None
    if secret and secret_key is None:
        raise BackendError(f"robot.curve_keys: {folder}: {name} holds no secret key")
    return public, secret_key


def _destroy(ctx: zmq.Context[Any] | None) -> None:
    """Close every socket of ``ctx`` with linger 0 and terminate it (never blocks)."""
    if ctx is not None:
        with contextlib.suppress(zmq.ZMQError):
            ctx.destroy(linger=0)


class _Wake:
    """A pipe other threads write to so that the I/O thread's poll returns.

    ``poke`` and ``close`` hold a lock: a poke after close writes nothing, never into a
    descriptor the process has since reused for something else.
    """

    def __init__(self) -> None:
        self.read_fd, self.write_fd = os.pipe()
        os.set_blocking(self.read_fd, False)
        os.set_blocking(self.write_fd, False)
        self._lock = threading.Lock()
        self._closed = False

    def poke(self) -> None:
        with self._lock, contextlib.suppress(BlockingIOError, OSError):
            if not self._closed:
                os.write(self.write_fd, b"x")

    def drain(self) -> None:
        with contextlib.suppress(BlockingIOError, OSError):
            while os.read(self.read_fd, 4096):
                pass

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            for fd in (self.read_fd, self.write_fd):
                with contextlib.suppress(OSError):
                    os.close(fd)


class ZmqServiceProxy:
    """A remote service: ``proxy.method(*args)`` blocks, ``_async=True`` gives a Future."""

    def __init__(self, session: ZmqSession, name: str) -> None:
        self._session = session
        self._name = name

    def __getattr__(self, method: str) -> Any:
        if method.startswith("_"):
            raise AttributeError(method)

        def call(*args: Any, _async: bool = False) -> Any:
            future = self._session._call(self._name, method, list(args))
            return future if _async else future.value()

        call.__name__ = method
        return call


class ZmqSession:
    """The qi.Session shape over ZeroMQ (client or server, not both).

    Args:
        curve_keys: Folder of CURVE certificates (:func:`make_curve_keys`); None = plain.
        connect_timeout_s: How long ``connect`` waits for the server's greeting.
    """

    def __init__(self, curve_keys: str | None = None, connect_timeout_s: float = 3.0) -> None:
        self._curve = Path(curve_keys) if curve_keys else None
        self._connect_timeout_s = connect_timeout_s
        self._ctx: zmq.Context[Any] | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._wake: _Wake | None = None
        # Who releases the context and the wake pipe: close() once the I/O thread has
        # ended, or the I/O thread itself when close() could not wait for it (see close).
        self._release_lock = threading.Lock()
        self._io_done = False
        self._io_releases = False
        self._outbox: deque[list[Any]] = deque()
        self._url = ""
        self._connected = False
        self._lost_reason = ""
        self.disconnected = Signal()
        self.connected = Signal()
        # client side
        self._ids = itertools.count(1)
        self._pending: dict[int, Promise] = {}
        self._pending_lock = threading.Lock()
        self._services: list[str] = []
        # server side
        self._objects: dict[str, Any] = {}
        self._core: Any = None
        self._workers_lock = threading.Lock()
        self._pool: CallPool | None = None
        self._urgent: frozenset[tuple[str, str]] = frozenset()
        self._pending_calls: dict[bytes, int] = {}
        self._heard: dict[bytes, float] = {}  # peer -> when it last sent anything
        self._endpoint = ""
        self._auth: Any = None
        self.protocol_errors = 0
        self._log = _OneLineLog("naoloc serve: ")

    # ------------------------------------------------------------------ client
    def connect(self, url: str, _async: bool = False) -> Any:
        """Connect to a zmq virtual NAOqi at ``tcp://host:port`` and greet it.

        Raises:
            ConnectionLost: Nothing answered within ``connect_timeout_s``.
            BackendError: A bad URL or CURVE certificates.
        """
        if self._thread is not None:
            raise BackendError("this session is already in use")
        parse_url(url, what="transport zmq", schemes=("tcp",), allow_any_port=False)
        keys = None
        if self._curve is not None:  # read before any socket exists: an error leaks nothing
            public, secret = _load_key(self._curve, "client.key_secret", secret=True)
            server_public, _ = _load_key(self._curve, "server.key", secret=False)
            keys = (public, secret, server_public)
        self._url = url
        self._ctx = zmq.Context()
        try:
            sock = self._ctx.socket(zmq.DEALER)
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.RECONNECT_IVL, 100)
            sock.setsockopt(zmq.MAXMSGSIZE, wire.MAX_BUFFER_BYTES + 1)
            if keys is not None:
                sock.curve_publickey, sock.curve_secretkey, sock.curve_serverkey = keys
            monitor = sock.get_monitor_socket(zmq.EVENT_DISCONNECTED)
            monitor.setsockopt(zmq.LINGER, 0)
            sock.connect(url)
        except zmq.ZMQError as err:
            _destroy(self._ctx)
            self._ctx = None
            raise BackendError(f"cannot connect to {url}: {err}") from None
        self._wake = _Wake()
        self._thread = threading.Thread(
            target=self._client_loop, args=(sock, monitor), name="naoloc-zmq-client", daemon=True
        )
        self._thread.start()
        hello = self._send_request({"k": "hello"})
        try:
            welcome = hello.value(max(1, int(self._connect_timeout_s * 1000)))
        except ConnectionLost as err:
            self.close()
            raise ConnectionLost(f"no virtual NAOqi (zmq) answers at {url}: {err}") from None
        self._services = list(welcome["services"])  # checked by wire.decode_reply
        self._connected = True
        self.connected()
        done = Promise()
        done.setValue(None)
        return done.future() if _async else None

    def isConnected(self) -> bool:
        """True while the server answers."""
        return self._connected

    def url(self) -> str:
        """The URL this session connected to or listens on."""
        return self._url or self._endpoint

    def services(self, _async: bool = False) -> Any:
        """Names of the served services (libqi returns ServiceInfo structs instead)."""
        if self._endpoint:
            names: list[str] = sorted(self._objects)
            return names
        future = self._send_request({"k": "hello"})
        future_names = Future()

        def done(f: Future) -> None:
            err = f.exception()
            if err is not None:
                future_names._finish(None, err)
            else:
                future_names._finish(list(f.value()["services"]), None)

        future.addCallback(done)
        return future_names if _async else future_names.value()

    def service(self, name: str) -> ZmqServiceProxy:
        """A proxy of a served service.

        Raises:
            RobotError: The server has no such service.
        """
        if not self._connected:
            raise ConnectionLost(f"not connected to {self._url or 'a server'}")
        if name not in self._services:
            raise RobotError(f"no service {name!r} at {self._url}")
        return ZmqServiceProxy(self, name)

    def _call(self, service: str, method: str, args: list[Any]) -> Future:
        if not self._connected:
            future = Future()
            future._finish(None, ConnectionLost(self._lost_reason or "not connected"))
            return future
        return self._send_request({"k": "call", "s": service, "m": method, "a": args})

    def _send_request(self, header: dict[str, Any]) -> Future:
        promise = Promise()
        ident = next(self._ids)
        header["i"] = ident
        try:
            frames = wire.encode(header)
        except ProtocolError as err:
            promise.setError(err)
            return promise.future()
        with self._pending_lock:
            if self._lost_reason:
                promise.setError(ConnectionLost(self._lost_reason))
                return promise.future()
            self._pending[ident] = promise
        self._outbox.append(frames)
        wake = self._wake
        if wake is not None:
            wake.poke()
        return promise.future()

    def _fail_all(self, why: str) -> None:
        """Fail every pending call; ``why`` is short, e.g. "peer disconnected"."""
        with self._pending_lock:
            first = not self._lost_reason
            if first:
                self._lost_reason = f"connection to {self._url} lost ({why})"
            pending, self._pending = self._pending, {}
        was_connected, self._connected = self._connected, False
        for promise in pending.values():
            promise.setError(ConnectionLost(self._lost_reason))
        if first and was_connected:
            self.disconnected(why)

    def _client_loop(self, sock: zmq.Socket[Any], monitor: zmq.Socket[Any]) -> None:
        assert self._wake is not None
        poller = zmq.Poller()
        poller.register(sock, zmq.POLLIN)
        poller.register(monitor, zmq.POLLIN)
        poller.register(self._wake.read_fd, zmq.POLLIN)
        last_rx = last_tx = time.monotonic()
        try:
            while not self._stop.is_set():
                events = dict(poller.poll(_POLL_MS))
                now = time.monotonic()
                if self._wake.read_fd in events:
                    self._wake.drain()
                while self._outbox:
                    sock.send_multipart(self._outbox.popleft(), copy=False)
                    last_tx = now
                if sock in events:
                    while sock.poll(0) and not self._lost_reason:
                        self._on_reply(sock.recv_multipart(copy=False))
                        last_rx = time.monotonic()
                if monitor in events:
                    while monitor.poll(0):
                        monitor.recv_multipart()
                        if self._connected:
                            self._fail_all("peer disconnected")
                if self._connected and now - last_tx >= PING_EVERY_S:
                    sock.send_multipart(wire.encode({"k": "ping", "i": 0}))
                    last_tx = now
                if self._connected and now - last_rx > LOST_AFTER_S:
                    self._fail_all(f"silent for {now - last_rx:.1f} s")
                if self._lost_reason and not self._connected:
                    break
        except zmq.ZMQError as err:
            self._fail_all(f"socket error: {err}")
        finally:
            if not self._lost_reason:
                self._fail_all("session closed")
            with contextlib.suppress(zmq.ZMQError):
                sock.disable_monitor()
            monitor.close(0)
            sock.close(0)
            self._io_ended()

    def _on_reply(self, frames: list[Any]) -> None:
        """Hand one reply to its waiting call; a malformed one ends the connection."""
        try:
            reply = wire.decode_reply(frames)
        except ProtocolError as err:
            self.protocol_errors += 1
            self._fail_all(f"bad reply: {err}")
            return
        try:
            self._deliver(reply)
        except Exception as err:  # a callback's bug must not kill the I/O thread
            self._fail_all(f"bad reply: {type(err).__name__}: {err}")

    def _deliver(self, reply: dict[str, Any]) -> None:
        if reply["k"] == "pong":
            return
        with self._pending_lock:
            promise = self._pending.pop(reply["i"], None)
        if promise is None:
            return
        if reply["k"] == "err":
            promise.setError(error_from_text(f"{reply['e'][0]}: {reply['e'][1]}"))
        else:
            promise.setValue(reply.get("v"))

    # ------------------------------------------------------------------ server
    def listenStandalone(self, url: str) -> None:
        """Bind a ROUTER socket at ``url`` (port 0 = any free port) and start serving.

        Raises:
            BackendError: The address cannot be bound, or bad CURVE certificates.
        """
        if self._thread is not None:
            raise BackendError("this session is already in use")
        parse_url(url, what="transport zmq", schemes=("tcp",))
        keys = None
        if self._curve is not None:  # read before any socket exists: an error leaks nothing
            keys = _load_key(self._curve, "server.key_secret", secret=True)
        self._ctx = zmq.Context()
        try:
            sock = self._ctx.socket(zmq.ROUTER)
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.ROUTER_HANDOVER, 1)
            # Replies a client does not read wait in zmq's queue up to this many messages,
            # then are dropped (bounded memory per client; the call times out client-side).
            sock.setsockopt(zmq.SNDHWM, REPLY_HWM)
            # a peer sending a frame over the wire limit is disconnected before it is buffered
            sock.setsockopt(zmq.MAXMSGSIZE, wire.MAX_BUFFER_BYTES + 1)
            if keys is not None:
                from zmq.auth.thread import ThreadAuthenticator

                self._auth = ThreadAuthenticator(self._ctx)
                self._auth.start()
                self._auth.configure_curve(domain="*", location=str(self._curve))
                sock.curve_server = True
                sock.curve_publickey, sock.curve_secretkey = keys
            sock.bind(url)
            self._endpoint = sock.getsockopt_string(zmq.LAST_ENDPOINT)
        except zmq.ZMQError as err:
            self._stop_auth()
            _destroy(self._ctx)
            self._ctx = None
            raise BackendError(f"cannot listen on {url}: {err}") from None
        from naoloc.backends.naoqi.signatures import URGENT

        self._urgent = URGENT
        self._pool = CallPool(WORKERS, per_client=WORKERS // 4, name="naoloc-zmq-call")
        self._wake = _Wake()
        self._thread = threading.Thread(
            target=self._server_loop, args=(sock,), name="naoloc-zmq-server", daemon=True
        )
        self._thread.start()

    def endpoints(self) -> list[str]:
        """The bound endpoint (with the real port), as a one-item list."""
        return [self._endpoint] if self._endpoint else []

    def registerService(self, name: str, obj: Any) -> int:
        """Serve ``obj`` as ``name``; returns the service id (2, 3, ... like libqi)."""
        if name in self._objects:
            raise BackendError(f"service {name!r} is already registered")
        self._objects[name] = obj
        return len(self._objects) + 1

    def set_core(self, core: Any) -> None:
        """Tell ``core`` (``touch(caller, heartbeat=True)``, ``gone(caller)``) who is alive."""
        self._core = core

    def _reply(self, peer: bytes, header: dict[str, Any]) -> None:
        try:
            frames = wire.encode(header)
        except ProtocolError as err:
            frames = wire.encode({"k": "err", "i": header["i"], "e": ["ProtocolError", str(err)]})
        self._outbox.append([peer, *frames])
        wake = self._wake
        if wake is not None:
            wake.poke()

    def _run_call(self, peer: bytes, ident: int, obj: Any, method: str, args: Any) -> None:
        """Run one call on a worker and queue its answer."""
        try:
            if isinstance(obj, Invokable):
                value = obj.invoke(peer.hex(), method, args)
            else:
                target = getattr(obj, method, None)
                if method.startswith("_") or not callable(target):
                    raise RobotError(f"no method {method!r}")
                value = target(*args)
            self._reply(peer, {"k": "ok", "i": ident, "v": value})
        except NaolocError as err:
            self._reply(peer, {"k": "err", "i": ident, "e": [type(err).__name__, str(err)]})
        except Exception as err:  # a server bug must not kill the worker
            message = f"{type(err).__name__}: {err}".splitlines()[0]
            print(f"naoloc serve: {message}", file=sys.stderr, flush=True)
            self._reply(peer, {"k": "err", "i": ident, "e": ["RobotError", message]})
        finally:
            with self._workers_lock:
                self._pending_calls[peer] = self._pending_calls.get(peer, 1) - 1
                if self._pending_calls[peer] <= 0:
                    del self._pending_calls[peer]

    def _dispatch_call(self, peer: bytes, ident: int, service: str, method: str, args: Any) -> None:
        obj = self._objects.get(service)
        if obj is None:
            error = ["RobotError", f"unknown service {service!r}"]
            self._reply(peer, {"k": "err", "i": ident, "e": error})
            return
        with self._workers_lock:
            pending = self._pending_calls.get(peer, 0)
            if pending >= MAX_PENDING_CALLS:
                busy = f"{service}.{method}: too many calls queued ({MAX_PENDING_CALLS})"
                self._reply(peer, {"k": "err", "i": ident, "e": ["RobotError", busy]})
                self._log(f"client {peer.hex()}: {busy}")
                return
            self._pending_calls[peer] = pending + 1

        def job() -> None:
            self._run_call(peer, ident, obj, method, args)

        pool = self._pool
        urgent = (service, method) in self._urgent
        if pool is not None and (
            (urgent and pool.submit_urgent(peer, job)) or pool.submit(peer, job)
        ):
            return
        with self._workers_lock:  # closing
            self._pending_calls[peer] = self._pending_calls.get(peer, 1) - 1
            if self._pending_calls[peer] <= 0:
                del self._pending_calls[peer]

    def _reap(self) -> None:
        """Clients silent for :data:`GONE_AFTER_S` have left: release what they held."""
        now = time.monotonic()
        gone = [peer for peer, heard in self._heard.items() if now - heard > GONE_AFTER_S]
        for peer in gone:
            del self._heard[peer]
            if self._pool is not None:
                self._pool.drop(peer)
            core = self._core
            if core is not None:
                try:
                    core.gone(peer.hex())
                except Exception as err:  # the dead-man's own failure must not end the loop
                    self._log(f"releasing client {peer.hex()} failed: {err}")

    def _on_request(self, frames: list[Any]) -> None:
        """Answer or dispatch one request; a malformed one gets an error reply if it has an id."""
        peer = frames[0].bytes
        try:
            request = wire.decode_request(frames[1:])
        except ProtocolError as err:
            self.protocol_errors += 1
            self._log(f"bad request from client {peer.hex()}: {err}")
            ident = wire.peek_id(frames[1:])
            if ident is not None:
                self._reply(peer, {"k": "err", "i": ident, "e": ["ProtocolError", str(err)]})
            return
        kind, ident = request["k"], request["i"]
        core = self._core
        self._heard[peer] = time.monotonic()
        if kind == "bye":
            self._heard.pop(peer, None)
            if self._pool is not None:
                self._pool.drop(peer)
        if core is not None:
            if kind == "bye":
                core.gone(peer.hex())
                return
            core.touch(peer.hex(), heartbeat=True)
        if kind == "ping":
            self._reply(peer, {"k": "pong", "i": ident})
        elif kind == "hello":
            services = sorted(self._objects)
            self._reply(peer, {"k": "welcome", "i": ident, "v": {"services": services}})
        elif kind == "call":
            self._dispatch_call(peer, ident, request["s"], request["m"], request["a"])

    def _server_loop(self, sock: zmq.Socket[Any]) -> None:
        assert self._wake is not None
        poller = zmq.Poller()
        poller.register(sock, zmq.POLLIN)
        poller.register(self._wake.read_fd, zmq.POLLIN)
        reaped = time.monotonic()
        try:
            while not self._stop.is_set():
                events = dict(poller.poll(0 if sock.poll(0) else _POLL_MS))
                if self._wake.read_fd in events:
                    self._wake.drain()
                turn = 0
                while turn < TURN_MESSAGES and sock.poll(0):  # then answer: fair to others
                    self._serve_one(sock.recv_multipart(copy=False))
                    turn += 1
                if time.monotonic() - reaped > 0.5:
                    reaped = time.monotonic()
                    self._reap()
                while self._outbox:
                    frames = self._outbox.popleft()
                    try:
                        sock.send_multipart(frames, copy=False)
                    except zmq.ZMQError as err:
                        if err.errno == zmq.ETERM:
                            raise
                        self._log(f"cannot answer client {frames[0].hex()}: {err}")
        except zmq.ZMQError as err:
            if err.errno != zmq.ETERM and not self._stop.is_set():
                self._log(f"server socket failed, no longer serving: {err}")
        finally:
            sock.close(0)
            self._io_ended()

    def _serve_one(self, frames: list[Any]) -> None:
        """Handle one incoming message; nothing a client sends may end the I/O thread."""
        try:
            self._on_request(frames)
        except Exception as err:  # a bug in handling one message: log it, keep serving
            self.protocol_errors += 1
            self._log(f"failed to handle a request: {type(err).__name__}: {err}")

    def _stop_auth(self) -> None:
        if self._auth is not None:
            with contextlib.suppress(Exception):
                self._auth.stop()
            self._auth = None

    # ------------------------------------------------------------------ both
    def close(self) -> None:
        """Stop the I/O thread and workers, close the sockets. Safe to call twice.

        Only the I/O thread touches its sockets: libzmq aborts the whole process when a
        socket is used from two threads, and a closed wake pipe's descriptor may be reused
        by anything the process opens next. So the context and the pipe are released here
        only once the I/O thread has ended; if it does not end within ``CLOSE_WAIT_S`` (or
        ``close`` runs on it, from a callback), the I/O thread releases them as it ends.
        """
        self._stop.set()
        wake = self._wake
        if wake is not None:
            wake.poke()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=CLOSE_WAIT_S)
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.close(1.0)
        self._stop_auth()
        with self._release_lock:
            if thread is None or self._io_done:
                self._release()
            elif not self._io_releases:
                self._io_releases = True
                if thread is not threading.current_thread():
                    self._log(f"the I/O thread did not stop within {CLOSE_WAIT_S:.0f} s")
        self._connected = False

    def _io_ended(self) -> None:
        """The I/O thread's last step: its sockets are closed; release the rest if asked."""
        with self._release_lock:
            self._io_done = True
            if self._io_releases:
                self._release()

    def _release(self) -> None:
        """Close the wake pipe and terminate the context (no socket of it is open)."""
        if self._wake is not None:
            self._wake.close()
            self._wake = None
        _destroy(self._ctx)
        self._ctx = None
