"""The fake backend: a kinematic NAO in a ray-cast, procedurally textured room.

For unit tests and quick experiments: no MuJoCo, no network, no threads, no wall clock,
yet real enough that feature extraction and the survey -> map -> localize pipeline run.

- Walking is kinematic, within NAO's walk speeds, at the 50 Hz ALMotion cycle; the
  robot (a disc of 0.15 m) never enters a wall: a walk that would is stopped.
- Walking is open-loop on odometry, as on a NAO: ``getRobotPosition(False)`` integrates the
  commands, ``getRobotPosition(True)`` the legs' measured motion (a little joint-sensor
  noise), and the body strays from both by ``world.odometry`` (profile ``nao``: a NAO's
  published drift; ``ideal``: exact); both read ``[0, 0, 0]`` at ``cfg.start_pose()``.
- Frames are ray-cast in numpy from the true camera pose: the true robot pose and the
  forward kinematics of the joints (``naoloc/robot/kinematics.py``; StandInit leans forward), with
  the walk's sway (``world.sim.camera_sway``). ``getPosition``/``getTransform`` use the same
  kinematics; ``robot.sim.true_camera_pose(i)`` gives the truth.
- The robot starts standing in StandInit with its motors on, as Webots' NAO does; with
  ``world.sim.start_awake: false`` it starts at rest in Crouch (motors off), like a NAO that
  was just switched on, and walks only after ``motion.wakeUp()``.

Usage::

    with naoloc.connect({"robot": {"backend": "fake"}}) as robot:
        robot.motion.wakeUp()
        robot.motion.moveTo(0.5, 0.0, 0.0)
"""

from __future__ import annotations

from naoloc.backends.fake.motion import FakeMotion
from naoloc.backends.fake.posture import FakePosture
from naoloc.backends.fake.render import RoomRenderer
from naoloc.backends.fake.sim import FakeSim
from naoloc.backends.fake.textures import make_atlas
from naoloc.backends.fake.video import FakeVideo
from naoloc.backends.fake.world import FakeWorld
from naoloc.config import Config
from naoloc.robot import Robot

__all__ = ["FakeMotion", "FakePosture", "FakeSim", "FakeVideo", "FakeWorld", "create"]


def create(cfg: Config) -> Robot:
    """Create a fake robot for a config.

    Args:
        cfg: The configuration: ``world.room`` (size, wall height, seed, posters),
            ``world.start_pose``, ``world.model`` (field of view), ``world.odometry``
            (drift) and ``world.camera_realism``. Furniture is not modelled.

    Returns:
        A :class:`~naoloc.robot.Robot` with ``backend="fake"`` and ``sim`` set.
    """
    room = cfg.world.room
    world = FakeWorld(cfg)
    renderer = RoomRenderer(make_atlas(room), room.size_m, room.wall_height_m)

    def close() -> None:
        world.stop_walk()
        world.closed = True

    info = {
        "model": cfg.world.model,
        "room_size_m": list(room.size_m),
        "wall_height_m": room.wall_height_m,
        "room_seed": room.seed,
        "start_pose": list(cfg.start_pose()),
        "furniture": False,
    }
    return Robot(
        motion=FakeMotion(world),
        video=FakeVideo(world, renderer),
        posture=FakePosture(world),
        sim=FakeSim(world),
        backend="fake",
        info=info,
        _closer=close,
    )
