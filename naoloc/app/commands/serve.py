"""``naoloc serve``: serve the simulated robot a config describes as a virtual NAOqi.

The robot (``robot.backend`` fake or mujoco) is served as ALMotion, ALVideoDevice and
ALRobotPosture, plus NaolocSim (ground truth, teleport) and NaolocWatchdog (keep-alive),
on ``--listen`` over libqi (NAOqi's own protocol), zmq (naoloc's shim) or qimessaging
(NAOqi's protocol in naoloc's own pure-Python implementation: real libqi clients
connect without libqi on the server). It prints
one line ``naoloc serve: listening on <url> (<transport>)`` once ready, runs until
SIGINT or SIGTERM, and stops the robot on exit.

The simulation runs continuously at ``--speed`` times real time (default 1.0, as a
NAO), so a client that sleeps sees the robot walk; see :mod:`naoloc.backends.naoqi.emulation.loop`.

Security: only loopback addresses unless ``--allow-remote``; on zmq a non-loopback
address also needs CURVE keys (``robot.curve_keys``); libqi is refused off loopback
(no NAOqi 2.9 login). Over qimessaging, ``--login`` asks clients for a user and a
password as NAOqi 2.9 does: they come from the environment (:data:`USER_ENV`,
:data:`PASSWORD_ENV`) or a prompt on the terminal, never from the command line or a
file; off loopback qimessaging needs both a login and TLS (``tcps://`` with
``--tls-cert``). Clients can never (un)register services.

The dead-man stops a velocity walk whose client makes no call for
``--command-timeout`` seconds (default 0.4, so it has stopped within 0.5 s; 0 = never,
as a real NAOqi).
"""

from __future__ import annotations

import argparse
import getpass
import ipaddress
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from naoloc.backends.naoqi.urls import parse_url
from naoloc.config import Config
from naoloc.errors import BackendError, ConfigError

USER_ENV = "NAOLOC_SERVE_USER"
PASSWORD_ENV = "NAOLOC_SERVE_PASSWORD"


def is_loopback(url: str) -> bool:
    """True when ``url``'s host is a loopback address (127.0.0.0/8, ::1, localhost)."""
    host = urlsplit(url).hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_listen(
    url: str,
    transport: str,
    allow_remote: bool,
    curve_keys: str | None,
    *,
    login: bool = False,
    tls: bool = False,
) -> None:
    """Refuse unsafe listen addresses.

    Args:
        url: ``tcp://host:port`` (or ``tcps://`` over qimessaging).
        transport: ``libqi``, ``zmq`` or ``qimessaging``.
        allow_remote: ``--allow-remote`` was given.
        curve_keys: zmq's CURVE folder, or None.
        login: qimessaging asks for a login.
        tls: qimessaging has a certificate.

    Raises:
        BackendError: A non-loopback address without ``--allow-remote``; on zmq
            without CURVE keys; on libqi; on qimessaging without a login over
            ``tcps://``; or a URL that is not ``tcp://host:port``.
    """
    schemes = ("tcp", "tcps") if transport == "qimessaging" else ("tcp",)
    parsed = parse_url(url, what="--listen", schemes=schemes)
    if parsed.scheme == "tcps" and not tls:
        raise BackendError("--listen tcps:// needs a certificate: pass --tls-cert PEM")
    if is_loopback(url):
        return
    host = parsed.host
    if not allow_remote:
        raise BackendError(
            f"{host} is not a loopback address; pass --allow-remote to expose the robot"
        )
    if transport == "zmq" and not curve_keys:
        raise BackendError(
            "serving zmq off loopback needs CURVE keys: set robot.curve_keys "
            "(create them with naoloc.backends.naoqi.zmq_transport.make_curve_keys)"
        )
    if transport == "libqi":
        raise BackendError(
            "serving libqi off loopback needs NAOqi 2.9 logins over tcps://, which naoloc "
            "serve does not implement: use --transport qimessaging with --login over tcps://"
        )
    if transport == "qimessaging" and not (login and parsed.scheme == "tcps"):
        raise BackendError(
            "serving qimessaging off loopback needs a login and TLS: --listen tcps://HOST:PORT "
            f"--tls-cert PEM --login (the password from {PASSWORD_ENV} or a prompt)"
        )


def read_login(ask: bool) -> dict[str, str] | None:
    """The login clients must give: from the environment, else a prompt; None = none.

    A login is asked for when ``ask`` (``--login``) or when :data:`PASSWORD_ENV` is set.
    The user is :data:`USER_ENV` (default ``nao``); the password :data:`PASSWORD_ENV`,
    else typed on the terminal (not echoed). Never from the command line or a file.

    Raises:
        ConfigError: A login is asked for, the environment has no password and there is
            no terminal to ask, or the password is empty.
    """
    password = os.environ.get(PASSWORD_ENV)
    if password is None and not ask:
        return None
    user = os.environ.get(USER_ENV) or "nao"
    if password is None:
        if not sys.stdin.isatty():
            raise ConfigError(
                f"--login: set {PASSWORD_ENV} (and {USER_ENV}) or run in a terminal to type it"
            )
        password = getpass.getpass(f"naoloc serve: password for {user}: ")
    if not password:
        raise ConfigError("--login: the password is empty")
    return {user: password}


