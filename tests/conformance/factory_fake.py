"""Conformance factory of the fake backend (kinematic robot, ray-cast room)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import naoloc
from naoloc.constants import COLORSPACE_LAYERS, kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA
from naoloc.robot import Robot

NAME = "fake"
MARKS: list[Any] = []
RESOLUTIONS = (kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA)
COLORSPACES = tuple(sorted(COLORSPACE_LAYERS))


@contextmanager
def make_robot() -> Iterator[Robot]:
    """A fake robot in the default 6 x 6 m room (room seed 1), closed on exit."""
    with naoloc.connect({"robot": {"backend": "fake"}, "world": {"room": {"seed": 1}}}) as robot:
        yield robot
