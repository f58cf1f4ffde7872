"""Validation of map files before anything in them is trusted (see naoloc.mapping.mapfile).

Order of the checks, cheapest and most dangerous first:

1. The zip directory: the file size, the member names (exactly the map's arrays, each once),
   the compression methods (stored or deflate) and every member's DECLARED uncompressed size
   are checked before one byte is inflated, so a zip bomb is refused from its directory
   (Python's zipfile never inflates a member past its declared size, and checks its CRC).
2. Each member's ``.npy`` header: the dtype must be the one the writer uses (never an object
   dtype), and the header's shape times the item size must be exactly the member's declared
   size, so a header cannot make numpy allocate more than the directory promised.
3. The metadata JSON: its size, its nesting depth (a deeply nested document is refused
   before the JSON parser recurses), its structure and the types of its fields.
4. The arrays: finiteness (NaN only in the whole rows where the format means "none", and
   there only when the rest of the map agrees: a neuron without a pose wins no wall
   picture, has no view direction, and some neuron has a pose), value ranges, shapes
   consistent with each other and with the metadata (feature kind, descriptor width,
   vocabulary size, binary words of 0/1 bits).

Every failure is a :class:`~naoloc.errors.MapFormatError` with one line naming the file
and the problem.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np

from naoloc.errors import MapFormatError
from naoloc.perception.features import DESCRIPTOR_WIDTH, FEATURE_KINDS
from naoloc.safe_yaml import open_regular

#: Largest map file accepted, and largest total of its members' uncompressed sizes, bytes.
#: The largest map the config allows (5000 neurons, 4096 words, thousands of images) is
#: well below; a bomb is refused from the zip directory before anything is inflated.
MAX_MAP_BYTES = 384 * 1024 * 1024
#: Largest metadata JSON, bytes, and its deepest nesting of objects and lists.
MAX_META_BYTES = 4 * 1024 * 1024
MAX_META_DEPTH = 32
_NPY_MAX_HEADER = 10000

_F4, _F8, _I8, _U1 = np.dtype("<f4"), np.dtype("<f8"), np.dtype("<i8"), np.dtype("|u1")
#: name -> (accepted dtypes, ndim), as naoloc.mapping.mapfile writes them.
ARRAYS: dict[str, tuple[tuple[np.dtype[Any], ...], int]] = {
    "vocab_centres": ((_F4,), 2),
    "vocab_idf": ((_F8,), 1),
    "gcs_weights": ((_F8,), 2),
    "gcs_triangles": ((_I8,), 2),
    "neuron_poses": ((_F8,), 2),
    "neuron_views": ((_F8,), 1),
    "keyframe_poses": ((_F8,), 2),
    "refined_poses": ((_F8,), 2),
    "keyframe_heads": ((_F8,), 2),
    "keyframe_cameras": ((_F8,), 2),
    "histograms": ((_F8,), 2),
    "winners": ((_I8,), 1),
    "kp_offsets": ((_I8,), 1),
    "kp_xy": ((_F4,), 2),
    "kp_desc": ((_U1, _F4), 2),
    "kp_points": ((_F8,), 2),
    "meta_json": ((_U1,), 1),
}


def fail(name: str, why: str) -> MapFormatError:
    """The one-line error for map file ``name``."""
    return MapFormatError(f"{name}: not a valid naoloc map: {why}")


def read_members(source: str | Path | bytes) -> tuple[dict[str, np.ndarray], str]:
    """Every array of a map file, each checked against the zip directory before reading.

    Args:
        source: A path or the file's bytes.

    Returns:
        The arrays by name and the name to use in messages.

    Raises:
        MapFormatError: A missing, oversized, foreign, truncated or inconsistent file.
    """
    name = "<bytes>" if isinstance(source, bytes) else str(source)
    if isinstance(source, bytes):
        size = len(source)
        stream: IO[bytes] = io.BytesIO(source)
    else:
        stream = open_regular(Path(source), "map file", MapFormatError)
        size = os.fstat(stream.fileno()).st_size
    with stream:
        return _read_zip(stream, size, name)


def _read_zip(stream: IO[bytes], size: int, name: str) -> tuple[dict[str, np.ndarray], str]:
    if size > MAX_MAP_BYTES:
        raise fail(name, f"file of {size} bytes exceeds the {MAX_MAP_BYTES} byte limit")
    try:
        with zipfile.ZipFile(stream) as zf:
            infos = _check_directory(zf, name)
            return {key: _read_member(zf, info, key, name) for key, info in infos.items()}, name
    except MapFormatError:
        raise
    except IsADirectoryError:
        raise MapFormatError(f"{name}: is a folder, not a map file") from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, ValueError, OSError) as err:
        raise fail(name, f"{type(err).__name__}: {str(err)[:100]}") from None
    except (NotImplementedError, RuntimeError) as err:  # unsupported zip features, encryption
        raise fail(name, f"unsupported zip archive: {str(err)[:100]}") from None


def _check_directory(zf: zipfile.ZipFile, name: str) -> dict[str, zipfile.ZipInfo]:
    infos: dict[str, zipfile.ZipInfo] = {}
    total = 0
    for info in zf.infolist():
        key = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
        if key not in ARRAYS:
            raise fail(name, f"unexpected member {info.filename[:60]!r}")
        if key in infos:
            raise fail(name, f"member {info.filename!r} appears twice")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise fail(name, f"member {info.filename!r} uses compression {info.compress_type}")
        if info.flag_bits & 0x1:
            raise fail(name, f"member {info.filename!r} is encrypted")
        total += info.file_size
        if total > MAX_MAP_BYTES:
            raise fail(
                name,
                f"members declare more than {MAX_MAP_BYTES} bytes uncompressed "
                f"({info.filename!r} alone {info.file_size}): refused before inflating",
            )
        infos[key] = info
    missing = sorted(set(ARRAYS) - set(infos))
    if "meta_json" in missing:
        raise fail(name, "no metadata (meta_json)")
    if missing:
        raise fail(name, f"missing array {missing[0]}")
    return infos


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, name: str) -> np.ndarray:
    dtypes, ndim = ARRAYS[key]
    with zf.open(info) as f:
        try:
            version = np.lib.format.read_magic(f)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(
                    f, max_header_size=_NPY_MAX_HEADER
                )
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(
                    f, max_header_size=_NPY_MAX_HEADER
                )
            else:
                raise fail(name, f"array {key} has .npy version {version}")
        except ValueError as err:
            raise fail(name, f"array {key}: bad .npy header: {str(err)[:80]}") from None
        if dtype.hasobject or dtype not in dtypes:
            raise fail(name, f"array {key} has dtype {dtype}")
        if len(shape) != ndim:
            raise fail(name, f"array {key} has {len(shape)} dimensions, not {ndim}")
        count = math.prod(shape)
        header = f.tell()
        if header + count * dtype.itemsize != info.file_size:
            raise fail(name, f"array {key}: header shape {shape} does not match its size")
        buf = bytearray(count * dtype.itemsize)
        if f.readinto(buf) != len(buf) or f.read(1):  # type: ignore[attr-defined]
            raise fail(name, f"array {key} is truncated")
    flat = np.frombuffer(buf, dtype=dtype, count=count)
    return flat.reshape(shape, order="F") if fortran else flat.reshape(shape)


_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')
_BRACKET = re.compile(r"[\[\]{}]")


def _depth(text: str) -> int:
    """Deepest nesting of ``[`` and ``{`` in JSON text (brackets inside strings skipped).

    Stops counting once past MAX_META_DEPTH.
    """
    if text.count("[") + text.count("{") <= MAX_META_DEPTH:
        return 0
    depth = deepest = 0
    for m in _BRACKET.finditer(_STRING.sub("", text)):
        if m.group() in "[{":
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_META_DEPTH:
                break
        else:
            depth -= 1
    return deepest


def parse_meta(raw: np.ndarray, name: str) -> dict[str, Any]:
    """The metadata JSON of a map, size- and depth-checked before parsing."""
    if raw.size > MAX_META_BYTES:
        raise fail(name, f"metadata of {raw.size} bytes exceeds {MAX_META_BYTES}")
    try:
        text = raw.tobytes().decode("utf-8")
    except UnicodeDecodeError:
        raise fail(name, "metadata is not UTF-8") from None
    if _depth(text) > MAX_META_DEPTH:
        raise fail(name, f"metadata nested deeper than {MAX_META_DEPTH} levels")
    try:
        meta = json.loads(text, parse_constant=_no_constant)
    except (ValueError, RecursionError):
        raise fail(name, "metadata is not JSON") from None
    if not isinstance(meta, dict):
        raise fail(name, f"metadata is {type(meta).__name__}, not an object")
    return meta


def _no_constant(token: str) -> float:
    raise ValueError(f"{token} is not JSON")


def meta_field(meta: Mapping[str, Any], key: str, kind: type, name: str) -> Any:
    """``meta[key]``, which must exist and be of type ``kind`` (bool is no int)."""
    value = meta.get(key)
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        got = "missing" if key not in meta else type(value).__name__
        raise fail(name, f"metadata field {key!r} must be {kind.__name__}, got {got}")
    return value


def check_features(a: dict[str, np.ndarray], meta: dict[str, Any], name: str) -> str:
    """The feature kind of the metadata, checked against config, vocabulary and descriptors.

    Returns:
        The kind (``akaze``, ``orb`` or ``sift``).
    """
    features = meta_field(meta, "features", dict, name)
    kind = features.get("kind")
    if kind not in FEATURE_KINDS:
        raise fail(name, f"unknown feature kind {str(kind)[:20]!r}")
    config = meta_field(meta, "config", dict, name)
    if config.get("features", kind) != kind:
        raise fail(
            name,
            f"feature kind {kind!r} does not match its config's features "
            f"{str(config.get('features'))[:20]!r}",
        )
    vocab = meta_field(meta, "vocabulary", dict, name)
    binary = kind != "sift"
    if vocab.get("binary") is not binary:
        raise fail(name, f"vocabulary binary={vocab.get('binary')!r} does not fit {kind}")
    width = DESCRIPTOR_WIDTH[kind]
    desc, centres = a["kp_desc"], a["vocab_centres"]
    want = np.dtype("|u1") if binary else np.dtype("<f4")
    if desc.dtype != want or desc.shape[1] != width:
        raise fail(
            name,
            f"descriptors {desc.dtype} x {desc.shape[1]} do not fit feature kind {kind!r} "
            f"({want} x {width})",
        )
    if centres.shape[1] != (8 * width if binary else width):
        raise fail(name, f"vocabulary words of {centres.shape[1]} values do not fit {kind!r}")
    if vocab.get("size") != centres.shape[0]:
        raise fail(name, f"vocabulary size {vocab.get('size')!r} is not {centres.shape[0]}")
    if binary and not np.isin(centres, (0.0, 1.0)).all():
        raise fail(name, "binary vocabulary words are not 0/1 bits")
    return str(kind)


def check_posed_winners(a: dict[str, np.ndarray], walls: int, name: str) -> None:
    """Every neuron that wins a wall picture (the first ``walls`` keyframes, whose poses
    make the neurons' poses) has a pose: NaN there is damage, not "none"."""
    winners = a["winners"][:walls]
    posed = ~np.isnan(a["neuron_poses"]).any(axis=1)
    if winners.size and not posed[winners].all():
        bad = int(winners[~posed[winners]][0])
        raise fail(name, f"neuron {bad} wins wall pictures but has no pose (NaN)")


def check_values(a: dict[str, np.ndarray], name: str) -> None:
    """Finiteness and value ranges of the arrays (shapes are checked before)."""
    finite = [
        "vocab_centres", "vocab_idf", "gcs_weights", "keyframe_poses", "refined_poses",
        "keyframe_heads", "keyframe_cameras", "histograms", "kp_xy", "kp_desc",
    ]  # fmt: skip
    for key in finite:
        if not np.isfinite(a[key]).all():
            raise fail(name, f"array {key} holds NaN or infinity")
    # NaN means "none" here (a neuron that wins no image, a keypoint without landmark), but
    # only for whole rows; infinity never.
    for key in ("neuron_poses", "kp_points", "neuron_views"):
        v = a[key].reshape(a[key].shape[0], -1)
        nan = np.isnan(v)
        if np.isinf(v).any() or (nan.any(axis=1) != nan.all(axis=1)).any():
            raise fail(name, f"array {key} holds infinity or partly NaN rows")
    posed = ~np.isnan(a["neuron_poses"]).any(axis=1)
    if not posed.any():
        raise fail(name, "no neuron has a pose (neuron_poses is all NaN)")
    if (np.isnan(a["neuron_views"]) == posed).any():
        raise fail(name, "neuron_views is NaN where neuron_poses is not, or the reverse")

    if (a["vocab_idf"] < 0).any():
        raise fail(name, "negative IDF")
    cams = a["keyframe_cameras"]
    ok = (
        (cams[:, 0] >= 1) & (cams[:, 1] >= 1) & (cams[:, 0] <= 10000) & (cams[:, 1] <= 10000)
        & (cams[:, 2] > 0) & (cams[:, 2] < math.pi) & (cams[:, 3] > 0) & (cams[:, 3] < math.pi)
        & np.isin(cams[:, 4], (0.0, 1.0))
    )  # fmt: skip
    if not ok.all():
        raise fail(name, f"keyframe camera {int(np.argmin(ok))} is not a camera")
    big = max(float(np.abs(a[k]).max(initial=0.0)) for k in ("keyframe_poses", "refined_poses"))
    if big > 1e4:
        raise fail(name, f"a keyframe pose {big:.3g} m or rad from the origin")
