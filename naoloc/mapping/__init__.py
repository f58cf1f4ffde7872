"""The visual map: built from a survey (Algorithm 4 and the geometry beside it).

Public API::

    from naoloc.mapping import VisualMap, build_map, load_map

    vmap = build_map(keyframes, cfg.map, meta={"origin_room_pose": [1.0, 1.0, 0.0]})
    vmap.save("room.npz")
    vmap = load_map("room.npz")

Localizing in a map is :mod:`naoloc.localization`'s. Layers (no import circles): ``data``
(MapData, plain) <- ``builder`` (Algorithm 4), ``mapfile`` (the .npz format) <- ``map``
(VisualMap: MapData with those as methods, build_map, load_map) <- ``from_survey`` (a
survey dataset to a map).
"""

from __future__ import annotations

from naoloc.mapping.data import MapData
from naoloc.mapping.map import VisualMap, build_map, load_map

__all__ = ["MapData", "VisualMap", "build_map", "load_map"]
