"""Client side: a watched connection to a NAOqi, and service proxies with timeouts.

:class:`Link` owns one session (libqi or zmq). Every call is made asynchronously and
waited for in 50 ms slices, so a call never outlives its timeout and notices a lost
connection at once. A heartbeat thread calls ``NaolocWatchdog.ping`` (virtual NAOqi;
it also feeds the server's dead-man) or lists the services (a real NAOqi) every
0.2 s; no answer within 0.9 s, or libqi's ``disconnected`` signal, marks the link
lost. Idempotent reads then try to reconnect with backoff for up to 0.6 s and retry
once; everything else raises :class:`~naoloc.errors.ConnectionLost` at once, so a lost
connection surfaces within 2 s.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from typing import Any, Final
from urllib.parse import urlsplit

from naoloc.backends.naoqi.session import Transport, error_from_text, new_session
from naoloc.backends.naoqi.signatures import WATCHDOG
from naoloc.backends.naoqi.urls import parse_url
from naoloc.errors import BackendError, ConnectionLost, NaolocError, RobotError

HEARTBEAT_EVERY_S: Final = 0.2
HEARTBEAT_TIMEOUT_S: Final = 0.9
RECONNECT_BUDGET_S: Final = 0.6
CONNECT_TIMEOUT_S: Final = 5.0
_SLICE_MS: Final = 50


def looks_like_zmq(url: str, timeout_s: float = 0.3) -> bool:
    """True when the server at ``url`` greets with ZMTP (a zmq virtual NAOqi).

    A ZeroMQ peer sends its 10-byte signature ``FF .. 7F`` as soon as a TCP connection
    opens; a libqi server does not. Used by transport ``auto``.
    """
    parts = urlsplit(url)
    if parts.scheme != "tcp" or parts.hostname is None or parts.port is None:
        return False
    try:
        with socket.create_connection((parts.hostname, parts.port), timeout=timeout_s) as sock:
            sock.settimeout(timeout_s)
            head = b""
            deadline = time.monotonic() + timeout_s
            while len(head) < 10 and time.monotonic() < deadline:
                chunk = sock.recv(10 - len(head))
                if not chunk:
                    break
                head += chunk
    except OSError:
        return False
    return len(head) == 10 and head[0] == 0xFF and head[9] == 0x7F


class Link:
    """A watched connection to a (real or virtual) NAOqi.

    Args:
        url: ``tcp://host:port`` (or ``tcps://`` for NAOqi 2.9+ over libqi/qimessaging).
        transport: ``libqi``, ``zmq`` or ``qimessaging``.
        user: NAOqi 2.9+ login (libqi and qimessaging), or None.
        password: NAOqi 2.9+ password, or None.
        curve_keys: zmq only: CURVE certificate folder, or None.
        tls_trust: qimessaging over tcps://: how the robot's certificate is checked
            (None = pinned on first use; see :mod:`~.qimessaging.trust`).
    """

    def __init__(
        self,
        url: str,
        transport: Transport,
        *,
        user: str | None = None,
        password: str | None = None,
        curve_keys: str | None = None,
        tls_trust: str | None = None,
    ) -> None:
        parse_url(url, what="robot.url", allow_any_port=False, default_port=9559)
        if transport == "zmq" and url.startswith("tcps://"):
            raise BackendError("tcps:// (NAOqi 2.9+) needs transport libqi or qimessaging")
        self.url = url
        self.transport = transport
        self._user, self._password, self._curve = user, password, curve_keys
        self._tls_trust = tls_trust
        self._session: Any = None
        self._proxies: dict[str, Any] = {}
        self._services: set[str] = set()
        self._lock = threading.Lock()
        self._lost = ""
        self._dead = False
        self._closed = False
        self._stop = threading.Event()
        self._heartbeat: threading.Thread | None = None

    # ------------------------------------------------------------------ lifecycle
    def open(self) -> None:
        """Connect, list the services, start the heartbeat.

        Raises:
            ConnectionLost: Nothing answers at the URL.
        """
        self._session = self._connect(CONNECT_TIMEOUT_S)
        self._heartbeat = threading.Thread(target=self._beat, name="naoloc-heartbeat", daemon=True)
        self._heartbeat.start()

    def _connect(self, timeout_s: float) -> Any:
        session = new_session(
            self.transport,
            curve_keys=self._curve,
            connect_timeout_s=timeout_s,
            tls_trust=self._tls_trust,
        )
        try:
            if self.transport == "qimessaging" and self._user:
                session.set_login(self._user, self._password or "")
            if self.transport == "libqi" and self._user:
                from naoloc.backends.naoqi.libqi_transport import set_login

                set_login(session, self._user, self._password or "")
            future = session.connect(self.url, _async=True)
            if self.transport in ("libqi", "qimessaging"):
                future.wait(int(timeout_s * 1000))
                if not future.isFinished():
                    raise ConnectionLost(f"no NAOqi answers at {self.url} within {timeout_s} s")
                if future.hasError():
                    raise ConnectionLost(
                        f"cannot connect to NAOqi at {self.url}: {_first_line(future.error())}"
                    )
                session.disconnected.connect(self._on_disconnected)
                names = [_service_name(s) for s in session.services()]
            else:
                session.disconnected.connect(self._on_disconnected)
                names = list(session.services())
        except NaolocError:
            with contextlib.suppress(Exception):
                session.close()
            raise
        except Exception as err:  # libqi raises RuntimeError
            with contextlib.suppress(Exception):
                session.close()
            raise ConnectionLost(
                f"cannot connect to NAOqi at {self.url}: {_first_line(str(err))}"
            ) from None
        with self._lock:
            self._services = set(names)
            self._proxies = {}
            self._lost = ""
        return session

    def has_service(self, name: str) -> bool:
        """True when the NAOqi serves ``name``."""
        return name in self._services

    def close(self) -> None:
        """Stop the heartbeat and close the session. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        if self._heartbeat is not None and self._heartbeat is not threading.current_thread():
            self._heartbeat.join(timeout=2.0)
        session, self._session = self._session, None
        if session is not None:
            with contextlib.suppress(Exception):
                session.close()

    # ------------------------------------------------------------------ liveness
    def _on_disconnected(self, *reason: Any) -> None:
        why = str(reason[0]) if reason else "disconnected"
        self._mark_lost(f"connection to NAOqi at {self.url} lost ({_first_line(why)})")

    def _mark_lost(self, reason: str) -> None:
        with self._lock:
            if not self._lost:
                self._lost = reason

    @property
    def lost(self) -> str:
        """Why the link is lost, or "" while it is healthy."""
        return self._lost

    def _ping_once(self) -> None:
        session = self._session
        if session is None:
            return
        try:
            if WATCHDOG in self._services:
                future = self._proxy(WATCHDOG).ping(_async=True)
            else:
                future = session.services(_async=True)
        except Exception as err:  # libqi raises RuntimeError on a dead socket
            self._mark_lost(f"connection to NAOqi at {self.url} lost ({_first_line(str(err))})")
            return
        future.wait(int(HEARTBEAT_TIMEOUT_S * 1000))
        if not future.isFinished():
            self._mark_lost(
                f"connection to NAOqi at {self.url} lost (no answer for {HEARTBEAT_TIMEOUT_S} s)"
            )
        elif future.hasError():
            self._mark_lost(
                f"connection to NAOqi at {self.url} lost ({_first_line(future.error())})"
            )

    def _beat(self) -> None:
        while not self._stop.is_set():
            started = time.monotonic()
            if not self._lost:
                self._ping_once()
            self._stop.wait(max(0.0, HEARTBEAT_EVERY_S - (time.monotonic() - started)))

    def _reconnect(self) -> bool:
        """Try to reconnect with backoff within :data:`RECONNECT_BUDGET_S`; True on success."""
        deadline = time.monotonic() + RECONNECT_BUDGET_S
        delay = 0.05
        while not self._closed:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            old, self._session = self._session, None
            if old is not None:
                with contextlib.suppress(Exception):
                    old.close()
            try:
                self._session = self._connect(min(remaining, 0.5))
                return True
            except NaolocError:
                time.sleep(min(delay, max(0.0, deadline - time.monotonic())))
                delay *= 2
        return False

    # ------------------------------------------------------------------ calls
    def _proxy(self, service: str) -> Any:
        proxy = self._proxies.get(service)
        if proxy is None:
            if self._session is None:
                raise ConnectionLost(self._lost or f"not connected to NAOqi at {self.url}")
            try:
                proxy = self._session.service(service)
            except NaolocError:
                raise
            except Exception as err:
                raise RobotError(
                    f"no service {service} at {self.url}: {_first_line(str(err))}"
                ) from None
            self._proxies[service] = proxy
        return proxy

    def _call_once(self, service: str, method: str, args: tuple[Any, ...], timeout_s: float) -> Any:
        if self._lost:
            raise ConnectionLost(self._lost)
        proxy = self._proxy(service)
        try:
            future = getattr(proxy, method)(*args, _async=True)
        except NaolocError:
            raise
        except Exception as err:  # libqi: RuntimeError / AttributeError
            raise error_from_text(str(err)) from None
        deadline = time.monotonic() + timeout_s
        while not future.isFinished():
            if self._lost:
                raise ConnectionLost(self._lost)
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ConnectionLost(
                    f"{service}.{method} got no answer from {self.url} within {timeout_s:g} s"
                )
            future.wait(max(1, min(_SLICE_MS, int(remaining * 1000))))
        if future.hasError():
            error = error_from_text(future.error())
            if self._lost or not self._session_alive():
                raise ConnectionLost(self._lost or str(error))
            raise error
        return future.value()

    def _session_alive(self) -> bool:
        session = self._session
        try:
            return session is not None and bool(session.isConnected())
        except Exception:  # a closed libqi session may raise
            return False

    def call(
        self,
        service: str,
        method: str,
        *args: Any,
        timeout_s: float,
        idempotent: bool = False,
    ) -> Any:
        """Call ``service.method(*args)`` remotely and wait at most ``timeout_s`` seconds.

        Args:
            service: e.g. "ALMotion".
            method: e.g. "getRobotPosition".
            *args: The NAOqi arguments.
            timeout_s: Longest wait for the answer (wall clock, s).
            idempotent: A read that may be repeated: after a lost connection it
                reconnects (with backoff) and retries once.

        Raises:
            ConnectionLost: The connection is dead or the call timed out.
            RobotError: The service refused the call (its own error type when naoloc's).
        """
        if self._closed:
            raise ConnectionLost(f"the connection to NAOqi at {self.url} is closed")
        if self._dead:
            raise ConnectionLost(self._lost or f"connection to NAOqi at {self.url} lost")
        try:
            return self._call_once(service, method, args, timeout_s)
        except ConnectionLost as err:
            if not self._lost:
                self._mark_lost(f"connection to NAOqi at {self.url} lost ({err})")
            if idempotent and self._reconnect():
                try:
                    return self._call_once(service, method, args, timeout_s)
                except ConnectionLost:
                    pass
            self._dead = True
            raise ConnectionLost(self._lost or str(err)) from None


def _first_line(text: str) -> str:
    lines = str(text).strip().splitlines()
    return lines[0] if lines else "unknown reason"


def _service_name(info: Any) -> str:
    if isinstance(info, dict):
        return str(info.get("name", ""))
    if isinstance(info, list | tuple) and info:
        return str(info[0])
    return str(getattr(info, "name", info))