def few_malloc_arenas() -> None:
    """Let glibc's malloc use two arenas, not one per thread (up to 8 per core).

    Every connection has threads of its own, and memory freed in a thread's arena mostly
    stays with the process: a server that took 31 x 512 KiB values three times kept 25 MB
    more each time; with two arenas it keeps nothing (tools/bench_attack.py).
    """
    if not sys.platform.startswith("linux"):
        return
    import contextlib
    import ctypes

    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).mallopt(-8, 2)  # M_ARENA_MAX (glibc); ignored elsewhere


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Serve until SIGINT/SIGTERM; return the summary printed as the last JSON line."""
    from naoloc.backends.naoqi.server import COMMAND_TIMEOUT_S, RobotThread, VirtualNaoqi
    from naoloc.backends.naoqi.session import resolve_transport
    from naoloc.robot.registry import connect
    from naoloc.viz.live import live_from_args, watch

    if cfg.robot.backend == "naoqi":
        raise ConfigError("naoloc serve: robot.backend must be a simulator (fake or mujoco)")
    transport = resolve_transport(args.transport or cfg.robot.transport)
    url: str = args.listen
    cert = getattr(args, "tls_cert", None)
    key = getattr(args, "tls_key", None)
    ask = bool(getattr(args, "login", False))
    if transport != "qimessaging" and (ask or cert or key):
        raise BackendError("--login and --tls-cert are served by --transport qimessaging only")
    users = read_login(ask) if transport == "qimessaging" else None
    check_listen(
        url, transport, bool(args.allow_remote), cfg.robot.curve_keys,
        login=users is not None, tls=cert is not None,
    )  # fmt: skip
    speed = float(getattr(args, "speed", 1.0) or 1.0)
    if not 0.0 < speed <= 1000.0:
        raise BackendError(f"--speed must be in (0, 1000], got {speed:g}")
    timeout = getattr(args, "command_timeout", None)
    timeout = COMMAND_TIMEOUT_S if timeout is None else float(timeout)
    if not 0.0 <= timeout <= 60.0:
        raise BackendError(f"--command-timeout must be in [0, 60] s, got {timeout:g}")
    trace = _open_trace(getattr(args, "trace", None))  # an unwritable path fails first
    few_malloc_arenas()  # before the server's threads exist
    live = live_from_args(args)
    stop = threading.Event()

    def on_signal(signum: int, frame: Any) -> None:
        stop.set()

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    # The robot lives on one thread: created, called and closed there (MuJoCo's OpenGL
    # context belongs to its thread; libqi calls services from a thread pool).
    robot_thread = RobotThread()
    try:
        robot = robot_thread.run(connect, cfg)
        try:
            with VirtualNaoqi(
                watch(robot, live),
                url,
                transport,
                curve_keys=cfg.robot.curve_keys,
                thread=robot_thread,
                speed=speed,
                command_timeout_s=timeout or None,
                users=users,
                certfile=str(cert) if cert else None,
                keyfile=str(key) if key else None,
                cfg=cfg,
            ) as server:
                if trace is not None:
                    server.core.trace = trace.write_call
                print(f"naoloc serve: listening on {server.endpoint} ({transport})", flush=True)
                while not stop.wait(0.2):
                    pass
                summary = {
                    "endpoint": server.endpoint,
                    "transport": transport,
                    "backend": cfg.robot.backend,
                    "calls": server.core.calls,
                    "deadman_stops": server.core.deadman_stops,
                    "speed": speed,
                    "errors": server.core.errors,
                }
        finally:
            robot_thread.run(robot.close)
    finally:
        robot_thread.close()
        live.close()
        if trace is not None:
            trace.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return summary


class _Trace:
    """``serve --trace FILE``: one line ``<caller> <Service>.<method>`` per call, flushed
    at once (a test or an owner reads which calls a client made, motion ones included)."""

    def __init__(self, path: Path) -> None:
        self._file = path.open("a", encoding="utf-8", buffering=1)
        self._lock = threading.Lock()

    def write_call(self, caller: str, service: str, method: str) -> None:
        with self._lock:
            if not self._file.closed:
                self._file.write(f"{caller} {service}.{method}\n")

    def close(self) -> None:
        with self._lock:
            self._file.close()


def _open_trace(path: Path | None) -> _Trace | None:
    return None if path is None else _Trace(path)
