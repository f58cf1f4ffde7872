"""The MuJoCo backend: a simulated NAO in a room generated from the config.

``create(cfg)`` builds the room, compiles it with the NAO model (``model/nao.xml``) and
returns a :class:`naoloc.robot.Robot` whose ``motion``, ``video`` and ``posture`` mirror
ALMotion, ALVideoDevice and ALRobotPosture, and whose ``sim`` gives ground truth, teleport
and a few knobs for robustness experiments (see README.md). Importing this package does
not import mujoco; ``create`` does, after choosing the headless OpenGL platform.
"""

from __future__ import annotations

import importlib

from naoloc.config import Config
from naoloc.errors import DependencyNotInstalled, RenderError
from naoloc.robot import Robot

__all__ = ["create"]


def create(cfg: Config) -> Robot:
    """Start a simulated NAO.

    Args:
        cfg: The validated config (world.*, camera.*, survey.* for the furniture layout).

    Returns:
        The robot; use it as a context manager.

    Raises:
        DependencyNotInstalled: mujoco or PyOpenGL is missing (``pip install 'naoloc[sim]'``).
        RenderError: No headless OpenGL (names the Debian packages to install).
        BackendError: The generated room does not compile.
    """
    from naoloc.backends.mujoco.gl import check_loaded, missing_message, probe, select_gl

    chosen = select_gl()
    try:
        importlib.import_module("OpenGL")
        mujoco = importlib.import_module("mujoco")
    except ModuleNotFoundError as err:
        missing = (err.name or "mujoco").split(".")[0]
        raise DependencyNotInstalled(
            f"backend 'mujoco' needs {missing!r}: pip install 'naoloc[sim]'"
        ) from None
    except ImportError as err:  # e.g. the GL platform library cannot be loaded
        raise RenderError(f"{missing_message()} ({type(err).__name__}: {err})") from None

    check_loaded(mujoco, chosen)
    probe(mujoco)

    from naoloc.backends.mujoco.motion import MujocoMotion, MujocoPosture
    from naoloc.backends.mujoco.sim import Simulation
    from naoloc.backends.mujoco.video import MujocoVideo

    sim = Simulation(cfg)
    motion = MujocoMotion(sim)
    posture = MujocoPosture(sim, motion)
    video = MujocoVideo(sim)

    def closer() -> None:
        video.close()
        sim.close()

    info = {
        "model": cfg.world.model,
        "room_size_m": list(sim.room_size()),
        "room_seed": cfg.world.room.seed,
        "posters": len(sim.poster_names()),
        "furniture": [f.name for f in sim.layout.furniture],
        "timestep_s": float(sim.model.opt.timestep),
        "start_pose": list(cfg.start_pose()),
    }
    return Robot(
        motion=motion,
        video=video,
        posture=posture,
        sim=sim,
        backend="mujoco",
        info=info,
        _closer=closer,
    )
