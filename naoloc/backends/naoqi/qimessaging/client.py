"""QiSession: the qi.Session call shapes over naoloc's own QiMessaging, on any OS.

A session connects to a service directory (``tcp://host:9559``; NAOqi 2.9+:
``tcps://host:9503`` with a login), authenticates with the capability map, and
resolves services by name into :class:`~.proxy.RemoteObject` proxies. Services that
live behind another endpoint get their own authenticated :class:`Channel`. When a
connection ends, every pending call fails with :class:`~naoloc.errors.ConnectionLost`
and ``disconnected`` fires once; nothing reconnects by itself (like libqi; the naoloc
Link reconnects).
"""

from __future__ import annotations

import contextlib
import itertools
import queue
import sys
import threading
from typing import Any, Final

from naoloc.backends.naoqi.qimessaging import capability, codec, message
from naoloc.backends.naoqi.qimessaging.connection import (
    Connection,
    normalize_url,
    open_socket,
    parse_url,
)
from naoloc.backends.naoqi.qimessaging.message import Header
from naoloc.backends.naoqi.qimessaging.meta import (
    META_OBJECT,
    MetaObject,
    Method,
    service_info_dict,
)
from naoloc.backends.naoqi.qimessaging.proxy import RemoteObject, RemoteSignal
from naoloc.backends.naoqi.qimessaging.signature import Sig, parse
from naoloc.backends.naoqi.session import Future, Promise, Signal, error_from_text
from naoloc.errors import BackendError, ConnectionLost, NaolocError, ProtocolError, RobotError

_AUTH = Method(message.ACTION_AUTHENTICATE, "authenticate", parse("({sm})"), parse("{sm}"))
_META = Method(META_OBJECT, "metaObject", parse("(I)"), parse(codec.METAOBJECT_SIGNATURE))
_CANCELLED: Final = "the call was cancelled"


