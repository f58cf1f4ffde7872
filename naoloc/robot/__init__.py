"""The robot: the NAOqi-mirroring interface, the backend registry and what sits on it.

- :mod:`~naoloc.robot.interface`: one Protocol per mirrored service (``Motion``,
  ``VideoDevice``, ``Posture``), ``SimControl`` and ``Robot`` (re-exported here);
- :mod:`~naoloc.robot.registry`: the lazy backend registry and ``connect``;
- :mod:`~naoloc.robot.conformance`: ``check_robot``, the conformance suite;
- :mod:`~naoloc.robot.rules`: NAOqi's argument rules and error texts;
- :mod:`~naoloc.constants`, :mod:`~naoloc.robot.kinematics`, :mod:`~naoloc.robot.lens`,
  :mod:`~naoloc.robot.image`, :mod:`~naoloc.robot.keyframe`, :mod:`~naoloc.robot.camera`.
"""

from __future__ import annotations

from naoloc.robot.interface import (
    Angles,
    Motion,
    Names,
    Posture,
    Robot,
    SimControl,
    VideoDevice,
    expand_joint_names,
    pose_of,
)

__all__ = [
    "Angles",
    "Motion",
    "Names",
    "Posture",
    "Robot",
    "SimControl",
    "VideoDevice",
    "expand_joint_names",
    "pose_of",
]
