"""QiServer: a service directory and served objects over naoloc's QiMessaging.

Real libqi clients (the ``qi`` package, NAOqi tools) connect to it as to a NAO: they
authenticate (service 0), find services in the directory (service 1) and call
methods described by MetaObjects built from :mod:`naoloc.backends.naoqi.signatures`
(or a table given at registration). Every connection is its own caller
(``qim-<n>``), so the virtual NAOqi's dead-man tells clients apart. Clients may
register services of their own under new names (as on a NAO: an old-SDK ALBroker's
modules, NaolocLocalization from another process), at most
:data:`MAX_CLIENT_SERVICES`; they are listed until their connection closes, and the
server's own services cannot be replaced or unregistered. Every incoming message is
validated before it is trusted; a bad payload gets an error reply, a bad header closes
that connection.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import os
import socket
import ssl
import struct
import sys
import threading
import time
import uuid
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Final

from naoloc.backends.naoqi.qimessaging import capability, codec, message, tls
from naoloc.backends.naoqi.qimessaging.connection import Connection, parse_url
from naoloc.backends.naoqi.qimessaging.memory import MemoryHub
from naoloc.backends.naoqi.qimessaging.message import Header
from naoloc.backends.naoqi.qimessaging.meta import (
    GENERIC_METHODS,
    META_OBJECT,
    PROPERTIES,
    PROPERTY,
    REGISTER_EVENT,
    REGISTER_EVENT_WITH_SIGNATURE,
    SERVICE_INFO_SIGNATURE,
    SET_PROPERTY,
    TERMINATE,
    UNREGISTER_EVENT,
    MetaObject,
    Method,
    build,
    describe,
)
from naoloc.backends.naoqi.qimessaging.proxy import fit
from naoloc.backends.naoqi.qimessaging.signature import parse
from naoloc.errors import BackendError, NaolocError, ProtocolError, RobotError

MAX_CONNECTIONS: Final = 64
MAX_IN_FLIGHT: Final = 64  # calls per connection
MAX_INCOMING: Final = 1024 * 1024  # bytes: clients send arguments, not images
MAX_IN_FLIGHT_ALL: Final = 256  # calls of every client (bounds queued arguments' memory)
SEND_TIMEOUT_S: Final = 5.0  # a client that stops reading is dropped after this long
AUTH_TIMEOUT_S: Final = 10.0  # a connection that does not authenticate is dropped
SD_NAME: Final = "ServiceDirectory"
MEMORY: Final = "ALMemory"
MAX_CLIENT_SERVICES: Final = 32  # services registered by clients, all together
_REFUSED: Final = "naoloc serve's own services cannot be unregistered by clients"


@dataclass
class _Served:
    """A served object: a service (object 1) or an object a method returned."""

    name: str
    service_id: int
    target: Any
    meta: MetaObject
    object_id: int = message.MAIN_OBJECT
    hooks: list[tuple[Any, int]] = field(default_factory=list)  # (signal, link) to undo


@dataclass
class _Client:
    conn: Connection
    caller: str
    opened: float = field(default_factory=time.monotonic)
    authenticated: bool = False
    features: dict[str, bool] = field(default_factory=lambda: dict(capability.LOCAL))
    in_flight: int = 0
    links: dict[tuple[int, int, int], set[int]] = field(default_factory=dict)
    exported: set[tuple[int, int]] = field(default_factory=set)
    registered: set[int] = field(default_factory=set)  # service ids it registered here


def _send_timeout(sock: socket.socket, seconds: float) -> None:
    """Make blocking sends give up after ``seconds`` (a client that never reads)."""
    whole = int(seconds)
    value = struct.pack("ll", whole, int((seconds - whole) * 1e6))
    if sys.platform == "win32":
        value = struct.pack("L", int(seconds * 1000))
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, value)


def _directory_meta() -> MetaObject:
    info = SERVICE_INFO_SIGNATURE
    meta = build([])
    for uid, name, params, returns in (
        (100, "service", "(s)", info),
        (101, "services", "()", f"[{info}]"),
        (102, "registerService", f"({info})", "I"),
        (103, "unregisterService", "(I)", "v"),
        (104, "serviceReady", "(I)", "v"),
        (105, "updateServiceInfo", f"({info})", "v"),
        (108, "machineId", "()", "s"),
    ):
        meta.methods[uid] = Method(uid, name, parse(params), parse(returns))
    meta.signals[106] = ("serviceAdded", parse("(Is)"))
    meta.signals[107] = ("serviceRemoved", parse("(Is)"))
    return meta


def _table(name: str) -> list[tuple[str, str, str]]:
    from naoloc.backends.naoqi.signatures import SERVICES

    if name not in SERVICES:
        raise BackendError(f"no signatures for service {name!r}; pass methods=[...]")
    return [
        (method, "(" + "".join(o.params) + ")", o.returns)
        for method, overloads in SERVICES[name].items()
        for o in overloads
    ]


class QiServer:
    """Serve objects over QiMessaging.

    Args:
        users: NAOqi 2.9-style logins ``{user: password}``; None = no login asked.
        certfile: PEM certificate (and key) for ``tcps://``; None = plain TCP only.
        keyfile: PEM key when not inside ``certfile``.
        workers: Threads that run calls (blocking calls from one client must not
            hold up another client's ``stopMove``).
    """

    def __init__(
        self,
        *,
        users: dict[str, str] | None = None,
        certfile: str | None = None,
        keyfile: str | None = None,
        workers: int = 16,
    ) -> None:
        self._users = users
        self._tls: ssl.SSLContext | None = None
        if certfile:
            self._tls = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
            self._tls.load_cert_chain(certfile, keyfile)
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="naoloc-qim-call")
        self._lock = threading.Lock()
        self._services: dict[int, _Served] = {}
        self._clients: dict[Connection, _Client] = {}
        self._ids = itertools.count(2)
        self._callers = itertools.count(1)
        self._sock: socket.socket | None = None
        self._endpoint = ""
        self._closed = threading.Event()
        self._thread: threading.Thread | None = None
        seed = f"{socket.gethostname()}-{os.getpid()}"
        self.machine_id = str(uuid.uuid5(uuid.NAMESPACE_DNS, seed))
        self._services[1] = _Served(SD_NAME, 1, self, _directory_meta())
        self._objects: dict[tuple[int, int], _Served] = {}
        self._object_ids = itertools.count(2)
        self._core: Any = None
        self._in_flight = 0
        self._memory: MemoryHub | None = None
        self._external: dict[int, tuple[Any, ...]] = {}  # clients' services: id -> ServiceInfo
        self.protocol_errors = 0

    # ------------------------------------------------------------------ lifecycle
    def listen(self, url: str) -> None:
        """Bind ``tcp://host:port`` (or ``tcps://`` with a certificate); port 0 = any.

        Raises:
            BackendError: A bad or busy address, or tcps:// without a certificate.
        """
        scheme, host, port = parse_url(url)
        if scheme == "tcps" and self._tls is None:
            raise BackendError("serving tcps:// needs a certificate (certfile)")
        try:
            sock = socket.create_server((host, port), reuse_port=False)
        except OSError as err:
            raise BackendError(f"cannot listen on {url}: {err.strerror or err}") from None
        self._sock = sock
        self._endpoint = f"{scheme}://{host}:{sock.getsockname()[1]}"
        self._thread = threading.Thread(target=self._accept, name="naoloc-qim-accept", daemon=True)
        self._thread.start()

    def endpoints(self) -> list[str]:
        """The listening URL (with the real port)."""
        return [self._endpoint] if self._endpoint else []

    def url(self) -> str:
        """The listening URL."""
        return self._endpoint

    def _accept(self) -> None:
        assert self._sock is not None
        self._sock.settimeout(1.0)
        while not self._closed.is_set():
            self._drop_silent()
            try:
                sock, _ = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            sock.settimeout(None)
            with self._lock:
                full = len(self._clients) >= MAX_CONNECTIONS
            if full:
                sock.close()
                continue
            threading.Thread(target=self._open, args=(sock,), daemon=True).start()

    def _drop_silent(self) -> None:
        """Close connections that never authenticated within :data:`AUTH_TIMEOUT_S`."""
        now = time.monotonic()
        with self._lock:
            silent = [
                c.conn
                for c in self._clients.values()
                if not c.authenticated and now - c.opened > AUTH_TIMEOUT_S
            ]
        for conn in silent:
            conn.close("did not authenticate in time")

    def _open(self, sock: socket.socket) -> None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        _send_timeout(sock, SEND_TIMEOUT_S)
        stream: socket.socket | tls.TlsSocket = sock
        if self._tls is not None:
            try:
                sock.settimeout(5.0)
                stream = tls.server(sock, self._tls)
                sock.settimeout(None)
            except (OSError, ssl.SSLError):
                sock.close()
                return
        caller = f"qim-{next(self._callers)}"
        conn = Connection(
            stream, self._on_message, self._on_close, max_payload=MAX_INCOMING, name=caller
        )
        with self._lock:
            self._clients[conn] = _Client(conn, caller)
        conn.start()

    def close(self) -> None:
        """Stop accepting, close every connection, finish running calls."""
        if self._closed.is_set():
            return
        self._closed.set()
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
        with self._lock:
            clients = list(self._clients)
        for conn in clients:
            conn.close("server closed")
        self._pool.shutdown(wait=True, cancel_futures=True)
        if self._thread is not None:
            self._thread.join(2.0)

    # ------------------------------------------------------------------ services
    def register(
        self,
        name: str,
        target: Any,
        *,
        methods: Iterable[tuple[str, str, str]] | None = None,
        signals: dict[str, str] | None = None,
        service_id: int | None = None,
    ) -> int:
        """Serve ``target`` as ``name``; returns its service id (2, 3, ...).

        Args:
            name: Service name.
            target: An object with ``invoke(caller, method, args)``, or plain methods.
            methods: ``(name, params tuple signature, return signature)`` overloads;
                None = the row of :data:`~naoloc.backends.naoqi.signatures.SERVICES`.
            signals: ``{name: tuple signature}``: ``target.<name>`` is a
                :class:`~naoloc.backends.naoqi.session.Signal` whose emissions reach
                subscribed clients.
            service_id: The id another service directory gave it (a client session
                serving its own services); None = the next id of this server.

        Raises:
            BackendError: The name is taken or has no signatures.
        """
        with self._lock:
            taken = any(s.name == name for s in self._services.values()) or any(
                i[0] == name for i in self._external.values()
            )
            if taken or service_id in self._services:
                raise BackendError(f"service {name!r} is already registered")
        table = list(methods) if methods is not None else _table(name)
        meta = build(table, signals=(signals or {}).items(), description=name)
        service_id = next(self._ids) if service_id is None else service_id
        served = _Served(name, service_id, target, meta)
        self._hook_signals(served)
        with self._lock:
            self._services[service_id] = served
        if name == MEMORY and self._memory is None:
            self._feed_memory()
        self._emit(self._services[1], 106, (service_id, name))
        return service_id

    def _feed_memory(self) -> None:
        memory = getattr(self._core, "memory", None)
        add_listener = getattr(memory, "add_listener", None)
        if callable(add_listener):
            self._memory = MemoryHub()
            add_listener(self._memory.emit)

    def set_core(self, core: Any) -> None:
        """Tell ``core.gone(caller)`` when a client's connection closes (dead-man).

        A core with ``memory.add_listener`` also feeds ALMemory.subscriber objects.
        """
        self._core = core
        with self._lock:
            has_memory = any(s.name == MEMORY for s in self._services.values())
        if has_memory and self._memory is None:
            self._feed_memory()

    def _hook_signals(self, served: _Served) -> None:
        for uid, (signal_name, _) in served.meta.signals.items():
            source = getattr(served.target, signal_name, None)
            if source is not None and callable(getattr(source, "connect", None)):
                link = source.connect(self._emitter(served, uid))
                served.hooks.append((source, link))

    def _export(self, client: _Client, owner: _Served, target: Any) -> codec.ObjectRef:
        """Serve ``target`` (returned by a method) as a new object of ``owner``'s service."""
        if isinstance(target, codec.ObjectRef):
            return target
        methods, signals = describe(target)
        meta = build(methods, signals=signals.items(), description=type(target).__name__)
        object_id = next(self._object_ids)
        served = _Served(f"{owner.name} object", owner.service_id, target, meta, object_id)
        self._hook_signals(served)
        key = (owner.service_id, object_id)
        with self._lock:
            self._objects[key] = served
            client.exported.add(key)
        uid = hashlib.sha1(f"{self.machine_id}/{key}".encode()).digest()
        return codec.ObjectRef(meta.to_wire(), owner.service_id, object_id, uid)

    def _drop(self, key: tuple[int, int]) -> None:
        with self._lock:
            served = self._objects.pop(key, None)
        if served is not None:
            for source, link in served.hooks:
                with contextlib.suppress(Exception):
                    source.disconnect(link)

    def unregister(self, service_id: int) -> None:
        """Stop serving a service."""
        with self._lock:
            served = self._services.pop(service_id, None) if service_id != 1 else None
        if served is not None:
            for source, link in served.hooks:
                with contextlib.suppress(Exception):
                    source.disconnect(link)
            self._emit(self._services[1], 107, (service_id, served.name))

    def services_info(self) -> list[dict[str, Any]]:
        """ServiceInfo dicts of every service (the qi.Session.services() shape)."""
        from naoloc.backends.naoqi.qimessaging.meta import service_info_dict

        with self._lock:
            served = list(self._services.values())
        return [service_info_dict(self._info(s)) for s in served]

    def _info(self, served: _Served) -> tuple[Any, ...]:
        uid = hashlib.sha1(f"{self.machine_id}/{served.service_id}".encode()).digest()
        endpoints = [f"qi:{served.name}", *self.endpoints()]
        return (served.name, served.service_id, self.machine_id, os.getpid(), endpoints, "", uid)

    def _emitter(self, served: _Served, uid: int) -> Any:
        def emit(*args: Any) -> None:
            self._emit(served, uid, args)

        return emit

    def _emit(self, served: _Served, uid: int, args: tuple[Any, ...]) -> None:
        key = (served.service_id, served.object_id, uid)
        with self._lock:
            targets = [c for c in self._clients.values() if c.links.get(key)]
        if not targets:
            return
        sig = served.meta.signals[uid][1]
        if len(sig.items) == 1 and len(args) != 1:
            args = (list(args),)
        try:
            payload = codec.encode(sig, args).getvalue()
        except ProtocolError as err:
            print(f"naoloc serve: cannot send signal {uid}: {err}", file=sys.stderr)
            return
        for client in targets:
            with contextlib.suppress(NaolocError):
                mid = client.conn.next_id()
                client.conn.send(
                    mid, message.EVENT, served.service_id, served.object_id, uid, [payload]
                )

    # ------------------------------------------------------------------ messages
    def _on_close(self, conn: Connection, reason: str) -> None:
        with self._lock:
            client = self._clients.pop(conn, None)
        if client is None:
            return
        for key in list(client.exported):
            self._drop(key)
        for service_id in list(client.registered):  # as libqi: a client's services go with it
            self._unregister_external(service_id)
        gone = getattr(self._core, "gone", None)
        if callable(gone):
            try:
                gone(client.caller)
            except Exception as err:  # the dead-man's own failure must not kill the reader
                print(f"naoloc serve: dead-man on disconnect failed: {err}", file=sys.stderr)

    def _on_message(self, conn: Connection, header: Header, payload: memoryview) -> None:
        with self._lock:
            client = self._clients.get(conn)
        if client is None:
            return
        kind = header.type
        if kind == message.CAPABILITY:  # a peer may announce its features at any time
            with contextlib.suppress(ProtocolError):
                peer = codec.decode("{sm}", payload)
                if isinstance(peer, dict):
                    client.features = capability.negotiated(peer)
            return
        if kind not in (message.CALL, message.POST):
            return  # replies, events, cancels (our calls cannot be cancelled): nothing to do
        if header.service == message.SERVICE_SERVER:
            self._authenticate(client, header, payload)
            return
        if not client.authenticated:
            self._error(client, header, "authenticate first (service 0, action 8)")
            return
        with self._lock:
            if header.object == message.MAIN_OBJECT:
                served = self._services.get(header.service)
            else:
                served = self._objects.get((header.service, header.object))
        if served is None:
            self._error(client, header, f"no object {header.service}.{header.object}")
            return
        method = served.meta.methods.get(header.action)
        if method is None:
            self._error(client, header, f"{served.name} has no action {header.action}")
            return
        try:
            args = self._arguments(client, header, method, payload)
        except ProtocolError as err:
            self.protocol_errors += 1
            self._error(client, header, f"{served.name}.{method.name}: bad arguments: {err}")
            return
        if header.action < 100:
            try:
                self._generic(client, header, served, method, args)
            except (TypeError, ValueError, IndexError, KeyError) as err:
                self._error(client, header, f"{served.name}.{method.name}: bad arguments: {err}")
            return
        with self._lock:
            busy = client.in_flight >= MAX_IN_FLIGHT or self._in_flight >= MAX_IN_FLIGHT_ALL
            client.in_flight += 0 if busy else 1
            self._in_flight += 0 if busy else 1
        if busy:
            self._error(client, header, "too many calls in flight; wait for answers")
            return
        try:
            self._pool.submit(self._run, client, header, served, method, args)
        except RuntimeError:  # shutting down
            with self._lock:
                client.in_flight -= 1
                self._in_flight -= 1

    def _arguments(
        self, client: _Client, header: Header, method: Method, payload: memoryview
    ) -> list[Any]:
        uid = client.features["ObjectPtrUID"]
        if header.flags & message.FLAG_DYNAMIC_PAYLOAD:
            value = codec.decode("m", payload, object_uid=uid)
            if not isinstance(value, tuple | list):
                value = (value,)
            params = method.params.items
            if len(value) != len(params) or not all(
                fit(p, v) for p, v in zip(params, value, strict=True)
            ):
                raise ProtocolError(f"a dynamic payload that does not fit {method.params}")
        else:
            exact = not header.flags & message.FLAG_RETURN_TYPE
            value = codec.decode(method.params, payload, object_uid=uid, exact=exact)
        if len(value) != len(method.params.items):
            raise ProtocolError(f"expected {len(method.params.items)} arguments")
        return list(value)

    def _authenticate(self, client: _Client, header: Header, payload: memoryview) -> None:
        if header.object != 0 or header.action != message.ACTION_AUTHENTICATE:
            self._error(client, header, "service 0 only has authenticate (action 8)")
            return
        try:
            request = codec.decode("{sm}", payload)
        except ProtocolError as err:
            self.protocol_errors += 1
            self._error(client, header, f"bad capability map: {err}")
            return
        state, reason = capability.STATE_DONE, ""
        if self._users is not None:
            user, token = request.get("auth_user"), request.get("auth_token")
            if not isinstance(user, str) or self._users.get(user) != token:
                state, reason = capability.STATE_ERROR, "wrong user or password"
        client.features = capability.negotiated(request)
        client.authenticated = state == capability.STATE_DONE
        reply = capability.server_reply(request, state, reason)
        self._reply(client, header, parse("{sm}"), reply)

    def _generic(
        self, client: _Client, header: Header, served: _Served, method: Method, args: list[Any]
    ) -> None:
        action = header.action
        if action == META_OBJECT:
            self._reply(client, header, method.returns, served.meta.to_wire())
        elif action in (REGISTER_EVENT, REGISTER_EVENT_WITH_SIGNATURE):
            signal, link = int(args[1]), int(args[2])
            if signal not in served.meta.signals:
                self._error(client, header, f"{served.name} has no signal {signal}")
                return
            with self._lock:
                key = (served.service_id, served.object_id, signal)
                client.links.setdefault(key, set()).add(link)
            self._reply(client, header, method.returns, link)
        elif action == UNREGISTER_EVENT:
            with self._lock:
                key = (served.service_id, served.object_id, int(args[1]))
                client.links.get(key, set()).discard(int(args[2]))
            self._reply(client, header, method.returns, None)
        elif action == TERMINATE:
            exported = (served.service_id, int(args[0]) or served.object_id)
            if exported in client.exported:
                client.exported.discard(exported)
                self._drop(exported)
            self._reply(client, header, method.returns, None)
        elif action == PROPERTIES:
            self._reply(client, header, method.returns, [])
        elif action in (PROPERTY, SET_PROPERTY):
            self._error(client, header, f"{served.name} has no property {args[0]!r}")
        else:
            self._error(client, header, f"{GENERIC_METHODS[action][0]} is not supported")

    def _run(
        self, client: _Client, header: Header, served: _Served, method: Method, args: list[Any]
    ) -> None:
        try:
            if served.service_id == 1:
                value = self._directory(client, method.name, args)
            elif served.name == MEMORY and method.name == "subscriber" and self._memory:
                value = self._memory.new(args[0] if args else None)
            elif hasattr(served.target, "invoke"):
                value = served.target.invoke(client.caller, method.name, args)
            else:
                value = getattr(served.target, method.name)(*args)
            if method.returns.kind == "o":
                value = self._export(client, served, value)
            if header.type == message.CALL:
                self._reply(client, header, method.returns, value)
        except NaolocError as err:
            self._error(client, header, f"{type(err).__name__}: {err}")
        except Exception as err:  # a service bug must not kill the server
            text = f"{type(err).__name__}: {err}".splitlines()[0]
            self._error(client, header, f"RobotError: {served.name}.{method.name}: {text}")
        finally:
            with self._lock:
                client.in_flight -= 1
                self._in_flight -= 1

    def _directory(self, client: _Client, name: str, args: list[Any]) -> Any:
        with self._lock:
            served = list(self._services.values())
            external = dict(self._external)
        if name == "service":
            found = next((s for s in served if s.name == args[0]), None)
            if found is not None:
                return self._info(found)
            info = next((i for i in external.values() if i[0] == args[0]), None)
            if info is None:
                raise RobotError(f"Cannot find service '{args[0]}' in index")
            return info
        if name == "services":
            return [self._info(s) for s in served] + list(external.values())
        if name == "machineId":
            return self.machine_id
        if name == "registerService":
            return self._register_external(client, tuple(args[0]))
        if name == "serviceReady":
            return None
        if name == "unregisterService":
            service_id = int(args[0])
            if service_id in external:
                self._unregister_external(service_id)
                return None
            if service_id in (s.service_id for s in served):
                raise RobotError(_REFUSED)
            raise RobotError(f"no service #{service_id} to unregister")
        raise RobotError(f"ServiceDirectory.{name} is not offered by naoloc serve")

    def _register_external(self, client: _Client, info: tuple[Any, ...]) -> int:
        """A client's own service: listed here, called at the endpoints it gives."""
        name = info[0]
        if not isinstance(name, str) or not name:
            raise RobotError("registerService: a service needs a name")
        with self._lock:
            taken = any(s.name == name for s in self._services.values()) or any(
                i[0] == name for i in self._external.values()
            )
            if taken:
                raise RobotError(f'Service "{name}" is already registered')
            if len(self._external) >= MAX_CLIENT_SERVICES:
                raise RobotError(f"registerService: at most {MAX_CLIENT_SERVICES} client services")
            service_id = next(self._ids)
            self._external[service_id] = (name, service_id, *info[2:])
            client.registered.add(service_id)
        self._emit(self._services[1], 106, (service_id, name))
        return service_id

    def _unregister_external(self, service_id: int) -> None:
        with self._lock:
            info = self._external.pop(service_id, None)
            for c in self._clients.values():
                c.registered.discard(service_id)
        if info is not None:
            self._emit(self._services[1], 107, (service_id, info[0]))

    def _reply(self, client: _Client, header: Header, sig: Any, value: Any) -> None:
        try:
            w = codec.encode(sig, value, object_uid=client.features["ObjectPtrUID"])
        except ProtocolError as err:
            self._error(client, header, f"RobotError: the reply does not match {sig}: {err}")
            return
        parts, size = w.finish()
        with contextlib.suppress(NaolocError):
            client.conn.send(
                header.id, message.REPLY, header.service, header.object, header.action, parts, size
            )

    def _error(self, client: _Client, header: Header, text: str) -> None:
        if header.type != message.CALL:
            return
        payload = codec.encode_bytes("m", text.splitlines()[0] if text else "error")
        with contextlib.suppress(NaolocError):
            client.conn.send(
                header.id, message.ERROR, header.service, header.object, header.action, [payload]
            )
