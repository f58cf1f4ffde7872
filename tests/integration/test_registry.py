"""The backend registry and the import-light guarantee."""

from __future__ import annotations

import subprocess
import sys

import pytest

import naoloc
from naoloc.errors import BackendError, DependencyNotInstalled
from naoloc.robot.registry import BACKENDS, BackendSpec, _load_factory, backend_names


def test_import_naoloc_imports_no_heavy_modules() -> None:
    code = (
        "import sys, naoloc, naoloc.app.cli, naoloc.robot, naoloc.config;"
        "bad = [m for m in ('mujoco', 'qi', 'zmq', 'cv2', 'matplotlib') if m in sys.modules];"
        "print(bad); sys.exit(1 if bad else 0)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr


def test_backend_names() -> None:
    assert backend_names() == ["fake", "mujoco", "naoqi"]


def test_unknown_backend_lists_valid_ones() -> None:
    with pytest.raises(BackendError, match="valid backends: fake, mujoco, naoqi"):
        _load_factory("webots")


def test_missing_optional_dependency_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    spec = BackendSpec(
        "naoloc_missing_mod_for_test:create", "sim", ("naoloc_missing_mod_for_test",), "x"
    )
    monkeypatch.setitem(BACKENDS, "ghost", spec)
    with pytest.raises(DependencyNotInstalled, match=r"pip install 'naoloc\[sim\]'"):
        _load_factory("ghost")


def test_connect_rejects_bad_config() -> None:
    with pytest.raises(naoloc.ConfigError, match="robot.backend"):
        naoloc.connect({"robot": {"backend": "webots"}})


def test_no_generic_backends_package_is_importable() -> None:
    code = (
        "import importlib.util, sys;"
        "sys.exit(0 if importlib.util.find_spec('backends') is None else 1)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/")
    assert out.returncode == 0
