"""Two runs never write into one output folder: ``naoloc evaluate`` holds its folder.

A second ``evaluate`` into a held folder fails at once with one line naming the folder and
the holder's pid, exit 1, and touches nothing; the lock goes with its holder, also when
the holder is killed, so a stale lock never blocks a later run.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from naoloc.app.cli import main
from naoloc.data.outputs import LOCK_NAME, folder_lock
from naoloc.errors import OutputBusy

TINY = {
    "robot": {"backend": "fake"},
    "world": {"room": {"size_m": [3.2, 3.2], "seed": 5, "style": "posters"}},
    "survey": {"laps": 1, "step_m": 0.3, "wall_offset_m": 0.9},
    "map": {"neurons": 12, "epochs": 12, "vocabulary_size": 48},
}
HOLD = """
import sys, time
from pathlib import Path
from naoloc.data.outputs import folder_lock
with folder_lock(Path(sys.argv[1]), "test"):
    print("held", flush=True)
    time.sleep(60)
"""


def test_evaluate_into_a_held_folder_fails_with_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(TINY))
    out = tmp_path / "out"
    with folder_lock(out, "test"):
        (out / "keep.txt").write_text("an earlier run's file")
        code = main(["evaluate", "-c", str(cfg), "--protocol", "random", "-n", "2", "-o", str(out)])
        err = capsys.readouterr().err
        assert code == 1, err
        assert err.count("\n") == 1, err
        assert f"{out} is in use by another naoloc run (pid {os.getpid()})" in err, err
        assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME, "keep.txt"]
    with folder_lock(out, "test"):  # released with its holder
        pass


def test_a_killed_holder_leaves_no_stale_lock(tmp_path: Path) -> None:
    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        busy = rf"in use by another naoloc run \(pid {holder.pid}\)"
        with pytest.raises(OutputBusy, match=busy), folder_lock(out, "test"):
            pass
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    with folder_lock(out, "test") as held:
        assert held == out
        assert (out / LOCK_NAME).read_text() == f"{os.getpid()}\n"
