"""The visual map: features, vocabulary, Growing Cell Structures, landmarks, localization.

Public API::

    from naoloc.mapping import Estimate, LocalizeMode, VisualMap, build_map, load_map

    vmap = build_map(keyframes, cfg.map, meta={"origin_room_pose": [1.0, 1.0, 0.0]})
    vmap.save("room.npz")
    vmap = load_map("room.npz")
    est = vmap.localize([kf1, kf2], mode=LocalizeMode.VERIFIED)   # or "paper"

Layers (no import circles): ``data`` (MapData, plain) <- ``builder`` (Algorithm 4),
``localizer`` (Algorithm 5), ``mapfile`` (the .npz format) <- ``map`` (VisualMap: MapData
with those as methods, build_map, load_map).
"""

from __future__ import annotations

from naoloc.mapping.data import MapData
from naoloc.mapping.localizer import Estimate, LocalizeMode, LocalizeStrategy
from naoloc.mapping.map import VisualMap, build_map, load_map

__all__ = [
    "Estimate",
    "LocalizeMode",
    "LocalizeStrategy",
    "MapData",
    "VisualMap",
    "build_map",
    "load_map",
]
