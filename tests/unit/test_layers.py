"""The package's layers: each part of naoloc imports only the parts below it.

Read from the source (every import, also those inside functions), so a lazy import that
climbs a layer fails here too. The order, lowest first, is the architecture drawn in
docs/DEVELOPING.md.
"""

from __future__ import annotations

import ast
from pathlib import Path

import naoloc

PACKAGE = Path(naoloc.__file__).parent

# Lowest first. A part may import itself and any part before it in this list.
LAYERS = [
    "errors",
    "geometry",
    "safe_yaml",
    "constants",
    "config",
    "robot",
    "perception",
    "mapping",
    "localization",
    "navigation",
    "behaviours",
    "data",
    "backends",
    "viz",
    "evaluation",
    "app",
    "qi",  # the public name of naoloc.backends.naoqi.qi
    "run",  # the old-SDK launcher: python -m naoloc.run script.py
]


def _imported_parts(tree: ast.AST) -> list[tuple[str, int]]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.module == "naoloc":
                found += [(alias.name, node.lineno) for alias in node.names]
            elif node.module.startswith("naoloc."):
                found.append((node.module.split(".")[1], node.lineno))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("naoloc."):
                    found.append((alias.name.split(".")[1], node.lineno))
    return found


def _part_of(path: Path) -> str:
    return path.relative_to(PACKAGE).parts[0].removesuffix(".py")


def test_every_part_of_the_package_has_a_layer() -> None:
    parts = {_part_of(p) for p in PACKAGE.iterdir() if p.suffix == ".py" or p.is_dir()}
    parts -= {"__init__", "__pycache__", "py"}
    assert parts <= set(LAYERS), f"give these a layer: {sorted(parts - set(LAYERS))}"


def test_no_part_imports_a_layer_above_it() -> None:
    rank = {name: i for i, name in enumerate(LAYERS)}
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path == PACKAGE / "__init__.py":
            continue  # the facade re-exports the public API
        part = _part_of(path)
        for target, line in _imported_parts(ast.parse(path.read_text(encoding="utf-8"))):
            if target in rank and rank[target] > rank[part]:
                upward.append(f"{path.relative_to(PACKAGE.parent)}:{line} ({part} -> {target})")
    assert not upward, "imports that climb a layer:\n" + "\n".join(upward)


def test_nothing_outside_the_app_imports_it() -> None:
    users = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if _part_of(path) in {"app", "__init__"}:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        users += [f"{path.relative_to(PACKAGE.parent)}:{line}"
                  for target, line in _imported_parts(tree) if target == "app"]  # fmt: skip
    assert not users, f"the app is the top layer; imported from {users}"


def test_at_most_eight_top_level_modules() -> None:
    modules = [p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"]
    assert len(modules) <= 8, sorted(modules)
