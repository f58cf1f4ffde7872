"""Build the API reference from naoloc's docstrings with pdoc (no network): HTML pages.

    python tools/build_api_docs.py [OUTDIR]      # default: build/api (not committed)

Documents the layers a user programs against (the robot interface, configuration,
localization, mapping, behaviours, datasets); the backends' and the CLI's insides are
left out. Google-style docstrings; a module that fails to import fails the build.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

PUBLIC = [
    "naoloc",
    "naoloc.config",
    "naoloc.errors",
    "naoloc.geometry",
    "naoloc.robot",
    "naoloc.localization",
    "naoloc.mapping",
    "naoloc.behaviours",
    "naoloc.navigation",
    "naoloc.data",
]


def build(out: Path) -> list[Path]:
    """Write the HTML reference into ``out``; returns the pages written.

    Raises:
        RuntimeError: A module failed to import.
    """
    import pdoc
    import pdoc.render

    pdoc.render.configure(docformat="google", show_source=False, search=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(*PUBLIC, output_directory=out)
    # Annotations behind TYPE_CHECKING cannot be resolved at runtime: those warnings are
    # expected; a module that does not import is not.
    problems = [str(w.message) for w in caught if "rror importing" in str(w.message)]
    if problems:
        raise RuntimeError("; ".join(problems[:5]))
    return sorted(out.rglob("*.html"))


if __name__ == "__main__":
    target = Path(sys.argv[1] if len(sys.argv) > 1 else "build/api")
    pages = build(target)
    print(f"api reference: {len(pages)} pages -> {target}/index.html")
