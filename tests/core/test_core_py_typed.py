"""The installed package says it is typed (PEP 561): every first-level subpackage of the ``swarmdeck`` namespace
has a ``py.typed`` marker, and pyproject.toml ships it as each one's package data (so wheels carry it too)."""
from __future__ import annotations

import importlib.resources
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_every_subpackage_ships_py_typed() -> None:
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    firsts = [name for name in setuptools["package-dir"] if name.count(".") == 1]
    assert len(firsts) >= 9
    unshipped = [name for name in firsts if "py.typed" not in setuptools["package-data"].get(name, [])]
    assert not unshipped, f"py.typed not in package-data of {unshipped}"
    missing = [name for name in firsts if not importlib.resources.files(name).joinpath("py.typed").is_file()]
    assert not missing, f"no py.typed in {missing}"
