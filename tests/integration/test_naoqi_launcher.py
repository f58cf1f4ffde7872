"""``python -m naoloc.run``: the old SDK's modules for a script, never installed.

The launcher finds naoloc's ``naoqi`` for a script, lets an official ``naoqi`` win when
one is importable (unless ``--shim``), passes the script its own arguments and exit
code, and says in one line when the script is missing. Outside the launcher
``import naoqi`` is untouched.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

SCRIPT = """
import sys
import almath, motion, naoqi, vision_definitions
print(naoqi.__file__)
print(motion.FRAME_ROBOT, vision_definitions.kVGA, round(almath.TO_DEG, 3))
print(sys.argv[1:])
sys.exit(3)
"""


def _run(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "naoloc.run", *args],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, **(env or {})},
        check=False,
    )


def test_a_script_gets_the_old_sdk_modules_and_its_arguments(tmp_path: Path) -> None:
    script = tmp_path / "old.py"
    script.write_text(SCRIPT, encoding="utf-8")
    result = _run(str(script), "--ip", "nao.local")
    assert result.returncode == 3, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].endswith(os.path.join("backends", "naoqi", "sdk", "naoqi.py"))
    assert lines[1] == "2 2 57.296"
    assert lines[2] == "['--ip', 'nao.local']"
    assert importlib.util.find_spec("naoqi") is None  # nothing was installed


def test_an_official_naoqi_wins_unless_the_shim_is_asked_for(tmp_path: Path) -> None:
    official = tmp_path / "sdk"
    official.mkdir()
    (official / "naoqi.py").write_text("OFFICIAL = True\n", encoding="utf-8")
    script = tmp_path / "which.py"
    script.write_text("import naoqi\nprint(hasattr(naoqi, 'OFFICIAL'))\n", encoding="utf-8")
    env = {"PYTHONPATH": str(official)}
    result = _run(str(script), env=env)
    assert result.stdout.strip() == "True"
    assert "using the official naoqi" in result.stderr
    assert _run("--shim", str(script), env=env).stdout.strip() == "False"


def test_a_missing_script_is_one_line_and_exit_2(tmp_path: Path) -> None:
    result = _run(str(tmp_path / "nope.py"))
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "no script at" in result.stderr
