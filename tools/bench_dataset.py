"""Size, write and read time of a survey dataset: the chunked layout against version 1's.

Usage::

    .venv/bin/python tools/bench_dataset.py [--frames 300] [--repeats 3]

Writes the same seeded frames (320 x 240 BGR, JPEG 95) with
:class:`naoloc.data.dataset.DatasetWriter`
(a zstd chunk per frame, indexes, CRCs, fsync on close) and, as the baseline in the same
process, with the same writer and messages in version 1's layout (unchunked, no data-section
CRC), then reads both with :func:`naoloc.data.dataset.read_dataset` (which checks CRCs, sizes and
image headers). Prints file size (MB) and best-of-N write and read times (s).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from naoloc.data.dataset import DatasetWriter, read_dataset  # noqa: E402
from naoloc.geometry import Pose2D  # noqa: E402
from naoloc.robot.keyframe import CameraInfo, Keyframe  # noqa: E402


def frames(n: int) -> list[Keyframe]:
    """Seeded smooth images (JPEG-friendly like a room) with poses along a line."""
    import cv2

    rng = np.random.default_rng(0)
    out = []
    for i in range(n):
        small = rng.integers(0, 255, (24, 32, 3), dtype=np.uint8)
        image = cv2.resize(small, (320, 240), interpolation=cv2.INTER_CUBIC)
        pose = Pose2D(0.1 * i, 0.0, 0.0)
        truth = Pose2D(1.0 + 0.1 * i, 1.0, 0.0)
        out.append(Keyframe(image, pose, -1.57, 0.0, CameraInfo(), 0.5 * i, pose, truth))
    return out


def write_new(path: Path, kfs: list[Keyframe]) -> None:
    with DatasetWriter(path, config={}, meta={"origin_room_pose": [1.0, 1.0, 0.0]}) as w:
        for kf in kfs:
            w.write(kf)


def write_unchunked(path: Path, kfs: list[Keyframe]) -> None:
    """The same writer and messages in version 1's layout: unchunked, no data-section CRC."""
    import mcap.writer

    real = mcap.writer.Writer

    def old_layout(stream: object, **_: object) -> object:
        return real(stream, use_chunking=False, enable_crcs=True)  # type: ignore[arg-type]

    mcap.writer.Writer = old_layout  # type: ignore[assignment,misc]
    try:
        write_new(path, kfs)
    finally:
        mcap.writer.Writer = real  # type: ignore[misc]


def best(fn: object, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()  # type: ignore[operator]
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    kfs = frames(args.frames)
    folder = Path(tempfile.mkdtemp(prefix="naoloc-bench-dataset-"))
    rows = []
    layouts = (("unchunked (baseline)", write_unchunked), ("chunked zstd", write_new))
    for name, writer in layouts:
        path = folder / f"{name.split()[0]}.mcap"
        w_s = best(lambda p=path, wr=writer: wr(p, kfs), args.repeats)
        r_s = best(lambda p=path: read_dataset(p), args.repeats)
        rows.append((name, path.stat().st_size / 1e6, w_s, r_s))
    print(f"{args.frames} frames, best of {args.repeats}")
    print(f"{'layout':<26} {'MB':>7} {'write s':>8} {'read s':>7}")
    for name, mb, w_s, r_s in rows:
        print(f"{name:<26} {mb:7.2f} {w_s:8.3f} {r_s:7.3f}")
    base, new = rows
    print(f"ratio new/baseline: size {new[1] / base[1]:.2f}, write {new[2] / base[2]:.2f}, "
          f"read {new[3] / base[3]:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
