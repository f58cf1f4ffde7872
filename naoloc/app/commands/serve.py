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
(no NAOqi 2.9 login). Clients can never (un)register services.
"""

from __future__ import annotations

import argparse
import ipaddress
import signal
import threading
from typing import Any
from urllib.parse import urlsplit

from naoloc.backends.naoqi.urls import parse_url
from naoloc.config import Config
from naoloc.errors import BackendError, ConfigError


def is_loopback(url: str) -> bool:
    """True when ``url``'s host is a loopback address (127.0.0.0/8, ::1, localhost)."""
    host = urlsplit(url).hostname or ""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_listen(url: str, transport: str, allow_remote: bool, curve_keys: str | None) -> None:
    """Refuse unsafe listen addresses.

    Raises:
        BackendError: A non-loopback address without ``--allow-remote``, or on zmq
            without CURVE keys, or a URL that is not ``tcp://host:port``.
    """
    host = parse_url(url, what="--listen", schemes=("tcp",)).host
    if is_loopback(url):
        return
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
            "serve does not implement: use --transport zmq with robot.curve_keys"
        )


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Serve until SIGINT/SIGTERM; return the summary printed as the last JSON line."""
    from naoloc.backends.naoqi.server import RobotThread, VirtualNaoqi
    from naoloc.backends.naoqi.session import resolve_transport
    from naoloc.robot.registry import connect
    from naoloc.viz.live import live_from_args, watch

    if cfg.robot.backend == "naoqi":
        raise ConfigError("naoloc serve: robot.backend must be a simulator (fake or mujoco)")
    transport = resolve_transport(args.transport or cfg.robot.transport)
    url: str = args.listen
    check_listen(url, transport, bool(args.allow_remote), cfg.robot.curve_keys)
    speed = float(getattr(args, "speed", 1.0) or 1.0)
    if not 0.0 < speed <= 1000.0:
        raise BackendError(f"--speed must be in (0, 1000], got {speed:g}")
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
                cfg=cfg,
            ) as server:
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
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return summary
