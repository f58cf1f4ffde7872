"""A corpus of corrupt map files, generated here on every run, each refused in one line.

Every file is checked twice: ``load_map`` raises one-line :class:`MapFormatError` naming
the file, and ``naoloc localize -c CFG -m BAD.npz`` exits non-zero with exactly one stderr
line and no traceback. The zip bomb (a 2 GB member in a 2 MB file) is also run under
``os.wait4`` to bound the CLI's peak memory.
"""

from __future__ import annotations

import io
import json
import os
import struct
import subprocess
import sys
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from naoloc.config import MapConfig
from naoloc.errors import MapFormatError
from naoloc.mapping import build_map, load_map
from naoloc.mapping.mapfile import checksum, map_bytes
from tests.unit.test_mapping_file import synthetic_keyframes


def _one_infinite_row(a: np.ndarray) -> np.ndarray:
    """The landmarks with the first row infinite (whether or not it was triangulated)."""
    out = a.copy()
    out[0] = np.inf
    return out


@pytest.fixture(scope="module")
def good() -> bytes:
    cfg = MapConfig(neurons=8, epochs=5, vocabulary_size=32)
    return map_bytes(build_map(synthetic_keyframes(), cfg, meta={"room_size_m": [6.0, 6.0]}))


def _members(data: bytes) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        arrays = {k: np.array(z[k]) for k in z.files}
    meta = json.loads(arrays.pop("meta_json").tobytes())
    return arrays, meta


def _zip(members: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as zf:
        for name, raw in members.items():
            zf.writestr(name, raw)
    return out.getvalue()


def _npy(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, a, allow_pickle=True)
    return buf.getvalue()


def forge(
    data: bytes,
    arrays: Callable[[dict[str, np.ndarray]], None] | None = None,
    meta: Callable[[dict[str, Any]], None] | None = None,
    *,
    meta_text: str | None = None,
) -> bytes:
    """A map edited as an attacker would: arrays and metadata changed, checksum recomputed."""
    a, m = _members(data)
    if arrays is not None:
        arrays(a)
    if meta is not None:
        meta(m)
    m["checksum"] = checksum(a)
    text = meta_text if meta_text is not None else json.dumps(m)
    raw = {f"{k}.npy": _npy(v) for k, v in a.items()}
    raw["meta_json.npy"] = _npy(np.frombuffer(text.encode(), np.uint8))
    return _zip(raw)


def zip_bomb(data: bytes, member: str = "gcs_weights", gigabytes: float = 2.0) -> bytes:
    """The map with one member replaced by a deflate stream of ``gigabytes`` of zeros.

    The stream is a valid ``.npy`` of that size (header, then zeros), built from one
    full-flushed 1 MiB deflate block repeated, so making it costs no inflating. Its CRC is
    not computed (it would take reading 2 GB); a reader finds that out only after inflating.
    """
    mib = 2**20
    blocks = int(gigabytes * 1024)
    header = io.BytesIO()
    count = (blocks * mib - 128) // 8
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (count,)}
    )
    head = header.getvalue()
    size = len(head) + 8 * count
    comp = zlib.compressobj(9, zlib.DEFLATED, -15)
    first = comp.compress(head + bytes(mib - len(head))) + comp.flush(zlib.Z_FULL_FLUSH)
    block = comp.compress(bytes(mib)) + comp.flush(zlib.Z_FULL_FLUSH)
    rest = size - mib
    stream = first + block * (rest // mib) + comp.compress(bytes(rest % mib)) + comp.flush()
    others = {n: raw for n, raw in _raw_members(data).items() if n != f"{member}.npy"}
    out = io.BytesIO()
    central = b""
    entries = [(n, raw, zipfile.ZIP_STORED, len(raw), zlib.crc32(raw)) for n, raw in others.items()]
    entries.append((f"{member}.npy", stream, zipfile.ZIP_DEFLATED, size, 0))
    for name, payload, method, usize, crc in entries:
        offset = out.tell()
        fname = name.encode()
        out.write(struct.pack("<4s5H3L2H", b"PK\x03\x04", 20, 0, method, 0, 33,
                              crc, len(payload), usize, len(fname), 0))  # fmt: skip
        out.write(fname + payload)
        central += struct.pack("<4s6H3L5H2L", b"PK\x01\x02", 20, 20, 0, method, 0, 33,
                               crc, len(payload), usize, len(fname), 0, 0, 0, 0, 0,
                               offset) + fname  # fmt: skip
    start = out.tell()
    out.write(central)
    out.write(struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, len(entries), len(entries),
                          len(central), start, 0))  # fmt: skip
    return out.getvalue()


