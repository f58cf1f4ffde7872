"""The qi-compatible shim: Future, Promise, Signal and the Session factory.

naoloc talks to NAOqi through the call shapes of libqi's ``qi.Session``: ``connect``,
``close``, ``isConnected``, ``service`` (a proxy whose methods accept ``_async=True``
and then return a future), ``services``, ``registerService``, ``listenStandalone``,
``endpoints`` and the ``disconnected`` signal. :func:`new_session` returns either a real
``qi.Session`` (transport ``libqi``), a :class:`~.zmq_transport.ZmqSession` (transport
``zmq``) or a :class:`~.qimessaging.client.QiSession` (transport ``qimessaging``: libqi's
wire protocol in pure Python), so the client and server code is written once.

Futures mirror ``qi.Future``: ``wait(ms)``, ``isFinished()``, ``hasError()``,
``error()`` (a string), ``hasValue()``, ``value(ms)``, ``addCallback(fn)``.
"""

from __future__ import annotations

import importlib.util
import threading
from collections.abc import Callable
from typing import Any, Literal

from naoloc.errors import BackendError, ConnectionLost, DependencyNotInstalled, NaolocError

Transport = Literal["libqi", "zmq", "qimessaging"]

QI_INSTALL_HINT = (
    "transport libqi needs the qi package: pip install 'naoloc[naoqi]' "
    "(qi wheels exist only for Linux x86-64 and Python <= 3.12); or use transport "
    "qimessaging (naoloc's own implementation of the same protocol, no qi needed)"
)

# States, spelled as qi.FutureState names.
RUNNING = "Running"
FINISHED_WITH_VALUE = "FinishedWithValue"
FINISHED_WITH_ERROR = "FinishedWithError"


class Future:
    """The result of an asynchronous call; the qi.Future shape, thread-safe.

    ``error()`` is a one-line string ``"<ErrorType>: <message>"``; ``value()`` raises
    the naoloc error it names (RobotError when unknown).
    """

    def __init__(self) -> None:
        self._done = threading.Event()
        self._lock = threading.Lock()
        self._value: Any = None
        self._error: NaolocError | None = None
        self._callbacks: list[Callable[[Future], None]] = []
        self._canceller: Callable[[], None] | None = None

    def _finish(self, value: Any, error: NaolocError | None) -> bool:
        with self._lock:
            if self._done.is_set():
                return False
            self._value, self._error = value, error
            self._done.set()
            callbacks, self._callbacks = self._callbacks, []
        for callback in callbacks:
            callback(self)
        return True

    def wait(self, timeout_ms: int | None = None) -> str:
        """Wait up to ``timeout_ms`` milliseconds (None = forever); return the state name."""
        self._done.wait(None if timeout_ms is None else timeout_ms / 1000.0)
        return self.state()

    def state(self) -> str:
        """``"Running"``, ``"FinishedWithValue"`` or ``"FinishedWithError"``."""
        if not self._done.is_set():
            return RUNNING
        return FINISHED_WITH_ERROR if self._error is not None else FINISHED_WITH_VALUE

    def isFinished(self) -> bool:
        """True once a value or an error is set."""
        return self._done.is_set()

    def isRunning(self) -> bool:
        """True while no value or error is set."""
        return not self._done.is_set()

    def hasError(self, timeout_ms: int | None = None) -> bool:
        """True when the call failed (waits up to ``timeout_ms`` like qi)."""
        self.wait(timeout_ms)
        return self._error is not None

    def hasValue(self, timeout_ms: int | None = None) -> bool:
        """True when the call succeeded (waits up to ``timeout_ms`` like qi)."""
        return self.wait(timeout_ms) == FINISHED_WITH_VALUE

    def error(self) -> str:
        """``"<ErrorType>: <message>"`` of a failed call, "" otherwise."""
        err = self._error
        return "" if err is None else f"{type(err).__name__}: {err}"

    def exception(self) -> NaolocError | None:
        """The naoloc error of a failed call, None otherwise."""
        return self._error

    def value(self, timeout_ms: int | None = None) -> Any:
        """The call's result, waiting up to ``timeout_ms`` milliseconds (None = forever).

        Raises:
            ConnectionLost: Timed out.
            NaolocError: The error the call failed with.
        """
        if not self._done.wait(None if timeout_ms is None else timeout_ms / 1000.0):
            raise ConnectionLost(f"no answer within {timeout_ms} ms")
        if self._error is not None:
            raise self._error
        return self._value

    def addCallback(self, callback: Callable[[Future], None]) -> None:
        """Call ``callback(future)`` once finished (at once if it already is)."""
        with self._lock:
            if not self._done.is_set():
                self._callbacks.append(callback)
                return
        callback(self)

    def _set_canceller(self, canceller: Callable[[], None]) -> None:
        """What :meth:`cancel` does (qimessaging sends a cancel message)."""
        self._canceller = canceller

    def cancel(self) -> None:
        """Ask the server to cancel the call (qimessaging); a no-op on zmq."""
        canceller = self._canceller
        if canceller is not None and not self._done.is_set():
            canceller()