class Channel:
    """One authenticated connection of a session, with its pending calls and events."""

    def __init__(self, session: QiSession, url: str, timeout_s: float) -> None:
        self.session, self.url = session, url
        self.timeout_ms = max(1, int(timeout_s * 1000))
        self.features: dict[str, bool] = dict(capability.LOCAL)
        self._pending: dict[int, tuple[Promise, Sig]] = {}
        self._lock = threading.Lock()
        self._events: dict[tuple[int, int, int], dict[int, tuple[Any, RemoteSignal]]] = {}
        self._conn = Connection(
            open_socket(url, timeout_s), self._on_message, self._on_close, name="naoloc-qim"
        )
        self._conn.start()

    @property
    def closed(self) -> bool:
        """True once the connection ended."""
        return self._conn.closed

    @property
    def peer(self) -> tuple[str, int] | None:
        """The peer's (address, port), None when unknown."""
        try:
            address: Any = self._conn.sock.getpeername()
        except OSError:
            return None
        return (str(address[0]), int(address[1]))

    def authenticate(self, user: str | None, token: str | None) -> None:
        """Send the capability map (and login); raise unless the server says done.

        Raises:
            ConnectionLost: No answer or a refused login.
        """
        request = capability.client_request(user, token)
        future = self.call(message.SERVICE_SERVER, 0, _AUTH, (request,))
        try:
            reply = future.value(self.timeout_ms)
            self.features = capability.check_reply(reply)
        except NaolocError as err:
            self.close(str(err))
            raise ConnectionLost(f"cannot connect to NAOqi at {self.url}: {err}") from None

    def call(
        self, service: int, obj: int, method: Method, args: tuple[Any, ...], where: str = ""
    ) -> Future:
        """Send a call; the future gets the decoded reply (or the remote error)."""
        promise = Promise()
        future = promise.future()
        try:
            w = codec.encode(method.params, tuple(args), object_uid=self.features["ObjectPtrUID"])
        except ProtocolError as err:
            promise.setError(RobotError(f"{where or method.name}: {err}"))
            return future
        parts, size = w.finish()
        mid = self._conn.next_id()
        with self._lock:
            self._pending[mid] = (promise, method.returns)
        future._set_canceller(lambda: self._cancel(mid, service, obj, method.uid))
        try:
            self._conn.send(mid, message.CALL, service, obj, method.uid, parts, size)
        except NaolocError as err:
            with self._lock:
                self._pending.pop(mid, None)
            promise.setError(ConnectionLost(f"connection to {self.url} lost ({err})"))
        return future

    def post(self, service: int, obj: int, method: Method, args: tuple[Any, ...]) -> None:
        """Send a post: call without an answer (errors are not reported).

        Raises:
            RobotError: The arguments do not fit the method.
            ConnectionLost: The connection is down.
        """
        try:
            w = codec.encode(method.params, tuple(args), object_uid=self.features["ObjectPtrUID"])
        except ProtocolError as err:
            raise RobotError(f"{method.name}: {err}") from None
        parts, size = w.finish()
        mid = self._conn.next_id()
        self._conn.send(mid, message.POST, service, obj, method.uid, parts, size)

    def _cancel(self, mid: int, service: int, obj: int, action: int) -> None:
        if self._conn.closed or mid not in self._pending:
            return
        payload = codec.encode_bytes("I", mid)
        with contextlib.suppress(NaolocError):
            self._conn.send(self._conn.next_id(), message.CANCEL, service, obj, action, [payload])

    def subscribe(
        self, service: int, obj: int, signal: int, link: int, callback: Any, owner: RemoteSignal
    ) -> None:
        """Route events of ``(service, obj, signal)`` to ``callback``."""
        with self._lock:
            self._events.setdefault((service, obj, signal), {})[link] = (callback, owner)

    def unsubscribe(self, service: int, obj: int, signal: int, link: int) -> None:
        """Stop routing events to ``link``."""
        with self._lock:
            self._events.get((service, obj, signal), {}).pop(link, None)

    def _on_message(self, conn: Connection, header: Header, payload: memoryview) -> None:
        kind = header.type
        if kind in (message.REPLY, message.ERROR, message.CANCELLED):
            with self._lock:
                entry = self._pending.pop(header.id, None)
            if entry is None:
                return
            promise, returns = entry
            uid = self.features["ObjectPtrUID"]
            try:
                if kind == message.CANCELLED:
                    promise.setError(RobotError(_CANCELLED))
                elif kind == message.ERROR:
                    text = codec.decode("m", payload, object_uid=uid)
                    promise.setError(error_from_text(str(text)))
                else:
                    sig = parse("m") if header.flags & message.FLAG_DYNAMIC_PAYLOAD else returns
                    value = codec.decode(sig, payload, object_uid=uid)
                    promise.setValue(self._objects(value))
            except ProtocolError as err:
                promise.setError(ProtocolError(f"bad reply from {self.url}: {err}"))
        elif kind == message.EVENT:
            self._on_event(header, payload)
        elif kind == message.CAPABILITY:
            with contextlib.suppress(ProtocolError):
                peer = codec.decode("{sm}", payload)
                if isinstance(peer, dict):
                    self.features = capability.negotiated({**self.features, **peer})
        elif kind == message.CALL:
            text = codec.encode_bytes("m", "naoloc qimessaging clients serve no objects")
            with contextlib.suppress(NaolocError):
                conn.send(header.id, message.ERROR, header.service, header.object,
                          header.action, [text])  # fmt: skip

    def _objects(self, value: Any) -> Any:
        if isinstance(value, codec.ObjectRef):
            meta = MetaObject.from_wire(value.meta)
            return RemoteObject(self, value.service, value.object, meta, f"object {value.object}")
        return value

    def _on_event(self, header: Header, payload: memoryview) -> None:
        with self._lock:
            links = list(
                self._events.get((header.service, header.object, header.action), {}).values()
            )
        if not links:
            return
        dynamic = header.flags & message.FLAG_DYNAMIC_PAYLOAD
        sig = parse("m") if dynamic else links[0][1].signature
        try:
            value = codec.decode(sig, payload, object_uid=self.features["ObjectPtrUID"])
        except ProtocolError as err:
            print(f"naoloc: dropped a bad event from {self.url}: {err}", file=sys.stderr)
            return
        if sig.kind == "m":  # a dynamic signal: libqi sends its arguments as one tuple
            args = tuple(value) if isinstance(value, tuple) else (value,)
        elif isinstance(value, tuple | list) and sig.kind == "(":
            args = tuple(value)
        else:
            args = (value,)
        for callback, _ in links:
            self.session._dispatch(callback, args)

    def _on_close(self, conn: Connection, reason: str) -> None:
        with self._lock:
            pending, self._pending = self._pending, {}
        lost = ConnectionLost(f"connection to {self.url} lost ({reason})")
        for promise, _ in pending.values():
            promise.setError(lost)
        self.session._channel_closed(self, reason)

    def close(self, reason: str = "session closed") -> None:
        """End the connection."""
        self._conn.close(reason)
        self._conn.join()


