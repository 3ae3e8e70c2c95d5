"""Type-checks the whole ``swarmdeck`` package with mypy (settings in pyproject.toml ``[tool.mypy]``).

Run as ``.venv/bin/python scripts/typecheck.py`` (``scripts/test`` does, so CI does); extra arguments go to mypy
(e.g. ``--strict`` to see what a stricter setting would find). mypy does not follow the editable install's import
hook, so this first links the package under ``build/typecheck/swarmdeck/`` (``scripts/package_tree.py``; ``build/``
is git-ignored) and checks it there as ``-p swarmdeck``; messages name the repository's files (``core/bounds.py``,
not the link). Exits with mypy's status.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from package_tree import ROOT, link_package  # noqa: E402  (beside this file)

TREE = ROOT / "build" / "typecheck"


def main(argv: list[str]) -> int:
    """Link the package, run mypy on it, print its report with the links read as repository paths."""
    link_package(TREE, init=False)
    command = [sys.executable, "-m", "mypy", "--python-executable", sys.executable, "-p", "swarmdeck", *argv]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)
    prefix = str(TREE.relative_to(ROOT) / "swarmdeck") + "/"
    sys.stdout.write(result.stdout.replace(prefix, "").replace(str(TREE / "swarmdeck") + "/", ""))
    sys.stderr.write(result.stderr)
    return result.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
