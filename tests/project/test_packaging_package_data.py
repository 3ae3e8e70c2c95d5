"""`pip install -e .` prints no setuptools warning about package data (issue 26 item 18): every folder that ships
data files inside a listed package is itself listed in pyproject's packages (setuptools warns "Package '…' is
absent from the `packages` configuration" for a data folder that is importable but unlisted)."""
from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_every_package_data_folder_is_a_listed_package():
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    packages, dirs, data = set(tool["packages"]), tool["package-dir"], tool["package-data"]
    for package, patterns in data.items():
        assert package in packages, package
        for pattern in patterns:
            assert "/" not in pattern, (package, pattern, "list the folder as a package with its own package-data")
    for package in packages:  # each listed package's subfolders with files (not caches) are listed too
        for sub in sorted(p for p in (ROOT / dirs[package]).iterdir() if p.is_dir() and p.name != "__pycache__"):
            files = [f for f in sub.iterdir() if f.is_file()]
            if files and not (sub / "__init__.py").exists() and sub.name.isidentifier():
                assert f"{package}.{sub.name}" in packages, f"{package}.{sub.name} holds data but is not listed"
