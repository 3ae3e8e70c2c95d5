"""MkDocs hook (mkdocs.yml ``hooks:``): lets mkdocstrings find the ``swarmdeck`` package for the API reference.

swarmdeck's subpackages live in top-level folders (``core/`` is ``swarmdeck.core``, pyproject.toml's
``[tool.setuptools.package-dir]``), which an editable install maps with an import hook that griffe (the
docstring reader) does not follow. This builds the package as griffe expects it — a temporary folder
``swarmdeck/`` whose subfolders link to those folders (``scripts/package_tree.py``, shared with the type
check) — and puts it first on ``sys.path`` before the plugins start (priority 100). Nothing is written inside
the repository.
"""
from __future__ import annotations

import atexit
import functools
import re
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from mkdocs.plugins import event_priority

sys.path.insert(0, str(Path(__file__).resolve().parent))
from package_tree import link_package  # noqa: E402  (beside this file; mkdocs loads hooks by path)


@functools.lru_cache(maxsize=1)
def _package_tree() -> Path:
    """A temporary folder holding ``swarmdeck/`` with a link per first-level subpackage; removed at exit."""
    tree = Path(tempfile.mkdtemp(prefix="swarmdeck-docs-"))
    atexit.register(shutil.rmtree, tree, True)
    return link_package(tree, init=True)


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
