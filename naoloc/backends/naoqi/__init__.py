"""The NAOqi network backend: a Robot over a qi session (a real NAO or ``naoloc serve``).

``robot.backend: naoqi`` with ``robot.url`` (``tcp://<ip>:9559``; NAOqi 2.9+:
``tcps://<ip>:9503`` with ``robot.user`` and ``robot.password``, or the password in the
environment variable ``NAOLOC_NAO_PASSWORD`` so it stays off disk) and
``robot.transport`` (``libqi`` = the real qi package, ``zmq`` = naoloc's pure-Python
shim, ``qimessaging`` = libqi's wire protocol in pure Python, ``auto`` = libqi when qi
imports, qimessaging otherwise, zmq when the server greets with ZeroMQ).

``robot.sim`` is None unless ``robot.sim_service: true`` asks for the virtual NAOqi's
``NaolocSim`` service (ground truth and teleport), so a real NAO never gets one.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from naoloc.config import Config
from naoloc.errors import BackendError
from naoloc.robot import Robot


def create(cfg: Config) -> Robot:
    """Connect to the NAOqi ``cfg.robot`` describes.

    Raises:
        ConnectionLost: Nothing answers at ``robot.url``.
        DependencyNotInstalled: transport libqi without the qi package.
        BackendError: ``robot.sim_service`` asked for but the server has no NaolocSim.
    """
    from naoloc.backends.naoqi.client import Link, looks_like_zmq
    from naoloc.backends.naoqi.proxies import RemoteMotion, RemotePosture, RemoteSim, RemoteVideo
    from naoloc.backends.naoqi.session import resolve_transport
    from naoloc.backends.naoqi.signatures import SIM

    rc = cfg.robot
    transport = resolve_transport(rc.transport)
    if rc.transport == "auto" and transport != "zmq" and looks_like_zmq(rc.url):
        transport = "zmq"
    # The password from the config (never written to any file) or the environment.
    password = (
        rc.password.get_secret_value()
        if rc.password is not None
        else os.environ.get("NAOLOC_NAO_PASSWORD")
    )
    link = Link(
        rc.url, transport, user=rc.user, password=password, curve_keys=rc.curve_keys,
        tls_trust=rc.tls_trust,
    )  # fmt: skip
    link.open()
    try:
        sim = None
        if rc.sim_service:
            if not link.has_service(SIM):
                raise BackendError(
                    f"robot.sim_service: the NAOqi at {rc.url} has no {SIM} service "
                    "(only `naoloc serve` has one)"
                )
            sim = RemoteSim(link, rc.timeout_s, rc.move_timeout_s)
        args = (link, rc.timeout_s, rc.move_timeout_s)
        return Robot(
            motion=RemoteMotion(*args),
            video=RemoteVideo(*args),
            posture=RemotePosture(*args),
            sim=sim,
            backend="naoqi",
            info={"url": rc.url, "transport": transport},
            read=_reader(link, rc.timeout_s),
            _closer=link.close,
        )
    except BaseException:
        link.close()
        raise


def _reader(link: Any, timeout_s: float) -> Callable[..., Any]:
    """``read(service, method, *args)``: a repeatable read of any served service, or
    None when the NAOqi does not serve ``service``."""

    def read(service: str, method: str, *args: Any) -> Any:
        if not link.has_service(service):
            return None
        return link.call(service, method, *args, timeout_s=timeout_s, idempotent=True)

    return read
