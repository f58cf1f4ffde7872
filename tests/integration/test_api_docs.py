"""Issue 33, item 5: the API reference builds from the docstrings, offline (pdoc)."""

from __future__ import annotations

from pathlib import Path

from tests.tools import load_tool


def test_api_reference_builds(tmp_path: Path) -> None:
    pages = load_tool("build_api_docs").build(tmp_path)
    names = {p.relative_to(tmp_path).as_posix() for p in pages}
    assert {"naoloc.html", "naoloc/localization.html", "naoloc/mapping.html"} <= names
    localization = (tmp_path / "naoloc" / "localization.html").read_text(encoding="utf-8")
    # the docstrings made it: the Localizer and its update, with the Google sections parsed
    assert 'id="Localizer.update"' in localization and "Arguments:" in localization
