"""Nothing lost, nothing secret: interrupted and failed runs, signals, config copies, passwords.

- An interrupted survey (SIGINT or SIGTERM) keeps ``NAME.partial.mcap``, marked incomplete,
  beside an older complete ``NAME.mcap``, which stays byte for byte, as does its config copy.
- ``build-map`` started as a background job (SIGINT ignored by the shell) stops on SIGINT
  and SIGTERM with 130 / 143 and leaves the older map, PNG and config copy as they were.
- A failed ``build-map`` does not touch them either.
- ``robot.password`` reaches no file under the output folder, and no message.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.data.dataset import read_dataset

pytest.importorskip("naoloc.backends.fake")

SMALL = {
    "robot": {"backend": "fake"},
    # Exact odometry: a NAO's drifting survey walks into the wall of this small room, and
    # these tests are about outputs, not odometry.
    "world": {
        "room": {"size_m": [3.0, 3.0], "seed": 5, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
    },
    "survey": {"laps": 1, "step_m": 0.25, "wall_offset_m": 0.75},
    "map": {"neurons": 40, "epochs": 30, "vocabulary_size": 64},
    "go_home": {"tolerance_m": 0.15, "max_tries": 2},
}
SECRET = "hunter2-not-on-disk"


def _cfg(folder: Path, name: str = "cfg.yaml", **changes: object) -> Path:
    data = json.loads(json.dumps(SMALL))
    data.update(changes)
    path = folder / name
    path.write_text(yaml.safe_dump(data))
    return path


def _snapshot(*paths: Path) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in paths}


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "naoloc.app.cli", *args]


@pytest.mark.parametrize(
    ("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"]
)
@pytest.mark.slow
def test_interrupted_survey_keeps_the_complete_dataset_and_a_marked_partial(
    tmp_path: Path, sig: signal.Signals, code: int
) -> None:
    out = tmp_path / "s.mcap"
    assert main(["survey", "-c", str(_cfg(tmp_path)), "-o", str(out)]) == 0
    before = _snapshot(out, tmp_path / "s.config.yaml")
    # 20 laps (1200 frames, about 13 s): the signal after 5 frames never races the end.
    long = _cfg(tmp_path, "long.yaml", survey={"laps": 20, "step_m": 0.1, "wall_offset_m": 0.75})
    partial = tmp_path / "s.partial.mcap"
    proc = subprocess.Popen(
        _cli("survey", "-c", str(long), "-o", str(out)),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )
    try:
        deadline, frames = time.monotonic() + 60, 0
        while frames < 5 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
            if partial.exists():
                try:  # the file is being written: its tail may be half a chunk
                    frames = len(read_dataset(partial).keyframes)
                except Exception:
                    frames = 0
        assert proc.poll() is None, "the survey ended before it could be interrupted"
        t0 = time.monotonic()
        proc.send_signal(sig)
        _, err_bytes = proc.communicate(timeout=10)
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = err_bytes.decode()
    assert proc.returncode == code, err
    assert elapsed < 2.0, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "interrupted" in err and f"kept in {partial}" in err, err
    assert _snapshot(*before) == before  # the complete dataset and its config copy
    data = read_dataset(partial)
    assert not data.complete and data.meta["complete"] is False
    assert data.meta["reason"] == f"interrupted ({sig.name})"
    assert 5 <= len(data.keyframes) == data.meta["frames"] < 1200
    assert read_dataset(out).complete and len(read_dataset(out).keyframes) == 24


@pytest.fixture(scope="module")
def mapped(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """A 300-frame dataset and a map of it, with PNG and config copy."""
    tmp = tmp_path_factory.mktemp("mapped")
    cfg = _cfg(tmp, survey={"laps": 5, "step_m": 0.1, "wall_offset_m": 0.75})
    dataset, map_path = tmp / "s.mcap", tmp / "map.npz"
    assert main(["survey", "-c", str(cfg), "-o", str(dataset)]) == 0
    assert main(["build-map", "-c", str(cfg), "-d", str(dataset), "-o", str(map_path)]) == 0
    return cfg, dataset, map_path


def _map_files(map_path: Path) -> list[Path]:
    return [map_path, map_path.with_suffix(".png"), map_path.with_name("map.config.yaml")]


@pytest.mark.parametrize(
    ("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"]
)
@pytest.mark.slow
def test_background_build_map_stops_on_signals_and_keeps_the_old_map(
    mapped: tuple[Path, Path, Path], tmp_path: Path, sig: signal.Signals, code: int
) -> None:
    _, dataset, map_path = mapped
    before = _snapshot(*_map_files(map_path))
    slow = _cfg(tmp_path, map={"neurons": 300, "epochs": 10000, "vocabulary_size": 64})
    # `&` in a non-interactive shell starts the job with SIGINT ignored (POSIX).
    script = '"$@" >/dev/null & echo $!; wait $!'
    command = _cli("build-map", "-c", str(slow), "-d", str(dataset), "-o", str(map_path))
    shell = subprocess.Popen(
        ["sh", "-c", script, "sh", *command],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert shell.stdout is not None
        pid = int(shell.stdout.readline())
        time.sleep(3.0)  # the build is under way (it takes about half a minute)
        assert shell.poll() is None, "build-map ended before it could be interrupted"
        ignored = _sig_mask(pid, "SigIgn")
        os.kill(pid, sig)
        _, err = shell.communicate(timeout=30)
    finally:
        if shell.poll() is None:
            os.kill(pid, signal.SIGKILL)
            shell.kill()
            shell.wait()
    assert not ignored & (1 << (signal.SIGINT - 1)), "SIGINT is still ignored"
    assert shell.returncode == code, err
    assert err.count("\n") == 1 and "interrupted" in err and "Traceback" not in err, err
    assert _snapshot(*before) == before
    assert not list(map_path.parent.glob(".*tmp*")), "temporary files left behind"


def _sig_mask(pid: int, field: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1], 16)
    raise AssertionError(f"no {field} in /proc/{pid}/status")


@pytest.mark.slow  # the module fixture surveys 300 frames and builds their map
def test_failed_build_map_keeps_the_old_map_and_config_copy(
    mapped: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, _, map_path = mapped
    before = _snapshot(*_map_files(map_path))
    other = _cfg(tmp_path, map={"neurons": 77, "epochs": 5, "vocabulary_size": 64})
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 64)
    capsys.readouterr()
    assert main(["build-map", "-c", str(other), "-d", str(bad), "-o", str(map_path)]) == 1
    assert capsys.readouterr().err.count("\n") == 1
    assert _snapshot(*before) == before
    assert "neurons: 77" not in map_path.with_name("map.config.yaml").read_text()


@pytest.mark.slow
def test_build_map_reads_a_partial_dataset_only_by_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from naoloc.data.dataset import DatasetWriter

    complete = read_dataset(_survey(tmp_path))
    stem = tmp_path / "p.mcap"
    writer = DatasetWriter(stem, config={}, meta=complete.meta)
    for kf in complete.keyframes[:10]:
        writer.write(kf)
    writer.close(complete=False, reason="interrupted (SIGINT)")
    cfg = _cfg(tmp_path)
    capsys.readouterr()
    code = main(["build-map", "-c", str(cfg), "-d", str(stem), "-o", str(tmp_path / "m.npz")])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1
    assert "p.partial.mcap: name that file" in err
    partial = tmp_path / "p.partial.mcap"
    args = ["build-map", "-c", str(cfg), "-d", str(partial), "-o", str(tmp_path / "m.npz")]
    # Named, it is read; a survey that stopped fails the map's survey_complete check...
    assert main(args) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "survey_complete" in err
    assert not (tmp_path / "m.npz").exists()
    # ...and --keep-unchecked keeps it, marked unchecked.
    assert main([*args, "--keep-unchecked"]) == 0
    out = capsys.readouterr().out
    assert "(partial dataset: interrupted (SIGINT))" in out
    line = json.loads(out.strip().splitlines()[-1])
    assert line["dataset_complete"] is False and line["images"] == 10


def _survey(folder: Path) -> Path:
    out = folder / "s.mcap"
    if not out.exists():
        assert main(["survey", "-c", str(_cfg(folder)), "-o", str(out)]) == 0
    return out


@pytest.mark.slow
def test_password_reaches_no_file_and_no_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = {"backend": "fake", "user": "nao", "password": SECRET}
    cfg = _cfg(tmp_path, robot=robot)
    out = tmp_path / "out"
    dataset, map_path = out / "s.mcap", out / "map.npz"
    assert main(["survey", "-c", str(cfg), "-o", str(dataset)]) == 0
    assert main(["build-map", "-c", str(cfg), "-d", str(dataset), "-o", str(map_path)]) == 0
    at = ["--at", "1.0", "1.2", "0.5"]
    loc = ["localize", "-c", str(cfg), "-m", str(map_path), *at, "--png", str(out / "l.png")]
    assert main(loc) in (0, 3)
    home = ["go-home", "-c", str(cfg), "-m", str(map_path), *at, "--png", str(out / "g.png")]
    assert main(home) in (0, 3)
    assert main(["demo", "-c", str(cfg), "-o", str(out / "demo")]) == 0
    # A config whose password has the wrong type: the error must not echo it either.
    bad = _cfg(tmp_path, "bad.yaml", robot={"backend": "fake", "password": [SECRET]})
    assert main(["survey", "-c", str(bad), "-o", str(out / "x.mcap")]) == 1
    printed = capsys.readouterr()
    assert SECRET not in printed.out + printed.err
    files = [p for p in out.rglob("*") if p.is_file()]
    assert len(files) >= 10
    for path in files:
        assert SECRET.encode() not in path.read_bytes(), path
    data = read_dataset(dataset)
    assert "password" not in data.config["robot"] and data.config["robot"]["user"] == "nao"
    assert "password" not in yaml.safe_load((out / "s.config.yaml").read_text())["robot"]


@pytest.mark.slow
def test_password_reaches_no_evaluation_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tiny = {
        "robot": {"backend": "fake", "password": SECRET},
        # The pre-issue-11 world: this test is about secrets, not realism.
        "world": {
            "room": {"size_m": [3.2, 3.2], "seed": 5, "style": "posters"},
            "camera_realism": {"profile": "ideal"},
            "odometry": {"profile": "ideal"},
        },
        "survey": {"laps": 1, "step_m": 0.3, "wall_offset_m": 0.9},
        "map": {"neurons": 12, "epochs": 12, "vocabulary_size": 48},
    }
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(tiny))
    out = tmp_path / "eval"
    assert main(["evaluate", "-c", str(cfg), "-n", "2", "--workers", "1", "-o", str(out)]) == 0
    printed = capsys.readouterr()
    assert SECRET not in printed.out + printed.err
    files = [p for p in out.rglob("*") if p.is_file()]
    assert {"summary.json", "config.yaml", "report.md"} <= {p.name for p in files}
    for path in files:
        assert SECRET.encode() not in path.read_bytes(), path
