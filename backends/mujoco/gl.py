"""Choose the headless OpenGL platform before mujoco is imported: EGL, else OSMesa.

MuJoCo and PyOpenGL read ``MUJOCO_GL`` and ``PYOPENGL_PLATFORM`` when they are first
imported, so the choice must be made before that and cannot change afterwards in the
same process. A value the user already set is respected.
"""

from __future__ import annotations

import ctypes.util
import importlib
import os
import sys
from typing import Any

from naoloc.errors import RenderError

EGL_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri"
OSMESA_PACKAGES = "libosmesa6"


def missing_message() -> str:
    """The one-line fix for a machine that cannot render headless."""
    return (
        "headless rendering needs EGL or OSMesa: "
        f"apt-get install {EGL_PACKAGES} (or {OSMESA_PACKAGES} with MUJOCO_GL=osmesa)"
    )


def probe(mujoco: Any) -> None:
    """Create and free a tiny OpenGL context, so that a machine that cannot render fails early.

    Args:
        mujoco: The imported mujoco module.

    Raises:
        RenderError: One line naming the packages to install.
    """
    try:
        context = mujoco.rendering.classic.gl_context.GLContext(16, 16)
        context.make_current()
        context.free()
    except Exception as err:  # GL failures come as many different exception types
        why = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        backend = os.environ.get("MUJOCO_GL", "")
        raise RenderError(f"{missing_message()}; MUJOCO_GL={backend} failed: {why}") from None


def select_gl(strict: bool = True) -> str:
    """Set ``MUJOCO_GL`` (and a matching ``PYOPENGL_PLATFORM``) if unset; return the choice.

    EGL is preferred when libEGL and a vendor library (Mesa or NVIDIA) are installed;
    OSMesa is the fallback. The backend's modules call this (not strict) before they
    import mujoco, which reads the variable once, at import.

    Args:
        strict: Raise when neither library is installed; otherwise leave the variable unset
            and return "".

    Raises:
        RenderError: When strict and neither library is installed (names the Debian packages).
    """
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    if not chosen:
        has_egl = ctypes.util.find_library("EGL") is not None
        has_vendor = any(ctypes.util.find_library(v) for v in ("EGL_mesa", "EGL_nvidia"))
        has_osmesa = ctypes.util.find_library("OSMesa") is not None
        if has_egl and has_vendor:
            chosen = "egl"
        elif has_osmesa:
            chosen = "osmesa"
        elif has_egl:
            chosen = "egl"
        elif strict:
            raise RenderError(missing_message())
        else:
            return ""
        os.environ["MUJOCO_GL"] = chosen
    if chosen in ("egl", "osmesa") and "OpenGL" not in sys.modules:
        os.environ["PYOPENGL_PLATFORM"] = chosen
    _reresolve_late_import(chosen)
    return chosen


def import_mujoco() -> Any:
    """Choose the headless GL platform (not strict), then import and return ``mujoco``.

    Imported by name so that type checkers never confuse it with this package's folder.
    """
    select_gl(strict=False)
    return importlib.import_module("mujoco")


def _reresolve_late_import(chosen: str) -> None:
    """Let mujoco pick up ``chosen`` if it was imported before MUJOCO_GL was set.

    mujoco resolves its GL context class once, when imported; imported with MUJOCO_GL unset
    it tries GLFW, which fails headless before OpenGL is loaded. Re-running that module
    (``mujoco.Renderer`` reads the class from it at construction) then picks the platform
    chosen here. Nothing is done once PyOpenGL is loaded: its platform is fixed for good.
    """
    module = sys.modules.get("mujoco.rendering.classic.gl_context")
    if module is None or getattr(module, "_MUJOCO_GL", chosen) == chosen:
        return
    if "OpenGL" in sys.modules:
        return
    importlib.reload(module)
