"""The visual map: features, vocabulary, Growing Cell Structures, landmarks, localization.

Public API::

    from naoloc.mapping import VisualMap, Estimate, build_map, load_map

    vmap = build_map(keyframes, cfg.map, meta={"origin_room_pose": [1.0, 1.0, 0.0]})
    vmap.save("room.npz")
    vmap = load_map("room.npz")
    est = vmap.localize([kf1, kf2], mode="verified")   # or mode="paper"
"""

from __future__ import annotations

from naoloc.mapping.localizer import Estimate
from naoloc.mapping.map import VisualMap, build_map
from naoloc.mapping.mapfile import load_map

__all__ = ["Estimate", "VisualMap", "build_map", "load_map"]
