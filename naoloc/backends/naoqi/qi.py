"""A qi-compatible module: NAO scripts run without libqi, on any OS and any Python.

``import naoloc.qi as qi`` in place of ``import qi``::

    session = qi.Session()
    session.connect("tcp://nao.local:9559")      # a real NAO, or `naoloc serve`
    session.service("ALMotion").moveTo(0.2, 0.0, 0.0)

The transport is chosen by the URL or by ``qi.Session(transport=...)``: ``tcp://`` and
``tcps://`` speak libqi's own protocol through naoloc's pure-Python QiMessaging (a
``naoloc serve --transport zmq`` server is recognised by its greeting and reached over
zmq), ``zmq://host:port`` forces zmq. Calls take ``_async=True`` and return a
:class:`Future`; remote errors raise ``RuntimeError`` like qi. Also: ``Application``
(``--qi-url``, a process-wide singleton like qi's), ``Promise``, ``Signal``,
``Property``, ``bind`` and the type names for services served with
``listenStandalone``, ``runAsync``, ``PeriodicTask``, ``Logger`` and ``logging``.
Nothing here imports the real ``qi`` package.
"""

from __future__ import annotations

import contextlib
import logging as pylogging
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, Final

from naoloc.backends.naoqi import session as _shim
from naoloc.backends.naoqi.qimessaging.codec import NamedStruct
from naoloc.errors import NaolocError

__all__ = [
    "Application",
    "Bool",
    "Buffer",
    "Double",
    "Dynamic",
    "Float",
    "Future",
    "FutureState",
    "Int8",
    "Int16",
    "Int32",
    "Int64",
    "List",
    "Map",
    "Object",
    "Promise",
    "Property",
    "Session",
    "Signal",
    "String",
    "UInt8",
    "UInt16",
    "UInt32",
    "UInt64",
    "Void",
    "bind",
    "runAsync",
]  # fmt: skip

# Type names for qi.bind, as libqi signatures.
Int8, UInt8, Int16, UInt16 = "c", "C", "w", "W"
Int32, UInt32, Int64, UInt64 = "i", "I", "l", "L"
Float, Double, Bool, String = "f", "d", "b", "s"
Buffer, Dynamic, Object, Void = "r", "m", "o", "v"


def List(element: str) -> str:
    """The signature of a list of ``element``."""
    return f"[{element}]"


def Map(key: str, value: str) -> str:
    """The signature of a map from ``key`` to ``value``."""
    return "{" + key + value + "}"


class FutureState:
    """qi.FutureState names."""

    Running: Final = _shim.RUNNING
    FinishedWithValue: Final = _shim.FINISHED_WITH_VALUE
    FinishedWithError: Final = _shim.FINISHED_WITH_ERROR


def _qi_value(value: Any) -> Any:
    """A decoded value as qi's Python binding gives it.

    Raw buffers (``r``) as ``bytearray`` (naoloc's client keeps zero-copy memoryviews),
    structs with named fields as ``dict``; lists, maps and tuples converted inside.
    """
    if isinstance(value, memoryview):
        return bytearray(value)
    if isinstance(value, NamedStruct):
        return {k: _qi_value(v) for k, v in value.as_dict().items()}
    if isinstance(value, list):
        return [_qi_value(v) for v in value] if _nested(value) else value
    if isinstance(value, tuple):
        return tuple(_qi_value(v) for v in value) if _nested(value) else value
    if isinstance(value, dict):
        return {_qi_value(k): _qi_value(v) for k, v in value.items()}
    return value


def _nested(items: list[Any] | tuple[Any, ...]) -> bool:
    return any(isinstance(v, list | tuple | dict | memoryview) for v in items)


def _runtime_error(err: NaolocError) -> RuntimeError:
    """qi's RuntimeError: the remote error's text as the server sent it, else one line."""
    text = getattr(err, "remote_text", None)
    return RuntimeError(text if isinstance(text, str) and text else f"{type(err).__name__}: {err}")


