"""The libqi transport: the real ``qi`` package (NAOqi's own wire protocol).

Only this module imports ``qi``, and only when the libqi transport is chosen. It
makes client sessions (with the NAOqi 2.9+ login when a user is given) and turns a
served object into a qi-bound object whose methods carry the typed signatures of
:mod:`.signatures`, so that any NAOqi client sees typed methods and receives image
buffers as binary.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Any, Final
from urllib.parse import urlsplit

from naoloc.backends.naoqi.session import QI_INSTALL_HINT
from naoloc.backends.naoqi.signatures import SERVICES
from naoloc.errors import BackendError, DependencyNotInstalled, NaolocError, RobotError

LIBQI_CALLER = "libqi"
MAX_SUBSCRIBERS_PER_KEY: Final = 256


def import_qi() -> Any:
    """Import and return the ``qi`` module.

    Raises:
        DependencyNotInstalled: qi is not installed (names the pip command).
    """
    try:
        import qi
    except ImportError:
        raise DependencyNotInstalled(QI_INSTALL_HINT) from None
    # libqi logs "No Application was created" and every service registration; naoloc
    # reports problems itself, so keep libqi's own log to errors.
    qi.logging.setLevel(qi.logging.ERROR)
    return qi


def new_session() -> Any:
    """A new, unconnected ``qi.Session``."""
    return import_qi().Session()


class _Authenticator:
    """NAOqi 2.9+ client login: the data sent on connection."""

    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def initialAuthData(self) -> dict[str, str]:
        return {"user": self._user, "token": self._password}


class _AuthenticatorFactory:
    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def newAuthenticator(self) -> _Authenticator:
        return _Authenticator(self._user, self._password)


def set_login(session: Any, user: str, password: str) -> None:
    """Make ``session`` log in as ``user`` (NAOqi 2.9+ over tcps://)."""
    session.setClientAuthenticatorFactory(_AuthenticatorFactory(user, password))


def bind_service(name: str, target: Any, caller: Callable[[str, int], str] | None = None) -> Any:
    """A qi-bound object serving ``SERVICES[name]`` by forwarding to ``target.invoke``.

    Args:
        name: Service name, a key of :data:`~.signatures.SERVICES`.
        target: An object with ``invoke(caller, method, args)``; its naoloc errors reach
            the client as one line ``"<ErrorType>: <message>"`` (no traceback).
        caller: ``caller(method, overload)`` names the client of a call (None = "libqi").

    Returns:
        A multi-threaded instance ready for ``qi.Session.registerService`` (calls to one
        service run in parallel, so a second client's stopMove ends a blocking moveTo).
    """
    qi = import_qi()
    namespace: dict[str, Any] = {"__doc__": f"naoloc virtual {name}"}
    for method, overloads in SERVICES[name].items():
        for k, overload in enumerate(overloads):
            namespace[f"{method}__{k}"] = qi.bind(
                overload.returns, list(overload.params), methodName=method
            )(_forwarder(target, method, k, overload.returns, caller))
    cls = qi.multiThreaded()(type(f"Qi{name}", (), namespace))
    return cls()


def _forwarder(
    target: Any, method: str, overload: int, returns: str, caller: Callable[[str, int], str] | None
) -> Any:
    as_tuple = returns.startswith("(")
    qi = import_qi()

    def call(self: Any, *args: Any) -> Any:
        who = caller(method, overload) if caller is not None else LIBQI_CALLER
        try:
            value = target.invoke(who, method, list(args))
        except NaolocError as err:
            promise = qi.Promise()
            promise.setError(
                f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}"
            )
            return promise.future()
        if as_tuple:
            return tuple(value)
        return value

    call.__name__ = method
    return call


class _MemorySubscribers:
    """ALMemory.subscriber(key) objects: each has a ``signal`` fired on every change of key."""

    def __init__(self) -> None:
        qi = import_qi()
        namespace: dict[str, Any] = {"__doc__": "naoloc ALMemory subscriber"}
        self._cls = type("QiMemorySubscriber", (), namespace)
        self._qi = qi
        self._lock = threading.Lock()
        self._by_key: dict[str, list[Any]] = {}

    def new(self, key: str) -> Any:
        subscriber = self._cls()
        subscriber.signal = self._qi.Signal("m")
        with self._lock:
            subs = self._by_key.setdefault(key, [])
            if len(subs) >= MAX_SUBSCRIBERS_PER_KEY:
                subs.pop(0)
            subs.append(subscriber)
        return subscriber

    def emit(self, key: str, value: Any) -> None:
        with self._lock:
            subs = list(self._by_key.get(key, ()))
        for subscriber in subs:
            with contextlib.suppress(Exception):  # a client gone mid-event
                subscriber.signal(value)


