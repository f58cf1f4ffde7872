"""Conformance factory: the naoqi backend over libqi (real qi), against `naoloc serve`."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest

import naoloc
from naoloc.backends.naoqi.testing import served
from naoloc.constants import COLORSPACE_LAYERS, kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA
from naoloc.robot import Robot

NAME = "naoqi-libqi"
TRANSPORT = "libqi"
MARKS: list[Any] = [pytest.mark.net]
RESOLUTIONS = (kQQQQVGA, kQQQVGA, kQQVGA, kQVGA, kVGA)
COLORSPACES = tuple(sorted(COLORSPACE_LAYERS))
SPEED = 4.0  # the server clock at 4 x real time keeps the suite short
SERVER_CONFIG = {"robot": {"backend": "fake"}, "world": {"room": {"seed": 1}}}


@contextmanager
def make_robot() -> Iterator[Robot]:
    """A naoqi robot connected to a fresh `naoloc serve` of the fake robot on loopback."""
    pytest.importorskip("qi", reason="transport libqi needs the qi package (naoloc[naoqi])")
    with (
        served(SERVER_CONFIG, TRANSPORT, speed=SPEED) as server,
        naoloc.connect(server.client_config(sim_service=True)) as robot,
    ):
        yield robot
