"""Packaging: shipped named configs work from any folder, py.typed, the package layout.

These tests also run against the installed wheel (tools/check_wheel.sh copies tests/ out of
the checkout); the ones that need the checkout skip there with a reason.
"""

from __future__ import annotations

import importlib.resources
import subprocess
import sys
from pathlib import Path

import pytest

import naoloc
from naoloc.config import load_config, shipped_configs
from naoloc.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]
IN_CHECKOUT = (REPO / "setup.py").is_file() and (REPO / "naoloc").is_dir()


def test_named_configs_are_shipped() -> None:
    assert {"paper_room", "lab_room", "nao"} <= set(shipped_configs())
    assert load_config("paper_room").world.room.size_m == (6.0, 6.0)
    assert load_config("lab_room").world.room.size_m == (4.0, 3.0)
    assert load_config("nao").robot.backend == "naoqi"
    assert load_config("sim_paper_room") == load_config("paper_room")


def test_unknown_name_is_one_line_listing_the_shipped_names(tmp_path: Path) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", "paper_rom", "-o", "s.mcap"],
        capture_output=True, text=True, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert "paper_rom" in lines[0] and "lab_room, nao, paper_room" in lines[0]
    assert not (tmp_path / "s.mcap").exists()


def test_a_path_still_wins_over_a_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "mine.yaml").write_text("world: {room: {size_m: [3.0, 3.0]}}\n")
    monkeypatch.chdir(tmp_path)
    assert load_config("mine.yaml").world.room.size_m == (3.0, 3.0)
    with pytest.raises(ConfigError, match=r"nope\.yaml: no such config file"):
        load_config("nope.yaml")


def test_named_config_from_another_folder_runs_a_verb(tmp_path: Path) -> None:
    # localize fails on the missing map, after the named config loaded from a foreign folder
    out = subprocess.run(
        [sys.executable, "-m", "naoloc.app.cli", "localize", "-c", "lab_room", "-m", "no.npz"],
        capture_output=True, text=True, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert out.returncode != 0
    assert "no.npz" in out.stderr and "config" not in out.stderr.lower()


def test_py_typed_and_configs_are_package_resources() -> None:
    root = importlib.resources.files("naoloc")
    if not IN_CHECKOUT:  # installed: configs live inside the package
        assert root.joinpath("configs", "sim_paper_room.yaml").is_file()
    assert root.joinpath("py.typed").is_file()
    assert Path(naoloc.__file__).parent.joinpath("backends", "__init__.py").is_file()


@pytest.mark.skipif(not IN_CHECKOUT, reason="needs the checkout's setup.py")
def test_setup_finds_every_source_folder() -> None:
    out = subprocess.run(
        [sys.executable, "-c", _LIST_PACKAGES], capture_output=True, text=True, cwd=REPO,
        timeout=60,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    packages = set(out.stdout.split())
    folders = {p.parent for p in (REPO / "naoloc").rglob("*.py")}
    expected = {"naoloc." + ".".join(f.relative_to(REPO / "naoloc").parts) for f in folders}
    for init in (REPO / "backends").glob("*/__init__.py"):
        for f in {p.parent for p in init.parent.rglob("*.py")}:
            rel = f.relative_to(REPO / "backends").parts
            expected.add("naoloc.backends." + ".".join(rel))
    expected = {e.rstrip(".") for e in expected} | {"naoloc", "naoloc.configs"}
    assert expected - packages == set()


_LIST_PACKAGES = """
import sys, setuptools
captured = {}
setuptools.setup = lambda **kw: captured.update(kw)
sys.argv = ["setup.py"]
exec(open("setup.py").read(), {"__file__": "setup.py", "__name__": "__main__"})
print(" ".join(captured["packages"]))
"""
