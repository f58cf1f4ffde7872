"""Choose the headless OpenGL platform before mujoco is imported: EGL, else OSMesa.

MuJoCo and PyOpenGL read ``MUJOCO_GL`` and ``PYOPENGL_PLATFORM`` once, when they are first
imported, so the choice is made by setting those variables in ``os.environ`` before that
(as dm_control does) and cannot change afterwards in the same process. A value the user
already set is respected. Nothing is reloaded: a process that imported mujoco before naoloc
chose a platform gets a one-line error saying what to set. Works with mujoco 3.x and 4.x.
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
HEADLESS = ("egl", "osmesa")


def missing_message() -> str:
    """The one-line fix for a machine that cannot render headless."""
    return (
        "headless rendering needs EGL or OSMesa: "
        f"apt-get install {EGL_PACKAGES} (or {OSMESA_PACKAGES} with MUJOCO_GL=osmesa)"
    )


def probe(mujoco: Any) -> None:
    """Create and free a tiny OpenGL context, so that a machine that cannot render fails early.

    Args:
        mujoco: The imported mujoco module (3.x or 4.x: both export ``GLContext``).

    Raises:
        RenderError: One line naming the packages to install.
    """
    try:
        context = mujoco.GLContext(16, 16)
        context.make_current()
        context.free()
    except Exception as err:  # GL failures come as many different exception types
        why = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        backend = os.environ.get("MUJOCO_GL", "")
        raise RenderError(f"{missing_message()}; MUJOCO_GL={backend} failed: {why}") from None


def loaded_platform(mujoco: Any) -> str:
    """The GL platform an imported mujoco resolved (``egl``, ``osmesa``, ``glfw``...), or "".

    mujoco picks its ``GLContext`` class from ``MUJOCO_GL`` at import; the class's module
    (``mujoco.egl``, ``mujoco.osmesa``, ``mujoco.glfw``) names the platform in 3.x and 4.x.
    """
    context = getattr(mujoco, "GLContext", None)
    module = getattr(context, "__module__", "") or ""
    return module.rsplit(".", 1)[-1] if module.startswith("mujoco.") else ""


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
    if chosen in HEADLESS and "OpenGL" not in sys.modules:
        os.environ["PYOPENGL_PLATFORM"] = chosen
    return chosen


def check_loaded(mujoco: Any, chosen: str) -> None:
    """Fail in one line when mujoco was imported before ``MUJOCO_GL`` was set to ``chosen``.

    Raises:
        RenderError: mujoco already resolved another platform (e.g. GLFW, which needs a
            display); names the variable to set before the first import.
    """
    loaded = loaded_platform(mujoco)
    if chosen in HEADLESS and loaded and loaded != chosen:
        raise RenderError(
            f"mujoco was imported with the {loaded} platform before naoloc chose {chosen}: "
            f"set MUJOCO_GL={chosen} PYOPENGL_PLATFORM={chosen} in the environment "
            "(or before the first `import mujoco`)"
        )


def import_mujoco() -> Any:
    """Choose the headless GL platform (not strict), then import and return ``mujoco``.

    Imported by name so that type checkers never confuse it with this package's folder.
    Rendering fails later with :func:`check_loaded`'s message when mujoco was imported
    earlier with another platform; physics works either way.
    """
    select_gl(strict=False)
    return importlib.import_module("mujoco")