def _raw_members(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        return {n: zf.read(n) for n in zf.namelist()}


def _lying_npy() -> bytes:
    """A ``.npy`` whose header promises 80 GB while 16 bytes follow."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<f8", "fortran_order": False, "shape": (10**5, 10**5)}
    )
    return buf.getvalue() + bytes(16)


def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


def _set(key: str, fn: Callable[[np.ndarray], np.ndarray]) -> Callable[[dict[str, Any]], None]:
    def edit(a: dict[str, Any]) -> None:
        a[key] = fn(a[key])

    return edit


def _meta_set(path: tuple[str, ...], value: Any) -> Callable[[dict[str, Any]], None]:
    def edit(m: dict[str, Any]) -> None:
        d = m
        for k in path[:-1]:
            d = d[k]
        d[path[-1]] = value

    return edit


def _kind(kind: str) -> Callable[[dict[str, Any]], None]:
    """Metadata claiming another feature kind, in the features and in the config."""

    def edit(m: dict[str, Any]) -> None:
        m["features"]["kind"] = m["config"]["features"] = kind

    return edit


def _nan(a: np.ndarray) -> np.ndarray:
    return np.full_like(a, np.nan)


CORPUS: dict[str, tuple[Callable[[bytes], bytes], str]] = {
    "empty": (lambda g: b"", "BadZipFile"),
    "not_a_zip": (lambda g: b"hello, world" * 50, "BadZipFile"),
    "truncated": (lambda g: g[: len(g) // 2], "not a valid naoloc map"),
    "zip_bomb": (lambda g: zip_bomb(g), "refused before inflating"),
    "lying_header": (
        lambda g: _zip({**_raw_members(g), "gcs_weights.npy": _lying_npy()}),
        "gcs_weights: header shape (100000, 100000) does not match its size",
    ),
    "object_dtype": (
        lambda g: _zip({**_raw_members(g), "winners.npy": _npy(np.array([None], dtype=object))}),
        "dtype object",
    ),
    "float32_poses": (
        lambda g: forge(g, _set("keyframe_poses", lambda a: a.astype(np.float32))),
        "keyframe_poses has dtype float32",
    ),
    "extra_member": (lambda g: _zip({**_raw_members(g), "evil.npy": _npy(np.zeros(1))}), "evil"),
    "missing_member": (
        lambda g: _zip({n: r for n, r in _raw_members(g).items() if n != "kp_xy.npy"}),
        "missing array kp_xy",
    ),
    "nan_weights": (lambda g: forge(g, _set("gcs_weights", _nan)), "gcs_weights holds NaN"),
    "nan_poses": (lambda g: forge(g, _set("refined_poses", _nan)), "refined_poses holds NaN"),
    "nan_everywhere": (
        lambda g: forge(
            g, lambda a: a.update({k: _nan(v) for k, v in a.items() if v.dtype.kind == "f"})
        ),
        "holds NaN",
    ),
    "inf_landmark": (
        lambda g: forge(g, _set("kp_points", _one_infinite_row)),
        "kp_points holds infinity",
    ),
    "histogram_columns": (
        lambda g: forge(g, _set("histograms", lambda a: a[:, :-1].copy())),
        "histograms must be (N, vocabulary)",
    ),
    "vocabulary_size_meta": (
        lambda g: forge(g, meta=_meta_set(("vocabulary", "size"), 7)),
        "vocabulary size 7",
    ),
    "grey_words": (
        lambda g: forge(g, _set("vocab_centres", lambda a: a * 0.5)),
        "not 0/1 bits",
    ),
    "bad_camera": (
        lambda g: forge(g, _set("keyframe_cameras", lambda a: a * np.array([1, 1, 0, 1, 1]))),
        "keyframe camera 0",
    ),
    "kind_sift": (
        lambda g: forge(g, meta=_meta_set(("features", "kind"), "sift")),
        "feature kind 'sift' does not match its config's features 'akaze'",
    ),
    "kind_sift_both": (
        lambda g: forge(g, meta=_kind("sift")),
        "vocabulary binary=True does not fit sift",
    ),
    "kind_orb": (
        lambda g: forge(g, meta=_kind("orb")),
        "do not fit feature kind 'orb'",
    ),
    "meta_null": (lambda g: forge(g, meta_text="null"), "metadata is NoneType"),
    "features_null": (lambda g: forge(g, meta=_meta_set(("features",), None)), "'features'"),
    "gcs_null": (lambda g: forge(g, meta=_meta_set(("gcs",), None)), "'gcs'"),
    "user_meta_null": (lambda g: forge(g, meta=_meta_set(("meta",), None)), "'meta'"),
    "timings_null": (lambda g: forge(g, meta=_meta_set(("timings",), None)), "'timings'"),
    "config_null": (lambda g: forge(g, meta=_meta_set(("config",), None)), "'config'"),
    "version_string": (lambda g: forge(g, meta=_meta_set(("version",), "1")), "version"),
    "deep_json": (
        lambda g: forge(
            g,
            meta_text=json.dumps({"format": "naoloc-map"})[:-1]
            + ', "meta": '
            + _nested(100000)
            + "}",
        ),
        "nested deeper",
    ),
    "nan_json": (
        lambda g: forge(g, meta=_meta_set(("timings", "total_s"), float("nan"))),
        "metadata is not JSON",
    ),
    "huge_meta": (
        lambda g: forge(g, meta=_meta_set(("meta", "pad"), "x" * (5 * 2**20))),
        "metadata of",
    ),
}


@pytest.fixture(scope="module")
def corpus(good: bytes, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("corrupt_maps")
    out = {}
    for name, (make, _why) in CORPUS.items():
        path = folder / f"{name}.npz"
        path.write_bytes(make(good))
        out[name] = path
    return out


def test_the_good_map_loads(good: bytes, tmp_path: Path) -> None:
    path = tmp_path / "good.npz"
    path.write_bytes(good)
    assert load_map(path).images == 12
    assert load_map(forge(good)).images == 12  # forging alone (same content) is harmless


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_load_map_refuses_in_one_line(name: str, corpus: dict[str, Path]) -> None:
    with pytest.raises(MapFormatError) as err:
        load_map(corpus[name])
    text = str(err.value)
    assert "\n" not in text and text.startswith(str(corpus[name]))
    assert CORPUS[name][1] in text, text


@pytest.mark.slow
def test_localize_cli_refuses_every_corrupt_map(corpus: dict[str, Path], tmp_path: Path) -> None:
    cfg = tmp_path / "fake.yaml"
    cfg.write_text("robot: {backend: fake}\n")
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    procs = {}
    for name, path in corpus.items():
        cmd = [sys.executable, "-m", "naoloc.app.cli", "localize", "-c", str(cfg), "-m", str(path)]
        procs[name] = subprocess.Popen(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
    for name, proc in procs.items():
        out, err = proc.communicate()
        lines = err.strip().splitlines()
        assert proc.returncode != 0, (name, out, err)
        assert len(lines) == 1 and "Traceback" not in err, (name, err)
        assert str(corpus[name]) in lines[0] and CORPUS[name][1] in lines[0], (name, err)
        assert out == "", (name, out)


# Started from a small Python so that the child's peak RSS does not count the memory of the
# test process it was forked from (Linux keeps the pre-exec peak in ru_maxrss).
_PEAK = """
import os, subprocess, sys
proc = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
_pid, status, usage = os.wait4(proc.pid, 0)
print(os.waitstatus_to_exitcode(status), usage.ru_maxrss, proc.stderr.read().decode().strip())
"""


def test_the_zip_bomb_is_refused_without_inflating(corpus: dict[str, Path], tmp_path: Path) -> None:
    cfg = tmp_path / "fake.yaml"
    cfg.write_text("robot: {backend: fake}\n")
    cmd = [sys.executable, "-m", "naoloc.app.cli", "localize", "-c", str(cfg), "-m"]
    baseline = subprocess.run(
        [sys.executable, "-c", _PEAK, *cmd, str(corpus["not_a_zip"])],
        capture_output=True, text=True, check=True,
    ).stdout.split(maxsplit=2)  # fmt: skip
    bomb = subprocess.run(
        [sys.executable, "-c", _PEAK, *cmd, str(corpus["zip_bomb"])],
        capture_output=True, text=True, check=True,
    ).stdout.split(maxsplit=2)  # fmt: skip
    assert bomb[0] == "1" and "refused before inflating" in bomb[2], bomb
    # The 2 GiB member is never inflated: the bomb costs no more than a 600-byte junk file.
    peak_kb, base_kb = int(bomb[1]), int(baseline[1])
    assert peak_kb < 500 * 1024 and peak_kb < base_kb + 64 * 1024, (peak_kb, base_kb)
