"""The CLI's last line of defence: one line for any error, a traceback only with NAOLOC_DEBUG=1."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from naoloc.app import cli
from naoloc.config import Config
from naoloc.errors import DatasetError

CFG = str(Path(__file__).resolve().parents[2] / "configs" / "sim_paper_room.yaml")


def _boom(exc: BaseException) -> object:
    def run_verb(verb: str, args: argparse.Namespace, cfg: Config) -> dict[str, object]:
        raise exc

    return run_verb


def test_an_unexpected_exception_is_one_line_with_a_hint(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("NAOLOC_DEBUG", raising=False)
    monkeypatch.setattr(cli, "_run_verb", _boom(ZeroDivisionError("float division by zero")))
    code = cli.main(["survey", "-c", CFG, "-o", "x.mcap"])
    err = capsys.readouterr().err
    assert code == cli.EXIT_INTERNAL
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "ZeroDivisionError" in lines[0] and "NAOLOC_DEBUG=1" in lines[0]
    assert "Traceback" not in err


def test_naoloc_debug_shows_the_traceback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("NAOLOC_DEBUG", "1")
    monkeypatch.setattr(cli, "_run_verb", _boom(RecursionError("maximum recursion depth")))
    code = cli.main(["survey", "-c", CFG, "-o", "x.mcap"])
    assert code == cli.EXIT_INTERNAL
    assert "Traceback" in capsys.readouterr().err


def test_a_multi_line_naoloc_error_is_printed_as_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(
        cli, "_run_verb", _boom(DatasetError("bad frame\nsecond line " + "x" * 900))
    )
    assert cli.main(["survey", "-c", CFG, "-o", "x.mcap"]) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "bad frame" in lines[0] and len(lines[0]) <= 1000


def test_memory_error_is_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("NAOLOC_DEBUG", raising=False)
    monkeypatch.setattr(cli, "_run_verb", _boom(MemoryError()))
    assert cli.main(["survey", "-c", CFG, "-o", "x.mcap"]) != 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "MemoryError" in lines[0]
