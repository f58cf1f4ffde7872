"""The CLI shell: --version, --help on every verb, and one-line config errors for every verb."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from naoloc import __version__
from naoloc.app.cli import VERBS, build_parser, main

ARGS = {
    "survey": ["-o", "x.mcap"],
    "build-map": ["-d", "x.mcap", "-o", "x.npz"],
    "localize": ["-m", "x.npz"],
    "go-home": ["-m", "x.npz"],
    "track": ["-m", "x.npz"],
    "evaluate": ["-o", "out"],
    "serve": [],
    "demo": [],
    "check": [],
    "replay": ["x.mcap", "-m", "x.npz"],
}


def _naoloc(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", *args], capture_output=True, text=True, cwd=cwd,
        timeout=120,
    )  # fmt: skip


def test_version() -> None:
    out = _naoloc("--version")
    assert out.returncode == 0 and out.stdout.strip() == f"naoloc {__version__}"


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_every_verb_has_help(verb: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args([verb, "--help"])
    assert info.value.code == 0
    assert VERBS[verb].split(":")[0] in capsys.readouterr().out


@pytest.mark.parametrize("verb", sorted(VERBS))
def test_unknown_key_fails_every_verb_with_one_line(
    verb: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("robot:\n  backend: fake\nmap:\n  neurones: 10\n")
    code = main([verb, "-c", str(cfg), *ARGS[verb]])
    err = capsys.readouterr().err.strip()
    assert code != 0
    assert len(err.splitlines()) == 1
    assert "map.neurones: unknown key" in err and str(cfg) in err


def test_usage_error_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["survey"])
    assert info.value.code == 2


def test_at_rejects_non_finite() -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["localize", "-c", "x", "-m", "y", "--at", "nan", "0", "0"])


def test_unwritable_output_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "fake.yaml"
    cfg.write_text("robot: {backend: fake}\n")
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code = main(["survey", "-c", str(cfg), "-o", str(blocker / "s.mcap")])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1 and "naoloc survey: error:" in err
