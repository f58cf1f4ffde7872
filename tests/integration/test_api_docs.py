"""Issue 33, item 5: the API reference builds from the docstrings, offline (pdoc)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_api_reference_builds(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location(
        "build_api_docs", ROOT / "tools" / "build_api_docs.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["build_api_docs"] = module
    spec.loader.exec_module(module)
    pages = module.build(tmp_path)
    names = {p.relative_to(tmp_path).as_posix() for p in pages}
    assert {"naoloc.html", "naoloc/localization.html", "naoloc/mapping.html"} <= names
    localization = (tmp_path / "naoloc" / "localization.html").read_text(encoding="utf-8")
    # the docstrings made it: the Localizer and its update, with the Google sections parsed
    assert 'id="Localizer.update"' in localization and "Arguments:" in localization
