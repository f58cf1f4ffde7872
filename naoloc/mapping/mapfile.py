"""The map file: one ``.npz`` (zip of ``.npy`` arrays) with JSON metadata inside.

Layout: every numeric array of :class:`~naoloc.mapping.data.MapData` under its own name,
plus ``meta_json``: a uint8 array holding UTF-8 JSON with the format tag and version, the
feature parameters, the training config, the user metadata, the timings and a SHA-256
checksum over every array (name, dtype, shape and bytes). Files are written
deterministically (stored, fixed timestamps), so a map round-trips bit for bit.

Reading never unpickles and parses JSON only: nothing in a file is ever executed. Every
member is validated before it is trusted (naoloc.mapping.mapcheck: sizes from the zip
directory before inflating, dtypes, finiteness, shapes against each other and the metadata).
Any truncated, foreign, tampered, corrupt, oversized or newer-version file raises
:class:`~naoloc.errors.MapFormatError` with a one-line reason naming the file.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

import naoloc.mapping.mapcheck as mapcheck
from naoloc.config import MapConfig
from naoloc.errors import MapFormatError, NaolocError
from naoloc.mapping.data import MapData
from naoloc.mapping.gcs import GCSNetwork
from naoloc.mapping.vocabulary import Vocabulary

FORMAT_TAG = "naoloc-map"
# 2: the feature parameters always name akaze_threshold and min_keypoints; a survey's meta
# with head_yaw also has picture_yaw. Older files are read through :func:`_migrate`.
FORMAT_VERSION = 4
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


# The arrays of a map file, each under the name of its MapData field.
_ARRAY_FIELDS = (
    "neuron_poses", "neuron_views", "keyframe_poses", "refined_poses", "keyframe_heads",
    "keyframe_cameras", "histograms", "winners", "kp_offsets", "kp_xy", "kp_desc", "kp_points",
)  # fmt: skip


def _arrays_of(vmap: MapData) -> dict[str, np.ndarray]:
    return {
        "vocab_centres": vmap.vocabulary.centres,
        "vocab_idf": vmap.vocabulary.idf,
        "gcs_weights": vmap.gcs.weights,
        "gcs_triangles": vmap.gcs.triangles,
        **{name: getattr(vmap, name) for name in _ARRAY_FIELDS},
    }


def checksum(arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 hex digest over the arrays' names, dtypes, shapes and bytes (sorted by name)."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def map_bytes(vmap: MapData) -> bytes:
    """The map file's bytes (deterministic for a given map)."""
    arrays = {k: np.ascontiguousarray(v) for k, v in _arrays_of(vmap).items()}
    meta = {
        "format": FORMAT_TAG,
        "version": FORMAT_VERSION,
        "features": vmap.feature_params,
        "vocabulary": {"binary": vmap.vocabulary.binary, "size": vmap.vocabulary.size},
        "gcs": {
            "inserted": vmap.gcs.inserted,
            "removed": vmap.gcs.removed,
            "steps": vmap.gcs.steps,
        },
        "config": vmap.config.model_dump(mode="json"),
        "meta": vmap.meta,
        "timings": vmap.timings,
        "checksum": checksum(arrays),
    }
    text = json.dumps(meta, sort_keys=True, allow_nan=False).encode("utf-8")
    arrays["meta_json"] = np.frombuffer(text, dtype=np.uint8)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_STORED) as zf:
        for name in sorted(arrays):
            member = io.BytesIO()
            np.lib.format.write_array(member, arrays[name], allow_pickle=False)
            zf.writestr(zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_TIME), member.getvalue())
    return buf.getvalue()


def save_map(vmap: MapData, path: str | Path) -> None:
    """Write a map file.

    Raises:
        NaolocError: When the file cannot be written or the metadata is not JSON-able.
    """
    try:
        data = map_bytes(vmap)
    except (TypeError, ValueError) as err:
        raise NaolocError(f"map metadata is not JSON-able: {err}") from None
    target = Path(path)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, target)  # atomic: an existing map is never left half-written
    except OSError as err:
        tmp.unlink(missing_ok=True)
        raise NaolocError(f"{path}: cannot write map file: {err.strerror or err}") from None


def _check(arrays: dict[str, np.ndarray], name: str) -> dict[str, Any]:
    meta = mapcheck.parse_meta(arrays["meta_json"], name)
    if meta.get("format") != FORMAT_TAG:
        raise _fail(name, f"format tag is not {FORMAT_TAG!r}")
    version = meta.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _fail(name, f"bad format version {str(version)[:20]!r}")
    if version > FORMAT_VERSION:
        raise MapFormatError(
            f"{name}: map format version {version} is newer than this naoloc reads "
            f"({FORMAT_VERSION}); upgrade naoloc"
        )
    body = {k: v for k, v in arrays.items() if k != "meta_json"}
    if meta.get("checksum") != checksum(body):
        raise _fail(name, "checksum mismatch (the file was modified)")
    return meta


