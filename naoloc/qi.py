"""``import naoloc.qi as qi``: the qi-compatible module, without libqi, on any OS and Python.

The implementation lives with the NAOqi backend (:mod:`naoloc.backends.naoqi.qi`); this is
its public name. See that module for what it offers.
"""

from __future__ import annotations

from typing import Any

from naoloc.backends.naoqi import qi as _impl
from naoloc.backends.naoqi.qi import *  # noqa: F403 - the public re-export of qi's names
from naoloc.backends.naoqi.qi import __all__ as __all__


def __getattr__(name: str) -> Any:
    """Every other name of the implementation (qi's module has more than ``__all__``)."""
    return getattr(_impl, name)
