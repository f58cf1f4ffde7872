"""Package layout (all metadata is in pyproject.toml).

Everything importable lives under ``naoloc/``; the named configs of ``-c`` live in the
top-level ``configs/`` folder and are installed as ``naoloc/configs/``. Every non-Python file
inside ``naoloc/`` ships as package data.
"""

from __future__ import annotations

from pathlib import Path

from setuptools import find_namespace_packages, setup

HERE = Path(__file__).resolve().parent
SKIP = ["*__pycache__*", "*.egg-info*"]

packages = ["naoloc", *(f"naoloc.{p}" for p in find_namespace_packages("naoloc", exclude=SKIP))]
package_data = {}
for package in packages:
    folder = HERE / package.replace(".", "/")
    data = [
        f.name for f in sorted(folder.iterdir()) if f.is_file() and f.suffix not in {".py", ".pyc"}
    ]
    if data:
        package_data[package] = data
package_data["naoloc.configs"] = [f.name for f in sorted((HERE / "configs").glob("*.yaml"))]

setup(
    packages=[*packages, "naoloc.configs"],
    package_dir={"naoloc": "naoloc", "naoloc.configs": "configs"},
    package_data=package_data,
)
