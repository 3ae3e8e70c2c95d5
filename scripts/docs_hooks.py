"""MkDocs hook (mkdocs.yml ``hooks:``): lets mkdocstrings find the ``swarmdeck`` package for the API reference.

swarmdeck's subpackages live in top-level folders (``core/`` is ``swarmdeck.core``, pyproject.toml's
``[tool.setuptools.package-dir]``), which an editable install maps with an import hook that griffe (the
docstring reader) does not follow. This builds the package as griffe expects it — a temporary folder
``swarmdeck/`` whose subfolders link to those folders — and puts it first on ``sys.path`` before the
plugins start (priority 100). Nothing is written inside the repository.
"""
from __future__ import annotations

import atexit
import re
import functools
import shutil
import sys
import tempfile
import tomllib
from pathlib import Path
from typing import Any

from mkdocs.plugins import event_priority

ROOT = Path(__file__).resolve().parents[1]


@functools.lru_cache(maxsize=1)
def _package_tree() -> Path:
    """A temporary folder holding ``swarmdeck/`` with a link per first-level subpackage; removed at exit."""
    tree = Path(tempfile.mkdtemp(prefix="swarmdeck-docs-"))
    atexit.register(shutil.rmtree, tree, True)
    package = tree / "swarmdeck"
    package.mkdir()
    (package / "__init__.py").write_text('"""swarmdeck: the console, runtime and portal of a multi-robot arena."""\n')
    folders = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    for name, folder in folders.items():
        parts = name.split(".")
        if len(parts) == 2:
            (package / parts[1]).symlink_to(ROOT / folder, target_is_directory=True)
    return tree


@event_priority(100)
def on_config(config: Any) -> Any:
    """Before mkdocstrings reads ``sys.path``: the package tree first."""
    tree = str(_package_tree())
    if tree not in sys.path:
        sys.path.insert(0, tree)
    return config


_ROLE = re.compile(r":(?:class|meth|func|mod|attr|data|exc|obj|const):(?=<code>)")
_TILDE = re.compile(r"<code>~(?:[\w]+\.)*([\w]+)</code>")


def on_page_content(html: str, **_: Any) -> str:
    """The docstrings' Sphinx roles (``:class:`Arena```) read as plain code in the API reference."""
    return _TILDE.sub(r"<code>\1</code>", _ROLE.sub("", html))
