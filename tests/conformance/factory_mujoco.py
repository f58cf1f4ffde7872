"""Conformance factory of the MuJoCo backend (simulated NAO, rendered room)."""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest

import naoloc
from naoloc.constants import COLORSPACE_LAYERS, k4VGA, kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA
from naoloc.robot import Robot

NAME = "mujoco"
MARKS: list[Any] = [pytest.mark.sim]
RESOLUTIONS = (kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA, k4VGA)
COLORSPACES = tuple(sorted(COLORSPACE_LAYERS))
# A small room keeps start-up short (fewer posters to draw); seed 3 is not a shipped config.
CONFIG = {
    "robot": {"backend": "mujoco"},
    "world": {"room": {"size_m": [4.0, 3.5], "seed": 3, "posters_per_wall": 3}},
    "survey": {"wall_offset_m": 0.8},
}


@contextmanager
def make_robot() -> Iterator[Robot]:
    """A simulated NAO in a 4 x 3.5 m room (seed 3), closed on exit."""
    if importlib.util.find_spec("mujoco") is None:
        pytest.skip("mujoco is not installed: pip install 'naoloc[sim]'")
    with naoloc.connect(CONFIG) as robot:
        yield robot
