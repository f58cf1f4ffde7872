"""docs/cli.md is generated from the code (tools/gen_cli_doc.py) and lists every JSON field
the verbs print: both are checked here, the second by running the verbs on the fake robot."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest
import yaml

from tests.tools import load_tool

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "gen_cli_doc.py"
pytestmark = pytest.mark.skipif(not TOOL.is_file(), reason="needs the checkout's tools/")

FAKE = {
    "robot": {"backend": "fake"},
    "world": {
        "room": {"size_m": [3.2, 3.2], "seed": 5, "style": "posters"},
        "camera_realism": {"profile": "ideal"},
        "odometry": {"profile": "ideal"},
        "sim": {"camera_sway": False},
    },  # the pre-issue-11 world: not about realism
    "survey": {"laps": 1, "step_m": 0.3, "wall_offset_m": 0.9},
    "map": {"neurons": 12, "epochs": 12, "vocabulary_size": 48},
}


def _tool() -> ModuleType:
    return load_tool("gen_cli_doc")


def test_docs_cli_md_is_up_to_date() -> None:
    text = (REPO / "docs" / "cli.md").read_text(encoding="utf-8")
    assert text == _tool().render(), "docs/cli.md is stale: run python tools/gen_cli_doc.py"


def test_every_config_key_and_verb_is_listed() -> None:
    from naoloc.app.cli import VERBS

    text = (REPO / "docs" / "cli.md").read_text(encoding="utf-8")
    for verb in VERBS:
        assert f"### `naoloc {verb}`" in text
    for key in ("world.room.size_m", "survey.step_m", "map.neurons", "robot.transport"):
        assert f"| `{key}` |" in text


def test_every_verb_has_its_json_fields_and_every_exit_code_is_listed() -> None:
    import re

    from naoloc.app import cli

    tool = _tool()
    assert set(tool.JSON_FIELDS) == set(cli.VERBS)
    codes = {int(c) for c in re.findall(r"\b(\d+)\s+(?:for|when)\b", cli.__doc__ or "")}
    assert {1, 2, 3, 4, 70, 130, 143} <= codes  # the docstring still says them all
    assert codes <= set(tool.EXIT_CODES), codes - set(tool.EXIT_CODES)
    assert cli.EXIT_INTERNAL in tool.EXIT_CODES


def _json_lines(tmp: Path, *args: str, ok: tuple[int, ...] = (0,)) -> list[dict[str, object]]:
    out = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", *args], capture_output=True, text=True, cwd=tmp,
        timeout=300,
    )  # fmt: skip
    assert out.returncode in ok, out.stderr
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def _json_line(tmp: Path, *args: str) -> dict[str, object]:
    out = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", *args], capture_output=True, text=True, cwd=tmp,
        timeout=300,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    line: dict[str, object] = json.loads(out.stdout.strip().splitlines()[-1])
    return line


@pytest.mark.slow
def test_every_printed_json_field_is_documented(tmp_path: Path) -> None:
    documented = _tool().JSON_FIELDS
    (tmp_path / "f.yaml").write_text(yaml.safe_dump(FAKE))
    lines = {
        "survey": _json_line(tmp_path, "survey", "-c", "f.yaml", "-o", "s.mcap"),
        "build-map": _json_line(
            tmp_path, "build-map", "-c", "f.yaml", "-d", "s.mcap", "-o", "m.npz"
        ),
        "localize": _json_line(
            tmp_path, "localize", "-c", "f.yaml", "-m", "m.npz", "--png", "l.png"
        ),
        "go-home": _json_line(
            tmp_path,
            "go-home",
            "-c",
            "f.yaml",
            "-m",
            "m.npz",
            "--at",
            "2",
            "2",
            "1",
            "--png",
            "g.png",
        ),
    }
    lines["check"] = _json_line(tmp_path, "check", "-c", "f.yaml", "--nod")
    tracked = _json_lines(tmp_path, "track", "-c", "f.yaml", "-m", "m.npz", "--duration", "2")
    assert len(tracked) >= 2
    lines["track"] = tracked[-1]
    for point in tracked[:-1]:
        assert not set(point) - set(_tool().TRACK_LINE), set(point) - set(_tool().TRACK_LINE)
    for verb, line in lines.items():
        missing = set(line) - set(documented[verb])
        assert not missing, f"{verb} prints fields docs/cli.md does not describe: {missing}"