class QiSession:
    """The qi.Session shape over naoloc's QiMessaging (client; or a server via listen).

    Args:
        connect_timeout_s: How long ``connect`` and look-ups wait for an answer.
    """

    def __init__(self, connect_timeout_s: float = 5.0) -> None:
        self._timeout_s = connect_timeout_s
        self._url = ""
        self._user: str | None = None
        self._token: str | None = None
        self._main: Channel | None = None
        self._channels: dict[str, Channel] = {}
        self._sd: RemoteObject | None = None
        self._proxies: dict[str, RemoteObject] = {}
        self._lock = threading.Lock()
        self._links = itertools.count(1)
        self._events: queue.Queue[Any] = queue.Queue()
        self._event_thread: threading.Thread | None = None
        self._server: Any = None
        self._registered: set[int] = set()  # ids given by a remote directory
        self._sd_process: tuple[str, int] | None = None  # the directory's (machine, pid)
        self._closed = False
        self.connected = Signal()
        self.disconnected = Signal()
        self.serviceRegistered = Signal()
        self.serviceUnregistered = Signal()

    # ------------------------------------------------------------------ login
    def setClientAuthenticatorFactory(self, factory: Any) -> None:
        """Log in with ``factory.newAuthenticator().initialAuthData()`` (user, token)."""
        data = factory.newAuthenticator().initialAuthData()
        self._user, self._token = str(data.get("user", "")), str(data.get("token", ""))

    def set_login(self, user: str, password: str) -> None:
        """Log in as ``user`` (NAOqi 2.9+ over tcps://)."""
        self._user, self._token = user, password

    # ------------------------------------------------------------------ client
    def connect(self, url: str, _async: bool = False) -> Any:
        """Connect and authenticate to the service directory at ``url``.

        Raises:
            ConnectionLost: Nothing answers, or the login is refused.
            BackendError: A bad URL, or the session is already in use.
        """
        if self._main is not None or self._server is not None:
            raise BackendError("this session is already in use")
        url = normalize_url(url)
        parse_url(url)
        self._url = url
        promise = Promise()
        try:
            channel = Channel(self, url, self._timeout_s)
            channel.authenticate(self._user, self._token)
            meta = MetaObject.from_wire(
                channel.call(message.SERVICE_DIRECTORY, 1, _META, (0,)).value(channel.timeout_ms)
            )
        except NaolocError as err:
            if _async:
                promise.setError(err)
                return promise.future()
            raise
        self._main = channel
        self._channels[url] = channel
        self._sd = RemoteObject(channel, message.SERVICE_DIRECTORY, 1, meta, "ServiceDirectory")
        self._watch_directory(self._sd)
        self.connected()
        promise.setValue(None)
        return promise.future() if _async else None

    def isConnected(self) -> bool:
        """True while the service directory connection is up."""
        return self._main is not None and not self._main.closed

    def url(self) -> str:
        """The URL connected to (or listened on)."""
        return self._url or (self._server.url() if self._server is not None else "")

    def _directory(self) -> RemoteObject:
        if self._sd is None or self._main is None or self._main.closed:
            reason = self._main._conn.reason if self._main is not None else ""
            raise ConnectionLost(f"not connected to {self._url or 'a NAOqi'} {reason}".strip())
        return self._sd

    def services(self, _async: bool = False) -> Any:
        """The ServiceInfo dicts of every service (like qi: name, serviceId, endpoints...)."""
        if self._server is not None and self._main is None:
            return self._server.services_info()
        raw = self._directory().services(_async=True)
        result = Future()

        def done(f: Future) -> None:
            err = f.exception()
            try:
                value = None if err else [service_info_dict(i) for i in f.value()]
            except NaolocError as bad:
                err = bad
            result._finish(value, err)

        raw.addCallback(done)
        return result if _async else result.value(max(1, int(self._timeout_s * 1000)))

    def service(self, name: str, _async: bool = False) -> Any:
        """A proxy of service ``name``.

        Raises:
            RobotError: No such service.
            ConnectionLost: The connection is down.
        """
        promise = Promise()
        try:
            proxy = self._proxies.get(name) or self._resolve(name)
        except NaolocError as err:
            if not _async:
                raise
            promise.setError(err)
            return promise.future()
        promise.setValue(proxy)
        return promise.future() if _async else proxy

    def _resolve(self, name: str) -> RemoteObject:
        timeout_ms = max(1, int(self._timeout_s * 1000))
        try:
            info = service_info_dict(self._directory().service(name, _async=True).value(timeout_ms))
        except RobotError as err:
            raise RobotError(f"no service {name!r} at {self._url} ({err})") from None
        channel = self._channel_for(info["endpoints"], self._with_directory(info))
        service_id = int(info["serviceId"])
        meta = MetaObject.from_wire(channel.call(service_id, 1, _META, (0,)).value(timeout_ms))
        proxy = RemoteObject(channel, service_id, 1, meta, name)
        self._proxies[name] = proxy
        return proxy

    def _with_directory(self, info: dict[str, Any]) -> bool:
        """True when the service lives in the service directory's own process."""
        if self._sd_process is None:
            timeout_ms = max(1, int(self._timeout_s * 1000))
            try:
                sd = service_info_dict(
                    self._directory().service("ServiceDirectory", _async=True).value(timeout_ms)
                )
                self._sd_process = (str(sd["machineId"]), int(sd["processId"]))
            except (NaolocError, KeyError, ValueError, TypeError):
                return True
        return (str(info.get("machineId")), int(info.get("processId", -1))) == self._sd_process

    def _channel_for(self, endpoints: list[str], local: bool = True) -> Channel:
        """The channel to reach a service listed at ``endpoints``.

        The service directory's own connection when the service lives in the
        directory's process (``local``) and an endpoint is relative (``qi:<name>``), or
        when an endpoint names the same peer (its URL, or its address and port, as a
        NAO lists ``tcp://<each interface>:9559``); otherwise a new authenticated
        connection, trying the peer's host first and loopback last. A service another
        client registered is reached at its own endpoints, never through the directory.
        """
        assert self._main is not None
        scheme, host, port = parse_url(self._url)
        peer = self._main.peer
        same = {(host, port), (peer[0], peer[1])} if peer else {(host, port)}
        usable = []
        for endpoint in endpoints:
            if endpoint.startswith("qi:"):
                if local:
                    return self._main
                continue
            if endpoint == self._url:
                return self._main
            try:
                e_scheme, e_host, e_port = parse_url(endpoint)
            except BackendError:
                continue
            if e_scheme == scheme and (e_host, e_port) in same:
                return self._main
            usable.append(endpoint)
        if not endpoints:
            return self._main
        usable.sort(key=lambda e: (urlhost(e) not in (host, peer[0] if peer else host),
                                   urlhost(e).startswith("127.")))  # fmt: skip
        for url in usable:
            with self._lock:
                channel = self._channels.get(url)
            if channel is not None and not channel.closed:
                return channel
            try:
                channel = Channel(self, url, min(self._timeout_s, 2.0))
                channel.authenticate(self._user, self._token)
            except NaolocError:
                continue
            with self._lock:
                self._channels[url] = channel
            return channel
        raise ConnectionLost(f"cannot reach any endpoint of the service: {endpoints}")

    def _watch_directory(self, directory: RemoteObject) -> None:
        """Relay serviceAdded/serviceRemoved as qi's serviceRegistered/Unregistered."""

        def removed(service_id: int, name: str) -> None:
            self._proxies.pop(name, None)  # a restarted service gets a fresh proxy
            self.serviceUnregistered(service_id, name)

        for signal, callback in (
            ("serviceAdded", self.serviceRegistered),
            ("serviceRemoved", removed),
        ):
            with contextlib.suppress(NaolocError, AttributeError):
                getattr(directory, signal).connect(callback)

    def waitForService(self, name: str, timeout_s: float = 5.0) -> None:
        """Return once ``name`` is registered (polls the service directory).

        Raises:
            RobotError: Not there within ``timeout_s``.
        """
        import time

        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if any(i["name"] == name for i in self.services()):
                return
            time.sleep(0.05)
        raise RobotError(f"service {name!r} did not appear within {timeout_s} s")

    def _new_link(self, signal: int) -> int:
        return (signal << 32) | (next(self._links) & 0xFFFFFFFF)

    def _dispatch(self, callback: Any, args: tuple[Any, ...]) -> None:
        if self._event_thread is None:
            self._event_thread = threading.Thread(
                target=self._run_events, name="naoloc-qim-events", daemon=True
            )
            self._event_thread.start()
        self._events.put((callback, args))

    def _run_events(self) -> None:
        while True:
            job = self._events.get()
            if job is None:
                return
            callback, args = job
            try:
                callback(*args)
            except Exception as err:  # a subscriber's bug must not stop event delivery
                print(f"naoloc: a signal callback failed: {err}", file=sys.stderr)

    def _channel_closed(self, channel: Channel, reason: str) -> None:
        if channel is self._main and not self._closed:
            self.disconnected(reason)

    # ------------------------------------------------------------------ server
    def listenStandalone(self, url: str) -> None:
        """Serve a service directory of our own at ``url`` (port 0 = a free port)."""
        from naoloc.backends.naoqi.qimessaging.server import QiServer

        if self._main is not None or self._server is not None:
            raise BackendError("this session is already in use")
        self._server = QiServer()
        self._server.listen(url)

    def listen(self, url: str) -> None:
        """A connected session: accept calls to the services it registers at ``url``.

        Without it, :meth:`registerService` listens on the address this machine uses
        to reach the service directory (loopback for a local NAOqi), on any free port.
        """
        from naoloc.backends.naoqi.qimessaging.server import QiServer

        if self._main is None:
            raise BackendError("listen needs a connected session (or use listenStandalone)")
        if self._server is not None:
            raise BackendError("this session already listens")
        server = QiServer()
        server.listen(url)
        self._server = server

    def local_address(self) -> str:
        """The address of this machine that reaches the service directory.

        Raises:
            ConnectionLost: Not connected.
        """
        if self._main is None or self._main.closed:
            raise ConnectionLost("not connected")
        sock: Any = self._main._conn.sock
        raw: Any = getattr(sock, "_sock", sock)  # a TLS socket wraps the TCP one
        return str(raw.getsockname()[0])

    def registerService(self, name: str, obj: Any, **kwargs: Any) -> int:
        """Serve ``obj`` as ``name``; returns its service id.

        A listening session (``listenStandalone``) lists it in its own directory. A
        connected session registers it with the remote service directory (a NAO's, or
        ``naoloc serve``'s) and serves its calls on its own endpoint, as libqi does;
        the service is listed until this session closes.

        Raises:
            BackendError: The session neither listens nor is connected.
            RobotError: The directory refused it (a name already taken...).
        """
        if self._main is not None:
            return self._register_remote(name, obj, **kwargs)
        if self._server is None:
            raise BackendError("registerService needs listenStandalone or connect first")
        service_id: int = self._server.register(name, obj, **kwargs)
        return service_id

    def _register_remote(self, name: str, obj: Any, **kwargs: Any) -> int:
        import hashlib
        import os

        assert self._main is not None
        if self._server is None:
            self.listen(f"tcp://{self.local_address()}:0")
        assert self._server is not None
        directory = self._directory()
        timeout_ms = max(1, int(self._timeout_s * 1000))
        machine = local_machine_id()
        uid = hashlib.sha1(f"{machine}/{os.getpid()}/{name}".encode()).digest()
        info = (name, 0, machine, os.getpid(), self._server.endpoints(), "", uid)
        service_id = int(directory.registerService(info, _async=True).value(timeout_ms))
        try:
            self._server.register(name, obj, service_id=service_id, **kwargs)
            directory.serviceReady(service_id, _async=True).value(timeout_ms)
        except NaolocError:
            with contextlib.suppress(NaolocError):
                directory.unregisterService(service_id, _async=True).value(timeout_ms)
            raise
        self._registered.add(service_id)
        return service_id

    def set_core(self, core: Any) -> None:
        """Listening sessions: tell ``core.gone(caller)`` when a client disconnects."""
        if self._server is None or self._main is not None:
            raise BackendError("set_core needs listenStandalone first (qimessaging)")
        self._server.set_core(core)

    def unregisterService(self, service_id: int) -> None:
        """Stop serving a service (one this session registered)."""
        if self._server is None:
            raise BackendError("unregisterService: this session serves nothing")
        if service_id in self._registered:
            self._registered.discard(service_id)
            timeout_ms = max(1, int(self._timeout_s * 1000))
            self._directory().unregisterService(service_id, _async=True).value(timeout_ms)
        self._server.unregister(service_id)

    def endpoints(self) -> list[str]:
        """Where a listening session accepts connections."""
        return self._server.endpoints() if self._server is not None else []

    # ------------------------------------------------------------------ both
    def close(self) -> None:
        """Close every connection (or stop serving). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        for channel in list(self._channels.values()):
            channel.close("session closed")
        self._channels.clear()
        if self._server is not None:
            self._server.close()
        if self._event_thread is not None:
            self._events.put(None)


def local_machine_id() -> str:
    """This machine's id as libqi knows it (``~/.config/qimessaging/machine_id``, which
    libqi writes), else a stable id from the host name (never written anywhere).

    libqi clients compare it with their own: on the same machine they may use loopback
    endpoints, on another they skip them.
    """
    import socket
    import uuid
    from pathlib import Path

    path = Path.home() / ".config" / "qimessaging" / "machine_id"
    try:
        text = path.read_text(encoding="utf-8").strip()
    except OSError:
        text = ""
    return text or str(uuid.uuid5(uuid.NAMESPACE_DNS, socket.gethostname()))


def urlhost(url: str) -> str:
    """The host part of a URL ("" when it has none)."""
    from urllib.parse import urlsplit

    return urlsplit(url).hostname or ""
