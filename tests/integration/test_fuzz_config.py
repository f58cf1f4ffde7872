"""Corrupt configs through the CLI, and random configs through the loader.

Every corrupt file makes ``naoloc`` exit non-zero with exactly one stderr line and no
traceback, within a bounded peak memory (bombs included); random documents and dicts
give a Config or a one-line ConfigError, nothing else.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from naoloc.app.cli import main
from naoloc.config import Config, load_config
from naoloc.errors import ConfigError
from tests.integration.test_config_hardening import BAD

ROOT = Path(__file__).resolve().parents[2]
MAX_PEAK_MB = 500.0

CORPUS: dict[str, bytes] = {name: text.encode() for name, (text, _) in BAD.items()}
CORPUS.update(
    {
        "not_utf8": b"robot: {backend: \xff\xfe}\n",
        "binary": bytes(range(256)) * 4,
        "oversized": b"# pad\n" * 60_000,
        "top_level_list": b"- 1\n- 2\n",
        "two_documents": b"robot: {backend: fake}\n---\nrobot: {backend: fake}\n",
        "unknown_key": b"robot: {backnd: fake}\n",
        "wrong_type": b"world: {room: {size_m: 'big'}}\n",
        "null_section": b"world: {room: {size_m: null}}\n",
        "bool_as_int": b"map: {seed: true, neurons: yes}\n",
    }
)


# Runs the CLI and prints the process's own peak RSS (VmHWM, per address space: unlike
# ru_maxrss it does not include the forking test process) as the last stdout line.
_PEAK = (
    "import atexit, sys\n"
    "from pathlib import Path\n"
    "from naoloc.app.cli import main\n"
    "def peak():\n"
    "    for line in Path('/proc/self/status').read_text().splitlines():\n"
    "        if line.startswith('VmHWM:'):\n"
    "            print(int(line.split()[1]) / 1024.0, flush=True)\n"
    "atexit.register(peak)\n"
    "sys.exit(main(sys.argv[1:]))\n"
)


def _run(args: list[str]) -> tuple[int, str, float]:
    """Run ``naoloc ARGS``; return (exit code, stderr, peak RSS in MB)."""
    env = dict(os.environ)
    env.pop("NAOLOC_DEBUG", None)
    done = subprocess.run(
        [sys.executable, "-c", _PEAK, *args],
        capture_output=True, text=True, env=env, timeout=60,
    )  # fmt: skip
    peak = float(done.stdout.strip().splitlines()[-1])
    return done.returncode, done.stderr, peak


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_every_corrupt_config_is_one_stderr_line_and_a_non_zero_exit(
    tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("NAOLOC_DEBUG", raising=False)
    path = tmp_path / f"{name}.yaml"
    path.write_bytes(CORPUS[name])
    code = main(["survey", "-c", str(path), "-o", str(tmp_path / "x.mcap")])
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert code == 1, out.err
    assert len(lines) == 1 and "Traceback" not in out.err, out.err[-2000:]
    assert str(path) in lines[0], lines[0]
    assert not out.out and not (tmp_path / "x.mcap").exists()


# The bombs and the worst files again, each in its own process: exit code, one stderr
# line, no traceback, and the process's peak memory.
BOMBS = ["laughs_key", "laughs_typed", "deep_flow", "digits_seed", "oversized", "binary"]


@pytest.mark.parametrize("name", BOMBS)
def test_bombs_through_the_command_line_stay_small(tmp_path: Path, name: str) -> None:
    path = tmp_path / f"{name}.yaml"
    path.write_bytes(CORPUS[name])
    code, err, peak_mb = _run(["survey", "-c", str(path), "-o", str(tmp_path / "x.mcap")])
    lines = err.strip().splitlines()
    assert code == 1
    assert len(lines) == 1 and "Traceback" not in err, err[-2000:]
    assert str(path) in lines[0], lines[0]
    assert peak_mb < MAX_PEAK_MB, peak_mb


@pytest.mark.slow
def test_config_paths_that_are_not_files(tmp_path: Path) -> None:
    for source in (str(tmp_path), "/dev/zero", str(tmp_path / "missing.yaml")):
        code, err, _ = _run(["survey", "-c", source, "-o", str(tmp_path / "x.mcap")])
        lines = err.strip().splitlines()
        assert code != 0 and len(lines) == 1 and "Traceback" not in err, err


_FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
_KEYS = st.sampled_from(
    ["robot", "world", "room", "size_m", "seed", "map", "survey", "step_m", "start_pose",
     "camera", "resolution", "backend", "fake", "timeout_s", "laps", "x"]
)  # fmt: skip
_LEAVES = (
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=12)
    | st.integers(min_value=10**18, max_value=10**40)
)  # fmt: skip
_DATA = st.recursive(
    _LEAVES,
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(_KEYS, kids, max_size=4),
    max_leaves=25,
)


def _only_config_errors(source: object) -> None:
    try:
        cfg = load_config(source)  # type: ignore[arg-type]
    except ConfigError as err:
        assert "\n" not in str(err) and len(str(err)) < 500, str(err)[:600]
        return
    assert isinstance(cfg, Config)


@_FUZZ
@given(st.dictionaries(_KEYS, _DATA, max_size=5))
def test_random_dicts_give_a_config_or_a_config_error(data: dict[str, object]) -> None:
    _only_config_errors(data)


@_FUZZ
@given(st.binary(max_size=40), st.integers(0, 400), st.data())
def test_mutated_config_files_give_a_config_or_a_config_error(
    patch: bytes, at: int, data: st.DataObject
) -> None:
    base = (ROOT / "configs" / "sim_paper_room.yaml").read_bytes()
    at = min(at, len(base))
    cut = data.draw(st.integers(0, 8))
    text = base[:at] + patch + base[at + cut :]
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"naoloc-fuzz-{os.getpid()}.yaml"
    try:
        path.write_bytes(text)
        _only_config_errors(path)
    finally:
        path.unlink(missing_ok=True)


@_FUZZ
@given(_DATA)
def test_random_yaml_documents_give_a_config_or_a_config_error(value: object) -> None:
    try:
        text = yaml.safe_dump({"world": value, "map": value})
    except (yaml.YAMLError, ValueError):
        return
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"naoloc-fuzz-doc-{os.getpid()}.yaml"
    try:
        path.write_text(text)
        _only_config_errors(path)
    finally:
        path.unlink(missing_ok=True)
