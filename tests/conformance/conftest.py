"""The conformance suite: the same NAOqi-semantics checks run over every backend.

Each ``tests/conformance/factory_<name>.py`` module describes one backend setup:

- ``NAME: str`` the test id (e.g. "fake", "mujoco", "naoqi-zmq");
- ``MARKS: list`` pytest marks for its tests (e.g. ``[pytest.mark.sim]``);
- ``make_robot()`` a context manager yielding a connected :class:`naoloc.Robot`; it may call
  ``pytest.skip(reason)`` when the backend cannot run here;
- optionally ``RESOLUTIONS`` and ``COLORSPACES``: the NAOqi ids the backend claims
  (default: kQQVGA, kQVGA, kVGA and all six colorspaces).

The ``robot`` fixture is parametrized over the factories; ``factory`` gives the module.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from naoloc.robot import Robot


def _load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"naoloc_conformance_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    for attr in ("NAME", "MARKS", "make_robot"):
        if not hasattr(module, attr):
            raise ImportError(f"{path.name} does not define {attr}")
    return module


def _factory_params() -> list[Any]:
    params = []
    for path in sorted(Path(__file__).parent.glob("factory_*.py")):
        try:
            module = _load(path)
        except Exception as err:  # a broken factory fails its tests, never silently dropped
            params.append(
                pytest.param(f"{path.name}: {type(err).__name__}: {err}", id=path.stem[8:])
            )
            continue
        params.append(pytest.param(module, id=module.NAME, marks=list(module.MARKS)))
    return params


@pytest.fixture(params=_factory_params())
def factory(request: pytest.FixtureRequest) -> ModuleType:
    """The factory module of the backend under test."""
    if isinstance(request.param, str):
        pytest.fail(f"broken conformance factory {request.param}")
    return request.param


@pytest.fixture
def robot(factory: ModuleType) -> Iterator[Robot]:
    """A connected robot of the backend under test, closed after the test."""
    with factory.make_robot() as robot:
        yield robot
