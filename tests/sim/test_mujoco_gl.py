"""The GL platform is chosen through MUJOCO_GL before mujoco is imported; never by a reload."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytest.importorskip("mujoco", reason="the sim extra is not installed")

LATE = """
import mujoco  # imported before naoloc chose a platform: GLFW, which needs a display
import naoloc
from naoloc.errors import RenderError
try:
    naoloc.connect({"robot": {"backend": "mujoco"}})
except RenderError as err:
    print("RenderError:", err)
"""

EARLY = """
import naoloc
with naoloc.connect({"robot": {"backend": "mujoco"}}) as robot:
    import mujoco
    from naoloc.backends.mujoco.gl import loaded_platform
    h = robot.video.subscribeCamera("t", 0, 0, 11, 5)
    print("platform", loaded_platform(mujoco), len(robot.video.getImageRemote(h)[6]))
"""


def _run(code: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )


def test_naoloc_chooses_the_platform_when_it_imports_mujoco_first() -> None:
    out = _run(EARLY)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[:2] in (["platform", "egl"], ["platform", "osmesa"])
    assert int(out.stdout.split()[2]) == 160 * 120 * 3


def test_mujoco_imported_earlier_is_a_one_line_error_naming_the_variable() -> None:
    out = _run(LATE)
    assert out.returncode == 0, out.stderr
    line = out.stdout.strip()
    assert line.startswith("RenderError:") and len(line.splitlines()) == 1
    assert "MUJOCO_GL=" in line and "before the first `import mujoco`" in line
