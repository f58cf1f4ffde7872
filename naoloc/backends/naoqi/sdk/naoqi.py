"""``naoqi`` of the old NAOqi Python SDK, on Python 3 (see naoloc.backends.naoqi.oldsdk)."""

from __future__ import annotations

from naoloc.backends.naoqi.oldsdk import ALBroker, ALModule, ALProxy

__all__ = ["ALBroker", "ALModule", "ALProxy"]
