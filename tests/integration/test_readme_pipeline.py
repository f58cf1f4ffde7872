"""Issue 33, item 5: README's Python pipeline (survey -> map -> localize) runs as written.

The first ```python block of README's "Python" section is executed with the shipped
config's name replaced by a small fake-backend room (the same code, a faster robot).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from tests.rooms import PIPELINE_ROOM as ROOM

ROOT = Path(__file__).resolve().parents[2]


def _pipeline_block() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Python\n", 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match is not None
    return match.group(1)


@pytest.mark.slow
def test_readme_pipeline_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    code = _pipeline_block()
    assert 'load_config("paper_room")' in code and "record_survey" in code
    cfg = tmp_path / "room.yaml"
    cfg.write_text(yaml.safe_dump(ROOM), encoding="utf-8")
    code = code.replace('"paper_room"', repr(str(cfg)))
    code = code.replace("(2.0, 3.0, 1.0)", "(1.4, 2.2, 0.6)")  # inside the 4 x 4 m room
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})  # our own README
    out = capsys.readouterr().out.split()
    assert out[0] == "tracking", out  # the estimate's status, then x, y, theta
    assert len(out) == 4 and (tmp_path / "room.mcap").is_file()
    assert (tmp_path / "room.npz").is_file()
