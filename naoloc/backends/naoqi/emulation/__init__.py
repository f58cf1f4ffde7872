"""NAOqi semantics shared by the simulated backends and the virtual NAOqi (``naoloc serve``).

Pure Python: nothing here imports mujoco, qi or zmq. The backends supply physics,
rendering and pose; this package supplies NAOqi's rules in front of them:

- :mod:`.rules` argument checking, name expansion, joint limits and NAOqi's error texts;
- :mod:`.loop` the robot thread and the server's clock (simulation at K x real time);
- :mod:`.tasks` ALMotion's task model (task ids, ``wait``, ``stop``, ``isRunning``);
- :mod:`.video` ALVideoDevice's subscriber bookkeeping;
- :mod:`.motion` and :mod:`.posture` ALMotion and ALRobotPosture in front of a backend;
- :mod:`.memory`, :mod:`.speech` and :mod:`.companions` ALMemory, speech, ALLeds and the
  other companion services.
"""
