"""Robot backends, one sub-package each, created through :mod:`naoloc.robot.registry`.

- ``fake``: a kinematic robot in a ray-cast room (fast tests);
- ``mujoco``: the simulated NAO in MuJoCo (extra ``sim``);
- ``naoqi``: a real NAO or a virtual NAOqi over the network, and the server side of
  ``naoloc serve`` (the NAOqi emulation in ``naoqi.emulation``);
- ``simulated``: the models both simulators share (odometry error, walk sway, camera).

Each backend exposes ``create(cfg: Config) -> Robot``. Nothing here is imported by
``import naoloc``.
"""