class Future:
    """qi.Future: ``value(ms)`` raises ``RuntimeError`` on a remote error, like qi."""

    def __init__(self, inner: _shim.Future | None = None) -> None:
        self._inner = inner if inner is not None else _shim.Future()

    def value(self, timeout: int | None = None) -> Any:
        """The result, waiting up to ``timeout`` ms (None = forever).

        Raises:
            RuntimeError: The call failed or timed out.
        """
        try:
            return _qi_value(self._inner.value(timeout))
        except NaolocError as err:
            raise _runtime_error(err) from None

    def wait(self, timeout: int | None = None) -> str:
        """Wait up to ``timeout`` ms; the state name."""
        return self._inner.wait(timeout)

    def hasError(self, timeout: int | None = None) -> bool:
        """True when the call failed."""
        return self._inner.hasError(timeout)

    def hasValue(self, timeout: int | None = None) -> bool:
        """True when the call succeeded."""
        return self._inner.hasValue(timeout)

    def error(self) -> str:
        """The error text ("" when none), as the server sent it."""
        exception = getattr(self._inner, "exception", None)
        err = exception() if callable(exception) else None
        return str(_runtime_error(err)) if err is not None else self._inner.error()

    def isFinished(self) -> bool:
        """True once finished."""
        return self._inner.isFinished()

    def isRunning(self) -> bool:
        """True while running."""
        return self._inner.isRunning()

    def isCanceled(self) -> bool:
        """True when the call ended cancelled."""
        return "cancelled" in self._inner.error()

    def cancel(self) -> None:
        """Ask the server to cancel the call."""
        self._inner.cancel()

    def addCallback(self, callback: Callable[[Future], Any]) -> None:
        """Call ``callback(future)`` once finished."""
        self._inner.addCallback(lambda _inner: callback(self))

    def then(self, callback: Callable[[Future], Any]) -> Future:
        """A future of ``callback(self)`` once this one finishes."""
        promise = Promise()

        def run(_: Future) -> None:
            try:
                promise.setValue(callback(self))
            except Exception as err:  # the callback's error becomes the future's
                promise.setError(str(err))

        self.addCallback(run)
        return promise.future()


class Promise:
    """qi.Promise: the producer side of a :class:`Future`."""

    def __init__(self) -> None:
        self._inner = _shim.Promise()
        self._future = Future(self._inner.future())

    def future(self) -> Future:
        """The future this promise completes."""
        return self._future

    def setValue(self, value: Any) -> None:
        """Complete with a value."""
        self._inner.setValue(value)

    def setError(self, error: str) -> None:
        """Complete with an error message."""
        self._inner.setError(_shim.error_from_text(str(error)))


class Signal(_shim.Signal):
    """qi.Signal: ``connect(fn) -> link``, ``disconnect(link)``, call to emit.

    Args:
        signature: Tuple signature of its arguments (for serving), default ``(m)``.
    """

    def __init__(self, signature: str = "(m)") -> None:
        super().__init__()
        self.signature = signature


class Property(Signal):
    """qi.Property: ``value()``, ``setValue(v)`` (emits the new value)."""

    def __init__(self, signature: str = "m") -> None:
        super().__init__(f"({signature})")
        self._value: Any = None

    def value(self) -> Any:
        """The current value."""
        return self._value

    def setValue(self, value: Any) -> None:
        """Set and announce a new value."""
        self._value = value
        self(value)


