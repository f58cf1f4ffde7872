"""The one explicit backend registry, and ``connect``.

Each backend is a lazy ``"module:function"`` entry point; the function takes a
:class:`~naoloc.config.Config` and returns a :class:`~naoloc.robot.Robot`. Nothing is
imported until a backend is asked for, so ``import naoloc`` never imports mujoco,
qi or zmq.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from naoloc.config import Config, load_config
from naoloc.errors import BackendError, DependencyNotInstalled, NaolocError
from naoloc.robot import Robot


@dataclass(frozen=True)
class BackendSpec:
    """A registered backend.

    Attributes:
        entry_point: ``"module:function"`` creating the robot from a Config.
        extra: The pip extra that installs its optional dependencies, or None.
        modules: Top-level modules the extra provides (to name the fix precisely).
        summary: One line for ``--help`` and error messages.
    """

    entry_point: str
    extra: str | None
    modules: tuple[str, ...]
    summary: str


BACKENDS: dict[str, BackendSpec] = {
    "fake": BackendSpec(
        "naoloc.backends.fake:create", None, (), "kinematic robot in a ray-cast room (tests)"
    ),
    "mujoco": BackendSpec(
        "naoloc.backends.mujoco:create", "sim", ("mujoco", "OpenGL"), "MuJoCo simulated NAO"
    ),
    "naoqi": BackendSpec(
        "naoloc.backends.naoqi:create", None, ("zmq",), "a real or virtual NAOqi over the network"
    ),
}


def backend_names() -> list[str]:
    """Names of the registered backends, sorted."""
    return sorted(BACKENDS)


def _load_factory(name: str) -> Callable[[Config], Robot]:
    try:
        spec = BACKENDS[name]
    except KeyError:
        raise BackendError(
            f"unknown backend {name!r}; valid backends: {', '.join(backend_names())}"
        ) from None
    module_name, _, attr = spec.entry_point.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        missing = (err.name or "").split(".")[0]
        if spec.extra and missing in spec.modules:
            raise DependencyNotInstalled(
                f"backend {name!r} needs {missing!r}: pip install 'naoloc[{spec.extra}]'"
            ) from None
        if missing in spec.modules:
            raise DependencyNotInstalled(
                f"backend {name!r} needs {missing!r}: pip install naoloc (it is a core dependency)"
            ) from None
        raise
    factory: Callable[[Config], Robot] | None = getattr(module, attr, None)
    if factory is None:
        raise BackendError(f"backend {name!r} is not built yet ({spec.entry_point} is missing)")
    return factory


def connect(config: str | Path | dict[str, Any] | Config | None = None) -> Robot:
    """Create the robot a config describes.

    Args:
        config: A YAML path, a dict, a Config, or None for defaults (MuJoCo simulator).

    Returns:
        A :class:`Robot`; use it as a context manager.

    Raises:
        ConfigError: The config is invalid.
        BackendError: The backend is unknown or failed to start.
        DependencyNotInstalled: An optional dependency is missing (names the pip extra).
    """
    cfg = load_config(config)
    factory = _load_factory(cfg.robot.backend)
    try:
        return factory(cfg)
    except NaolocError:
        raise
    except Exception as err:
        raise BackendError(
            f"backend {cfg.robot.backend!r} failed to start: {type(err).__name__}: {err}"
        ) from err
