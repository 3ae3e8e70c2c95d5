"""Every exception class swarmdeck defines derives from ``SwarmdeckError`` and keeps its builtin base.

The rule is read with ``ast`` from the source folders named in pyproject.toml (like test_import_graph), so a new
exception class anywhere in the package is held to it; two control-flow signals are exempt (core/errors.py).
"""
from __future__ import annotations

import ast
import builtins
import importlib
import tomllib
from pathlib import Path

import pytest

from swarmdeck.core.errors import SwarmdeckError

ROOT = Path(__file__).resolve().parents[2]
SIGNALS = {"ExperimentFinished", "VerificationCancelled"}  # an experiment's end and a cancellation: not errors
BUILTIN_EXCEPTIONS = {name for name, v in vars(builtins).items() if isinstance(v, type) and issubclass(v, BaseException)}


def exception_classes() -> list[tuple[str, str, list[str]]]:
    """(file, class name, base names) of every class in the package deriving from a builtin exception or from
    another class in this list (by name)."""
    dirs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    classes: list[tuple[str, str, list[str]]] = []
    for name, folder in dirs.items():
        if name.count(".") != 1:
            continue
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.ClassDef):
                    bases = [b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", "") for b in node.bases]
                    classes.append((str(path.relative_to(ROOT)), node.name, bases))
    ours = {"SwarmdeckError"}
    found: list[tuple[str, str, list[str]]] = []
    changed = True
    while changed:  # close over subclasses of our own exception classes
        changed = False
        for entry in classes:
            if entry not in found and any(b in BUILTIN_EXCEPTIONS or b in ours for b in entry[2]):
                found.append(entry)
                ours.add(entry[1])
                changed = True
    return found


def test_every_exception_class_derives_from_swarmdeck_error() -> None:
    found = exception_classes()
    assert len(found) >= 25  # the scan sees the package (ConfigError, RecordingError, PortalError, …)
    ours = {name for _, name, _ in found}
    wrong = [f"{file}: {name}({', '.join(bases)})" for file, name, bases in found
             if name not in SIGNALS | {"SwarmdeckError"} and not any(b == "SwarmdeckError" or b in ours for b in bases)]
    assert not wrong, "exception classes not deriving from SwarmdeckError:\n" + "\n".join(wrong)


@pytest.mark.parametrize(("module", "name", "builtin"), [
    ("swarmdeck.core.config", "ConfigError", ValueError),
    ("swarmdeck.safety.filter", "InputError", ValueError),
    ("swarmdeck.inputs.oscparse", "MalformedDatagram", ValueError),
    ("swarmdeck.devices.fleet.setup", "SetupFailed", RuntimeError),
    ("swarmdeck.console.recording.reader", "RecordingError", Exception),
    ("swarmdeck.console.web.foxglove_live", "FoxglovePortInUse", OSError),
])
def test_builtin_bases_are_kept(module: str, name: str, builtin: type[BaseException]) -> None:
    """``except ValueError`` (etc.) still catches them, and ``except SwarmdeckError`` does too."""
    cls = getattr(importlib.import_module(module), name)
    assert issubclass(cls, SwarmdeckError) and issubclass(cls, builtin)