def bind(
    returnType: str = Void,
    paramsType: Sequence[str] | None = None,
    methodName: str | None = None,
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """qi.bind: declare a served method's signature (used by ``registerService``)."""

    def mark(function: Callable[..., Any]) -> Callable[..., Any]:
        params = paramsType
        if params is None:
            count = function.__code__.co_argcount - 1  # without self
            params = [Dynamic] * max(0, count)
        function._qi_signature = (methodName or function.__name__, list(params), returnType)  # type: ignore[attr-defined]
        return function

    return mark


def runAsync(function: Callable[..., Any], *args: Any, delay: int = 0) -> Future:
    """Run ``function(*args)`` on a thread after ``delay`` microseconds; its Future."""
    promise = Promise()

    def run() -> None:
        if delay:
            threading.Event().wait(delay / 1e6)
        try:
            promise.setValue(function(*args))
        except Exception as err:  # the function's error becomes the future's
            promise.setError(f"{type(err).__name__}: {err}")

    threading.Thread(target=run, name="naoloc-qi-async", daemon=True).start()
    return promise.future()


class _Logging:
    """qi.logging: levels and module-level log functions over Python's logging."""

    SILENT, FATAL, ERROR, WARNING, INFO, VERBOSE, DEBUG = 0, 1, 2, 3, 4, 5, 6
    _TO_PY: Final = {0: 100, 1: 50, 2: 40, 3: 30, 4: 20, 5: 15, 6: 10}

    def __init__(self) -> None:
        self._logger = pylogging.getLogger("naoloc.qi")

    def setLevel(self, level: int) -> None:
        """Show messages of ``level`` (qi.logging.ERROR...) and more severe."""
        self._logger.setLevel(self._TO_PY.get(int(level), 20))

    def fatal(self, message: str, category: str = "naoloc.qi") -> None:
        """Log a fatal message."""
        pylogging.getLogger(category).critical(message)

    def error(self, message: str, category: str = "naoloc.qi") -> None:
        """Log an error."""
        pylogging.getLogger(category).error(message)

    def warning(self, message: str, category: str = "naoloc.qi") -> None:
        """Log a warning."""
        pylogging.getLogger(category).warning(message)

    def info(self, message: str, category: str = "naoloc.qi") -> None:
        """Log information."""
        pylogging.getLogger(category).info(message)

    def verbose(self, message: str, category: str = "naoloc.qi") -> None:
        """Log a verbose message."""
        pylogging.getLogger(category).log(15, message)

    def debug(self, message: str, category: str = "naoloc.qi") -> None:
        """Log a debug message."""
        pylogging.getLogger(category).debug(message)


logging = _Logging()


class Logger:
    """qi.Logger(category): ``info``, ``warning``, ``error``, ``fatal``, ``verbose``, ``debug``."""

    def __init__(self, category: str) -> None:
        self._category = category

    def fatal(self, message: str) -> None:
        """Log a fatal message."""
        logging.fatal(message, self._category)

    def error(self, message: str) -> None:
        """Log an error."""
        logging.error(message, self._category)

    def warning(self, message: str) -> None:
        """Log a warning."""
        logging.warning(message, self._category)

    def info(self, message: str) -> None:
        """Log information."""
        logging.info(message, self._category)

    def verbose(self, message: str) -> None:
        """Log a verbose message."""
        logging.verbose(message, self._category)

    def debug(self, message: str) -> None:
        """Log a debug message."""
        logging.debug(message, self._category)


class PeriodicTask:
    """qi.PeriodicTask: call a function every period on a thread of its own."""

    def __init__(self) -> None:
        self._callback: Callable[[], Any] | None = None
        self._period_s = 1.0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def setCallback(self, callback: Callable[[], Any]) -> None:
        """The function to call."""
        self._callback = callback

    def setUsPeriod(self, period_us: int) -> None:
        """The period, microseconds."""
        self._period_s = max(1e-4, period_us / 1e6)

    def start(self, immediate: bool = True) -> None:
        """Start calling (at once when ``immediate``)."""
        if self._callback is None:
            raise RuntimeError("PeriodicTask: setCallback first")
        if self.isRunning():
            return
        self._stop.clear()
        callback = self._callback

        def run() -> None:
            if not immediate and self._stop.wait(self._period_s):
                return
            while not self._stop.is_set():
                started = time.monotonic()
                try:
                    callback()
                except Exception as err:  # qi logs a failing periodic callback and goes on
                    logging.error(f"PeriodicTask callback failed: {err}")
                self._stop.wait(max(0.0, self._period_s - (time.monotonic() - started)))

        self._thread = threading.Thread(target=run, name="naoloc-qi-periodic", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop and wait for the current call to end."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        self._thread = None

    def isRunning(self) -> bool:
        """True while started."""
        return self._thread is not None and self._thread.is_alive()


class _SignalProxy:
    """A remote signal or property whose callbacks and values are qi's Python types."""

    def __init__(self, inner: Any) -> None:
        self._inner = inner

    def connect(self, callback: Callable[..., Any]) -> int:
        """Call ``callback(*args)`` on every emission; the link id."""

        def relay(*args: Any) -> Any:
            return callback(*(_qi_value(a) for a in args))

        link: int = self._inner.connect(relay)
        return link

    def disconnect(self, link: int) -> bool:
        """Stop one link; True when it was connected."""
        return bool(self._inner.disconnect(link))

    def disconnectAll(self) -> None:
        """Stop every link made through this proxy."""
        self._inner.disconnectAll()

    def value(self, _async: bool = False) -> Any:
        """A property's value."""
        try:
            found = self._inner.value(_async=True)
        except NaolocError as err:
            raise _runtime_error(err) from None
        wrapped = Future(found)
        return wrapped if _async else wrapped.value()

    def setValue(self, value: Any, _async: bool = False) -> Any:
        """Change a property's value."""
        try:
            done = self._inner.setValue(value, _async=True)
        except NaolocError as err:
            raise _runtime_error(err) from None
        wrapped = Future(done)
        return wrapped if _async else wrapped.value()

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self._inner, name)


class _Proxy:
    """A service proxy whose calls raise RuntimeError and return qi-style Futures."""

    def __init__(self, inner: Any, name: str) -> None:
        self._inner, self._name = inner, name

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        member = getattr(self._inner, name)
        if callable(getattr(member, "connect", None)):
            return _SignalProxy(member)
        if not callable(member):
            return member

        def call(*args: Any, _async: bool = False) -> Any:
            try:
                future = member(*args, _async=True)
            except NaolocError as err:
                raise _runtime_error(err) from None
            wrapped = Future(future)
            if _async:
                return wrapped
            value = wrapped.value()
            if callable(getattr(value, "metaObject", None)):  # an object a method returned
                return _Proxy(value, f"{self._name}.{name}()")
            return value

        call.__name__ = name
        return call

    def __repr__(self) -> str:
        return f"<naoloc.qi proxy {self._name}>"


def _transport_for(url: str, transport: str | None) -> tuple[str, str]:
    from naoloc.backends.naoqi.client import looks_like_zmq
    from naoloc.backends.naoqi.qimessaging.connection import normalize_url

    if url.startswith("zmq://"):
        return "zmq", "tcp://" + url[len("zmq://") :]
    url = normalize_url(url)
    if transport in ("zmq", "qimessaging"):
        return transport, url
    if transport == "libqi":
        raise RuntimeError("naoloc.qi never uses libqi; use `import qi` for that")
    return ("zmq" if looks_like_zmq(url) else "qimessaging"), url


class Session:
    """qi.Session over naoloc's transports (no libqi).

    Args:
        transport: ``qimessaging``, ``zmq`` or None (choose from the URL: ``zmq://``,
            or a zmq greeting, means zmq; anything else qimessaging).
    """

    def __init__(self, transport: str | None = None) -> None:
        self._transport = transport
        self._session: Any = None
        self._login: tuple[str, str] | None = None
        self.connected = Signal("()")
        self.disconnected = Signal("(s)")

    def _inner(self) -> Any:
        if self._session is None:
            raise RuntimeError("Session not connected")
        return self._session

    def setClientAuthenticatorFactory(self, factory: Any) -> None:
        """NAOqi 2.9+ login (``initialAuthData()`` gives user and token)."""
        data = factory.newAuthenticator().initialAuthData()
        self._login = (str(data.get("user", "")), str(data.get("token", "")))

    def connect(self, url: str, _async: bool = False) -> Any:
        """Connect to a NAOqi (``tcp://``, ``tcps://`` or ``zmq://``).

        Raises:
            RuntimeError: Nothing answers, or the login is refused.
        """
        transport, real_url = _transport_for(url, self._transport)
        inner = _shim.new_session(transport)  # type: ignore[arg-type]
        if self._login is not None:
            if transport != "qimessaging":
                raise RuntimeError("a login (NAOqi 2.9+) needs a tcps:// NAOqi, not zmq")
            inner.set_login(*self._login)
        try:
            inner.connect(real_url)
        except NaolocError as err:
            with contextlib.suppress(Exception):
                inner.close()
            raise RuntimeError(str(err)) from None
        inner.disconnected.connect(lambda *why: self.disconnected(*(why or ("closed",))))
        self._session = inner
        self.connected()
        if _async:
            promise = Promise()
            promise.setValue(None)
            return promise.future()
        return None

    def isConnected(self) -> bool:
        """True while connected."""
        return self._session is not None and bool(self._session.isConnected())

    def service(self, name: str, _async: bool = False) -> Any:
        """A proxy of service ``name``.

        Raises:
            RuntimeError: No such service or no connection.
        """
        try:
            proxy = _Proxy(self._inner().service(name), name)
        except NaolocError as err:
            raise RuntimeError(f"Cannot find service '{name}' ({err})") from None
        if _async:
            promise = Promise()
            promise.setValue(proxy)
            return promise.future()
        return proxy

    def services(self) -> list[dict[str, Any]]:
        """ServiceInfo dicts (``name``, ``serviceId``...) of every service."""
        try:
            found = self._inner().services()
        except NaolocError as err:
            raise RuntimeError(str(err)) from None
        return [s if isinstance(s, dict) else {"name": str(s)} for s in found]

    def waitForService(self, name: str, timeout: float = 5.0) -> None:
        """Return once ``name`` is served (polls; ``timeout`` in seconds)."""
        deadline = time.monotonic() + timeout
        while not any(s.get("name") == name for s in self.services()):
            if time.monotonic() > deadline:
                raise RuntimeError(f"service {name!r} did not appear within {timeout} s")
            time.sleep(0.05)

    def listenStandalone(self, url: str) -> None:
        """Serve a service directory at ``url`` (qimessaging; port 0 = any)."""
        inner = _shim.new_session("qimessaging")
        try:
            inner.listenStandalone(url)
        except NaolocError as err:
            raise RuntimeError(str(err)) from None
        self._session = inner

    def listen(self, url: str) -> None:
        """A connected session: serve the services it registers at ``url`` (qi's
        ``Session.listen``; by default they are served on the address that reaches the
        robot, any free port)."""
        try:
            self._inner().listen(url)
        except NaolocError as err:
            raise RuntimeError(str(err)) from None

    def registerService(self, name: str, obj: Any) -> int:
        """Serve ``obj`` (methods marked with :func:`bind`, Signal/Property attributes).

        On a connected session the service is registered with the robot's service
        directory (a NAO's or ``naoloc serve``'s), as qi does, until the session closes.
        """
        from naoloc.backends.naoqi.qimessaging.client import QiSession
        from naoloc.backends.naoqi.qimessaging.meta import describe

        inner = self._inner()
        if not isinstance(inner, QiSession):
            raise RuntimeError(
                "registerService: a zmq connection cannot serve services; connect with "
                "tcp:// to a NAOqi that speaks libqi's protocol"
            )
        methods, signals = describe(obj)
        try:
            service_id: int = inner.registerService(name, obj, methods=methods, signals=signals)
        except NaolocError as err:
            raise RuntimeError(str(err)) from None
        return service_id

    def unregisterService(self, service_id: int) -> None:
        """Stop serving a service."""
        self._inner().unregisterService(service_id)

    def endpoints(self) -> list[str]:
        """Where a listening session accepts connections."""
        return list(self._inner().endpoints())

    def url(self) -> str:
        """The URL connected to or listened on."""
        return str(self._inner().url())

    def close(self) -> None:
        """Close the connection. Safe to call twice."""
        session, self._session = self._session, None
        if session is not None:
            session.close()


class Application:
    """qi.Application: parses ``--qi-url`` from argv; one per process, like qi.

    Args:
        args: The command line (default ``sys.argv``); qi's options are removed from it.
        url: Default NAOqi URL when ``--qi-url`` is absent.
        transport: As for :class:`Session`.

    Raises:
        RuntimeError: An Application already exists in this process.
    """

    _instance: ClassVar[Application | None] = None
    _guard: ClassVar[threading.Lock] = threading.Lock()

    def __init__(
        self,
        args: list[str] | None = None,
        url: str = "tcp://127.0.0.1:9559",
        transport: str | None = None,
    ) -> None:
        with Application._guard:
            if Application._instance is not None:
                raise RuntimeError("Application was already initialized")
            Application._instance = self
        argv = sys.argv if args is None else args
        self.url = _pop_option(argv, "--qi-url") or url
        self._stop = threading.Event()
        self._session = Session(transport)

    @property
    def session(self) -> Session:
        """The application's session (connected by :meth:`start`)."""
        return self._session

    def start(self) -> None:
        """Connect the session to :attr:`url`."""
        if not self._session.isConnected():
            self._session.connect(self.url)

    def run(self) -> None:
        """Start, then block until :meth:`stop` (or Ctrl-C)."""
        self.start()
        with contextlib.suppress(KeyboardInterrupt):
            while not self._stop.wait(0.1):
                pass
        self._session.close()

    def stop(self) -> None:
        """Make :meth:`run` return."""
        self._stop.set()

    @classmethod
    def _reset_for_tests(cls) -> None:
        """Forget the singleton (tests create several applications in one process)."""
        with cls._guard:
            cls._instance = None


ApplicationSession = Application


def _pop_option(argv: list[str], name: str) -> str | None:
    """Remove ``name VALUE`` or ``name=VALUE`` from ``argv``; the value or None."""
    for i, arg in enumerate(argv):
        if arg == name and i + 1 < len(argv):
            value = argv[i + 1]
            del argv[i : i + 2]
            return value
        if arg.startswith(name + "="):
            del argv[i]
            return arg.split("=", 1)[1]
    return None
