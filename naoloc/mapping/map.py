"""The public map object: :class:`VisualMap`, the map's data with its verbs as methods.

:class:`~naoloc.mapping.data.MapData` is the plain data; building
(naoloc.mapping.builder), localizing (naoloc.localization) and the file format
(naoloc.mapping.mapfile) are functions of it that import nothing of each other. This
module sits above them all and adds them as methods, so ``vmap.extract(...)`` and
``vmap.save(...)`` work without any of those modules importing this one (no import
circles).

Frames: as :class:`~naoloc.mapping.data.MapData` (the map frame, metres and radians).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from naoloc.config import MapConfig
from naoloc.mapping.builder import ProgressFn, build_map_data, map_extractor, pinhole_features
from naoloc.mapping.data import MapData
from naoloc.mapping.landmarks import query_camera
from naoloc.mapping.mapfile import read_map, save_map
from naoloc.perception.features import FeatureExtractor, Features
from naoloc.robot.keyframe import Keyframe
from naoloc.robot.lens import Lens

__all__ = ["VisualMap", "build_map", "load_map"]


@dataclass(eq=False)
class VisualMap(MapData):
    """A learned room (see :class:`~naoloc.mapping.data.MapData` for the attributes),
    with extract and save as methods."""

    _extractor: FeatureExtractor | None = field(default=None, repr=False)

    @classmethod
    def of(cls, data: MapData, extractor: FeatureExtractor | None = None) -> VisualMap:
        """The map object of plain map data (the arrays are shared, not copied)."""
        values = {f.name: getattr(data, f.name) for f in dataclasses.fields(MapData)}
        return cls(**values, _extractor=extractor)

    def extractor(self) -> FeatureExtractor:
        """The feature extractor the map was built with (created once)."""
        if self._extractor is None:
            p = self.feature_params
            self._extractor = FeatureExtractor(
                p["kind"],
                int(p.get("max_features", 0)),
                float(p.get("akaze_threshold", 0.001)),
                int(p.get("min_keypoints", 0)),
            )
        return self._extractor

    def extract(self, queries: Sequence[Keyframe]) -> list[Features]:
        """Features of query images with the map's extractor, moved to the pinhole the map
        models when the survey recorded a distorting lens (``meta["lens"]``)."""
        ex = self.extractor()
        lens = Lens.from_dict(self.meta.get("lens"))  # the same robot's camera as the survey's
        return [pinhole_features(ex, q, query_camera(q), lens) for q in queries]

    def save(self, path: str | Path) -> None:
        """Write the map to one ``.npz`` file (see naoloc.mapping.mapfile)."""
        save_map(self, path)


def build_map(
    keyframes: Sequence[Keyframe],
    cfg: MapConfig,
    *,
    meta: dict[str, Any] | None = None,
    progress: ProgressFn | None = None,
    far: Sequence[tuple[int, Keyframe]] = (),
    wall_features: Sequence[Features] | None = None,
) -> VisualMap:
    """Algorithm 4 (see :func:`naoloc.mapping.builder.build_map_data`) as a :class:`VisualMap`.

    ``far``: the survey's far pictures with their stops (indices into ``keyframes``);
    ``wall_features``: the features of ``keyframes`` when already extracted with the map's
    extractor.

    Raises:
        DatasetError: When there are no keyframes, or a far picture's stop is not one.
    """
    extractor = map_extractor(cfg)
    data = build_map_data(
        keyframes,
        cfg,
        meta=meta,
        progress=progress,
        extractor=extractor,
        far=far,
        wall_features=wall_features,
    )
    return VisualMap.of(data, extractor)


def load_map(source: str | Path | bytes) -> VisualMap:
    """Read and validate a map file (or its bytes) (see naoloc.mapping.mapfile).

    Raises:
        MapFormatError: On a missing, truncated, foreign, tampered, corrupt or newer file.
    """
    return VisualMap.of(read_map(source))