class Promise:
    """The producer side of a :class:`Future` (the qi.Promise shape)."""

    def __init__(self) -> None:
        self._future = Future()

    def future(self) -> Future:
        """The future this promise completes."""
        return self._future

    def setValue(self, value: Any) -> bool:
        """Complete with a value; False when already complete."""
        return self._future._finish(value, None)

    def setError(self, error: NaolocError) -> bool:
        """Complete with an error; False when already complete."""
        return self._future._finish(None, error)


class Signal:
    """A qi.Signal shape: ``connect(fn) -> link id``, ``disconnect(id)``, call to emit."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._next = 1
        self._subscribers: dict[int, Callable[..., None]] = {}

    def connect(self, callback: Callable[..., None]) -> int:
        """Subscribe; returns the link id."""
        with self._lock:
            link, self._next = self._next, self._next + 1
            self._subscribers[link] = callback
        return link

    def disconnect(self, link: int) -> bool:
        """Unsubscribe a link id; True when it existed."""
        with self._lock:
            return self._subscribers.pop(link, None) is not None

    def __call__(self, *args: Any) -> None:
        with self._lock:
            subscribers = list(self._subscribers.values())
        for callback in subscribers:
            callback(*args)


def qi_available() -> bool:
    """True when the real ``qi`` package can be imported (checked without importing it)."""
    try:
        return importlib.util.find_spec("qi") is not None
    except (ImportError, ValueError):  # blocked (an import hook, or sys.modules["qi"] = None)
        return False


def resolve_transport(transport: str) -> Transport:
    """Turn ``auto | libqi | zmq | qimessaging`` into a concrete transport.

    ``auto`` prefers libqi when the qi package is installed, otherwise naoloc's own
    QiMessaging (the zmq greeting is detected by the caller, see ``looks_like_zmq``).

    Raises:
        DependencyNotInstalled: ``libqi`` without the qi package.
        BackendError: An unknown transport name.
    """
    if transport == "auto":
        return "libqi" if qi_available() else "qimessaging"
    if transport == "libqi":
        if not qi_available():
            raise DependencyNotInstalled(QI_INSTALL_HINT)
        return "libqi"
    if transport in ("zmq", "qimessaging"):
        return "zmq" if transport == "zmq" else "qimessaging"
    raise BackendError(f"unknown transport {transport!r}; valid: auto, libqi, zmq, qimessaging")


def new_session(
    transport: Transport, *, curve_keys: str | None = None, connect_timeout_s: float = 3.0
) -> Any:
    """A fresh, unconnected session with the qi.Session call shapes.

    Args:
        transport: ``libqi`` (a real ``qi.Session``), ``zmq`` (our shim) or
            ``qimessaging`` (naoloc's own libqi wire protocol, no qi package).
        curve_keys: zmq only: folder with CURVE certificates (see
            :func:`~.zmq_transport.make_curve_keys`); None = no encryption.
        connect_timeout_s: zmq and qimessaging: how long ``connect`` waits for an answer.

    Raises:
        DependencyNotInstalled: libqi without the qi package.
    """
    if transport == "libqi":
        from naoloc.backends.naoqi import libqi_transport

        return libqi_transport.new_session()
    if transport == "qimessaging":
        from naoloc.backends.naoqi.qimessaging.client import QiSession

        return QiSession(connect_timeout_s=connect_timeout_s)
    from naoloc.backends.naoqi.zmq_transport import ZmqSession

    return ZmqSession(curve_keys=curve_keys, connect_timeout_s=connect_timeout_s)


def error_from_text(text: str) -> NaolocError:
    """Turn a remote error string into a naoloc error.

    Accepts our ``"HandleError: msg"`` and libqi's forms (``"RuntimeError: HandleError:
    msg"`` followed by a traceback, or a plain NAOqi message); keeps the first line.
    Known naoloc error names are re-raised as themselves, anything else as RobotError.
    """
    err = _error_from_line(text)
    err.remote_text = text  # type: ignore[attr-defined]  # naoloc.qi raises it verbatim, as qi
    return err


def _error_from_line(text: str) -> NaolocError:
    from naoloc import errors

    known: dict[str, type[NaolocError]] = {
        cls.__name__: cls
        for cls in (
            errors.RobotError,
            errors.HandleError,
            errors.MotionError,
            errors.ProtocolError,
            errors.BackendError,
            errors.ConnectionLost,
        )
    }
    lines = (text or "").strip().splitlines()
    line = lines[0].strip() if lines else ""
    line = line or "remote call failed"
    for _ in range(3):
        name, sep, rest = line.partition(": ")
        if not sep or not name.isidentifier():
            break
        if name in known:
            return known[name](rest)
        if name not in ("RuntimeError", "Exception"):
            break
        line = rest
    lowered = line.lower()
    if any(m in lowered for m in ("not connected", "session closed", "connection closed")):
        return errors.ConnectionLost(line)
    return errors.RobotError(line)
