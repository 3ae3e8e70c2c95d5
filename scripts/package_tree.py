"""The ``swarmdeck`` package as tools that do not follow import hooks expect it: a folder of links.

swarmdeck's subpackages live in top-level folders (``core/`` is ``swarmdeck.core``, pyproject.toml's
``[tool.setuptools.package-dir]``), which an editable install maps with an import hook. griffe (the docs'
docstring reader, ``scripts/docs_hooks.py``) and mypy (``scripts/typecheck.py``) do not follow that hook, so
both read the package from a folder ``<parent>/swarmdeck/`` whose subfolders link to the real folders: the
checked files are the repository's own, under the module names users import.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def link_package(parent: Path, *, init: bool) -> Path:
    """Make (or refresh) ``parent/swarmdeck/`` with one link per first-level subpackage; returns ``parent``.

    ``init`` writes a ``swarmdeck/__init__.py`` (griffe wants a regular package); without it ``swarmdeck`` is the
    namespace package it is when installed.
    """
    package = parent / "swarmdeck"
    package.mkdir(parents=True, exist_ok=True)
    if init:
        (package / "__init__.py").write_text('"""swarmdeck: the console, runtime and portal of a multi-robot arena."""\n')
    folders = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    for name, folder in folders.items():
        parts = name.split(".")
        if len(parts) != 2:
            continue
        link = package / parts[1]
        target = ROOT / folder
        if link.is_symlink() and link.resolve() == target.resolve():
            continue
        if link.is_symlink():
            link.unlink()
        link.symlink_to(target, target_is_directory=True)
    return parent