class LibqiServer:
    """The served NAOqi over libqi, behind a :class:`~.qi_relay.QiRelay`.

    libqi listens on a private loopback port; clients connect to ``url`` through the
    relay, which names each connection (per-client dead-man), lets clients register
    services of their own but not unregister the served ones, and bounds the replies a
    slow reader can pile up.

    Args:
        core: The served robot (``invoke``, ``touch``, ``gone``, ``memory``).
        url: ``tcp://host:port`` to accept clients on (port 0 = any free port).
        names: Services to register.
        log: One-line notices.

    Raises:
        BackendError: The address cannot be bound.
    """

    def __init__(self, core: Any, url: str, names: list[str], log: Callable[[str], None]) -> None:
        from naoloc.backends.naoqi.qi_relay import QiRelay
        from naoloc.backends.naoqi.server import ServiceEndpoint
        from naoloc.backends.naoqi.signatures import MEMORY

        qi = import_qi()
        parts = urlsplit(url)
        if parts.scheme != "tcp" or not parts.hostname or parts.port is None:
            raise BackendError(f"libqi serving needs tcp://HOST:PORT, got {url!r}")
        self._session = qi.Session()
        self._session.listenStandalone("tcp://127.0.0.1:0")
        self._relay: Any = None
        try:
            inner = next(str(e) for e in self._session.endpoints() if str(e).startswith("tcp://"))
            inner_parts = urlsplit(inner)
            self._ids: dict[tuple[str, str, int], tuple[int, int]] = {}
            self._service_ids: dict[str, int] = {}
            self._subscribers = _MemorySubscribers()
            for name in names:
                endpoint: Any = ServiceEndpoint(core, name)
                if name == MEMORY:
                    endpoint = _MemoryEndpoint(endpoint, self._subscribers)
                    core.memory.add_listener(self._subscribers.emit)
                bound = bind_service(name, endpoint, self._caller_for(name))
                self._service_ids[name] = int(self._session.registerService(name, bound))
            self._learn_action_ids(inner, names)
            try:
                self._relay = QiRelay(
                    (parts.hostname, parts.port),
                    (str(inner_parts.hostname), int(inner_parts.port or 0)),
                    on_alive=core.touch,
                    on_gone=core.gone,
                    log=log,
                    protected=frozenset(self._service_ids.values()),
                )
            except OSError as err:
                raise BackendError(f"cannot listen on {url}: {err.strerror or err}") from None
        except BaseException:
            self.close()
            raise

    def _learn_action_ids(self, inner: str, names: list[str]) -> None:
        qi = import_qi()
        client = qi.Session()
        client.connect(inner)
        try:
            for name in names:
                methods = client.service(name).metaObject()["methods"]
                by_shape = {
                    (m["name"], m["parametersSignature"]): int(uid) for uid, m in methods.items()
                }
                for method, overloads in SERVICES[name].items():
                    for k, overload in enumerate(overloads):
                        uid = by_shape.get((method, "(" + "".join(overload.params) + ")"))
                        if uid is not None:
                            self._ids[(name, method, k)] = (self._service_ids[name], uid)
        finally:
            client.close()

    def _caller_for(self, name: str) -> Callable[[str, int], str]:
        def caller(method: str, overload: int) -> str:
            ids = self._ids.get((name, method, overload))
            if ids is None or self._relay is None:
                return LIBQI_CALLER
            return str(self._relay.caller_of(*ids))

        return caller

    def endpoints(self) -> list[str]:
        """The URL clients connect to (the relay's)."""
        if self._relay is None:
            return []
        host, port = self._relay.address
        return [f"tcp://{host}:{port}"]

    def close(self) -> None:
        """Stop the relay and the libqi session. Safe to call twice."""
        relay, self._relay = self._relay, None
        if relay is not None:
            relay.close()
        session, self._session = self._session, None
        if session is not None:
            with contextlib.suppress(Exception):
                session.close()


class _MemoryEndpoint:
    """ALMemory's endpoint on libqi: ``subscriber(key)`` returns a qi object with a signal."""

    def __init__(self, inner: Any, subscribers: _MemorySubscribers) -> None:
        self._inner = inner
        self._subscribers = subscribers

    def invoke(self, caller: str, method: str, args: list[Any]) -> Any:
        if method == "subscriber":
            if len(args) != 1 or not isinstance(args[0], str) or not args[0]:
                raise RobotError("ALMemory.subscriber: the key must be a non-empty string")
            return self._subscribers.new(args[0])
        return self._inner.invoke(caller, method, args)
