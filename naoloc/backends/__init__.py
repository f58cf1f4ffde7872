"""Backends, mapped into the naoloc namespace.

The sources live in the top-level ``backends/`` folder (one folder per backend). An
installed wheel maps each of them to ``naoloc.backends.<name>``; in a source checkout
(editable install or a plain ``pytest``) this package extends its search path to that
folder, so no generic top-level package named ``backends`` is ever importable.
"""

from __future__ import annotations

from pathlib import Path

_SOURCE = Path(__file__).resolve().parent.parent.parent / "backends"
if (_SOURCE / "fake" / "__init__.py").is_file() and (_SOURCE.parent / "naoloc").is_dir():
    __path__.append(str(_SOURCE))
