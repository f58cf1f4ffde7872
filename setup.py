"""Package layout (all metadata is in pyproject.toml).

The design card keeps three source folders at the top: ``naoloc/``, ``backends/`` and
``configs/``. Installed, they become one package, found here so that a new folder needs no
edit anywhere:

- ``naoloc/`` and every folder below it;
- ``backends/<name>/`` (any folder with an ``__init__.py``) as ``naoloc.backends.<name>``,
  with every folder below it; never a generic top-level package named ``backends``;
- ``configs/*.yaml`` as ``naoloc/configs/`` (the named configs of ``-c``).

Every non-Python file inside these folders is shipped as package data.
"""

from __future__ import annotations

from pathlib import Path

from setuptools import find_namespace_packages, setup

HERE = Path(__file__).resolve().parent
SKIP = ["*__pycache__*", "*.egg-info*"]


def _tree(package: str, folder: str) -> dict[str, str]:
    """Map ``package`` and every folder below ``folder`` to its dotted name -> folder."""
    found = {package: folder}
    for sub in find_namespace_packages(folder, exclude=SKIP):
        found[f"{package}.{sub}"] = f"{folder}/{sub.replace('.', '/')}"
    return found


folders = _tree("naoloc", "naoloc")
for init in sorted(HERE.glob("backends/*/__init__.py")):
    folders.update(_tree(f"naoloc.backends.{init.parent.name}", f"backends/{init.parent.name}"))
folders["naoloc.configs"] = "configs"

package_data = {}
for package, folder in folders.items():
    files = [
        f.name for f in sorted((HERE / folder).iterdir()) if f.is_file() and f.suffix != ".pyc"
    ]
    data = [n for n in files if not n.endswith(".py")]
    if data:
        package_data[package] = data

setup(
    packages=sorted(folders),
    package_dir={
        "naoloc": "naoloc",
        "naoloc.configs": "configs",
        **{p: d for p, d in folders.items() if p.count(".") == 2 and d.startswith("backends/")},
    },
    package_data=package_data,
)