def _migrate(meta: dict[str, Any]) -> None:
    """Bring an older file's metadata to the current format, in place (the one place that
    knows the older formats; checked afterwards like a current file's).

    - 1 -> 2: maps from before the adaptive A-KAZE threshold did not name it (it was off:
      ``min_keypoints`` 0, the OpenCV threshold 0.001); maps from before the survey's
      look-ahead took their pictures where the head pointed (``picture_yaw = head_yaw``).
    - 2 -> 3: the map's config no longer tunes a localizer (``tuning.localizer``): the
      localization filter's tuning is the robot's (``localize.filter``).
    - 3 -> 4: the survey start's heading gate (``tuning.wall_poses.start_gate_rad``) gave way
      to two sigmas (``start_view_std_rad``, ``start_frames_std_rad``; their defaults).
    """
    if meta["version"] < 2:
        features = meta["features"]
        features.setdefault("akaze_threshold", 0.001)
        features.setdefault("min_keypoints", 0)
        user = meta.get("meta")
        if isinstance(user, dict) and "head_yaw" in user:
            user.setdefault("picture_yaw", user["head_yaw"])
    if meta["version"] < 3:
        tuning = (
            meta.get("config", {}).get("tuning") if isinstance(meta.get("config"), dict) else None
        )
        if isinstance(tuning, dict):
            tuning.pop("localizer", None)
    if meta["version"] < 4:
        config = meta.get("config")
        tuning = config.get("tuning") if isinstance(config, dict) else None
        walls = tuning.get("wall_poses") if isinstance(tuning, dict) else None
        if isinstance(walls, dict):
            walls.pop("start_gate_rad", None)


def _fail(path: str, why: str) -> MapFormatError:
    return mapcheck.fail(path, why)


def _consistent(a: dict[str, np.ndarray], name: str) -> None:
    n = a["keyframe_poses"].shape[0]
    k, v = a["gcs_weights"].shape[0], a["vocab_centres"].shape[0]
    m = a["kp_xy"].shape[0]
    off = a["kp_offsets"]
    rules = [
        (a["keyframe_poses"].shape[1] == 3, "keyframe_poses must be (N, 3)"),
        (a["keyframe_heads"].shape == (n, 2), "keyframe_heads must be (N, 2)"),
        (a["refined_poses"].shape == (n, 3), "refined_poses must be (N, 3)"),
        (a["keyframe_cameras"].shape == (n, 5), "keyframe_cameras must be (N, 5)"),
        (a["histograms"].shape == (n, v), "histograms must be (N, vocabulary)"),
        (a["vocab_idf"].shape == (v,), "vocab_idf must be (vocabulary,)"),
        (a["gcs_weights"].shape[1] == v, "gcs_weights must be (K, vocabulary)"),
        (a["neuron_poses"].shape == (k, 3), "neuron_poses must be (K, 3)"),
        (a["neuron_views"].shape == (k,), "neuron_views must be (K,)"),
        (a["winners"].shape == (n,), "winners must be (N,)"),
        (n == 0 or (a["winners"].min() >= 0 and a["winners"].max() < k), "winner out of range"),
        (a["gcs_triangles"].shape[1] == 3, "gcs_triangles must be (T, 3)"),
        (
            a["gcs_triangles"].size == 0
            or (a["gcs_triangles"].min() >= 0 and a["gcs_triangles"].max() < k),
            "triangle cell out of range",
        ),
        (off.shape == (n + 1,), "kp_offsets must be (N + 1,)"),
        (
            off.size > 0 and off[0] == 0 and off[-1] == m and bool(np.all(np.diff(off) >= 0)),
            "bad kp_offsets",
        ),
        (a["kp_xy"].shape[1] == 2, "kp_xy must be (M, 2)"),
        (a["kp_desc"].shape[0] == m, "kp_desc must have M rows"),
        (a["kp_points"].shape == (m, 3), "kp_points must be (M, 3)"),
        (n > 0 and k >= 3, "empty map"),
    ]
    for ok, why in rules:
        if not ok:
            raise _fail(name, why)


def read_map(source: str | Path | bytes) -> MapData:
    """Read a map file (or its bytes).

    Raises:
        MapFormatError: On a missing, truncated, foreign, tampered or newer-version file.
    """
    arrays, name = mapcheck.read_members(source)
    meta = _check(arrays, name)
    _consistent(arrays, name)
    mapcheck.check_values(arrays, name)
    kind = mapcheck.check_features(arrays, meta, name)
    _migrate(meta)
    features = meta["features"]
    if (
        not isinstance(features.get("max_features", 0), int)
        or not isinstance(features.get("akaze_threshold"), (int, float))
        or not isinstance(features.get("min_keypoints"), int)
        or not 0 <= features["min_keypoints"] <= 100_000
    ):
        raise _fail(name, "bad feature parameters")
    try:
        config = MapConfig.model_validate(meta["config"])
    except ValueError as err:
        raise _fail(name, f"bad map config: {str(err).splitlines()[0][:80]}") from None
    g = mapcheck.meta_field(meta, "gcs", dict, name)
    counts = [g.get(k) for k in ("inserted", "removed", "steps")]
    if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts):
        raise _fail(name, "bad GCS counters in the metadata")
    user_meta = mapcheck.meta_field(meta, "meta", dict, name) if "meta" in meta else {}
    timings_raw = mapcheck.meta_field(meta, "timings", dict, name) if "timings" in meta else {}
    if not all(
        isinstance(t, (int, float)) and not isinstance(t, bool) for t in timings_raw.values()
    ):
        raise _fail(name, "bad timings in the metadata")
    timings = {str(k): float(t) for k, t in timings_raw.items()}
    far = user_meta.get("far_pictures", 0)
    if isinstance(far, bool) or not isinstance(far, int) or not 0 <= far < len(arrays["winners"]):
        raise _fail(name, f"far_pictures {str(far)[:20]!r} is not a count below the keyframes'")
    mapcheck.check_posed_winners(arrays, len(arrays["winners"]) - far, name)
    binary = kind != "sift"
    gcs = GCSNetwork(
        arrays["gcs_weights"], arrays["gcs_triangles"], int(counts[0]), int(counts[1]),
        int(counts[2]),
    )  # fmt: skip
    return MapData(
        config=config,
        meta=user_meta,
        feature_params=dict(features),
        vocabulary=Vocabulary(arrays["vocab_centres"], arrays["vocab_idf"], binary),
        gcs=gcs,
        timings=timings,
        **{name: arrays[name] for name in _ARRAY_FIELDS},
    )
