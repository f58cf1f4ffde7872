"""The corrupt-dataset corpus (tests/corrupt_datasets.py), generated and run on every run.

Each file must make ``naoloc build-map -d FILE`` exit 1 with exactly one stderr line that
names the file and the problem, no traceback, and no library noise (libpng and libjpeg
print to file descriptor 2, so this captures at that level). A few also run in a real
subprocess, whose peak memory is read with ``os.wait4``: the bombs stay under 500 MB.
Bytes of a real dataset flipped in turn are one-line errors too (CRCs everywhere).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from corrupt_datasets import corpus, craft, record, record_offsets

from naoloc.app.cli import main
from naoloc.data.dataset import read_dataset
from naoloc.errors import DatasetError

# Runs argv, prints its exit code, output and peak resident memory (ru_maxrss: KiB on Linux).
_MEASURE = """
import json, resource, subprocess, sys
r = subprocess.run(sys.argv[1:], capture_output=True, text=True)
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
print(json.dumps({"code": r.returncode, "out": r.stdout, "err": r.stderr, "peak_mb": peak}))
"""
CONFIG = {"robot": {"backend": "fake"}, "map": {"neurons": 40, "epochs": 5}}


@pytest.fixture(scope="module")
def cases(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[str, Path, str]]:
    return corpus(tmp_path_factory.mktemp("corpus"))


@pytest.fixture()
def cfg(tmp_path: Path) -> Path:
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(CONFIG))
    return path


def test_every_corrupt_file_is_one_line_through_the_cli(
    cases: list[tuple[str, Path, str]], cfg: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    assert len(cases) >= 50
    out_map = tmp_path / "m.npz"
    failures = []
    for name, path, expected in cases:
        code = main(["build-map", "-c", str(cfg), "-d", str(path), "-o", str(out_map)])
        err = capfd.readouterr().err
        good = (
            code == 1
            and err.count("\n") == 1
            and err.startswith("naoloc build-map: error: ")
            and str(path) in err
            and expected in err
            and "Traceback" not in err
        )
        if not good:
            failures.append(f"{name}: exit {code}, stderr {err!r}, expected {expected!r}")
    assert not failures, "\n".join(failures)
    assert not out_map.exists() and not (tmp_path / "m.config.yaml").exists()


@pytest.mark.parametrize(
    "name",
    ["flip-0.5", "png-bomb", "png-bomb-camera", "jpeg-bomb", "zstd-bomb", "chunk-declares-1gib",
     "meta-deep", "record-deep", "hfov-0"],
)  # fmt: skip
def test_real_process_rejects_in_one_line_under_500_mb(
    cases: list[tuple[str, Path, str]], cfg: Path, tmp_path: Path, name: str
) -> None:
    path, expected = next((p, e) for n, p, e in cases if n == name)
    argv = [sys.executable, "-m", "naoloc.app.cli", "build-map", "-c", str(cfg), "-d", str(path),
            "-o", str(tmp_path / "m.npz")]  # fmt: skip
    # A small wrapper process runs the CLI: a child forked from this (large) test process
    # would count this process's pages in its peak memory until it execs.
    wrapper = subprocess.run(
        [sys.executable, "-c", _MEASURE, *argv], capture_output=True, text=True, timeout=120
    )
    result = json.loads(wrapper.stdout)
    code, out, err, peak_mb = result["code"], result["out"], result["err"], result["peak_mb"]
    assert code == 1, err
    assert err.count("\n") == 1 and expected in err and "Traceback" not in err, err
    assert out == ""
    assert peak_mb < 500, f"{name}: peak resident memory {peak_mb:.0f} MB"


@pytest.mark.slow
def test_flipped_bytes_of_a_real_dataset_are_one_line_errors(tmp_path: Path) -> None:
    from corrupt_datasets import _valid

    valid = _valid(tmp_path)
    raw = valid.read_bytes()
    assert len(read_dataset(valid).keyframes) == 3
    bad = tmp_path / "flipped.mcap"
    missed = []
    # Every byte of the first and last 256 (magic, header, metadata, summary, footer) and
    # every 13th in between (chunks): about 1,400 files.
    ends = [*range(256), *range(len(raw) - 256, len(raw))]
    for at in sorted({*ends, *range(256, len(raw) - 256, 13)}):
        bad.write_bytes(raw[:at] + bytes([raw[at] ^ 0x01]) + raw[at + 1 :])
        try:
            read_dataset(bad)
        except DatasetError as err:
            if "\n" in str(err) or str(bad) not in str(err):
                missed.append(f"byte {at}: {err}")
        else:
            missed.append(f"byte {at}: accepted")
    assert not missed, f"{len(missed)} of {len(raw)}: " + "; ".join(missed[:5])


def test_version_1_unchunked_datasets_still_read(tmp_path: Path) -> None:
    path = craft(tmp_path / "old.mcap", version="1", chunked=False, status=False)
    offsets = record_offsets(path.read_bytes())
    assert 6 not in offsets  # no chunk: the old layout
    data = read_dataset(path)
    assert data.complete and len(data.keyframes) == 3
    assert data.keyframes[1].pose.x == pytest.approx(0.2)
    # An old file whose writer died: everything before the cut, marked incomplete.
    raw = path.read_bytes()
    cut = tmp_path / "old-cut.mcap"
    cut.write_bytes(raw[: offsets[3][-1] + 20])  # inside the last keyframe message... or later
    partial = read_dataset(cut)
    assert not partial.complete and 1 <= len(partial.keyframes) <= 3


def test_a_truncated_dataset_reads_as_partial_not_complete(tmp_path: Path) -> None:
    from corrupt_datasets import _valid

    raw = _valid(tmp_path).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(raw[: len(raw) // 2])
    data = read_dataset(cut)
    assert not data.complete and data.meta["complete"] is False
    assert 0 < len(data.keyframes) < 3


def test_a_crafted_dataset_is_valid_when_nothing_is_wrong(tmp_path: Path) -> None:
    data = read_dataset(craft(tmp_path / "ok.mcap", [record(i) for i in range(4)]))
    assert data.complete and len(data.keyframes) == 4
    assert data.keyframes[0].image.shape == (24, 32, 3)
