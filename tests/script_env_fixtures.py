"""A tiny script environment for the tests of ``--script-env``: a real virtual environment (no pip) holding one
pure-Python package, ``labtools`` 1.2, and a module ``leaky`` that imports something outside the environment.

The fixture ``env`` is registered for every test by ``pytest_plugins`` in ``tests/conftest.py`` (module-scoped:
made once per test module).
"""
import os
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

USES_THE_ENV = """
import numpy as np
import labtools
from labtools import helper
import math, json
assert helper() == "labtools"
def experiment(arena):
    while True:
        arena.set_velocities(np.full((arena.n, 2), labtools.GAIN))
        arena.step()
"""


def make_env(with_package: bool = True) -> Path:
    """A tiny virtual environment (no pip) holding one pure-Python package, ``labtools`` 1.2, and a
    package ``leaky`` that imports something outside the environment."""
    root = Path(tempfile.mkdtemp(prefix="swarmdeck-test-env-"))
    os.chmod(root, 0o755)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(root / "env")], check=True)
    site = root / "env" / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    if with_package:
        (site / "labtools").mkdir()
        (site / "labtools" / "__init__.py").write_text("GAIN = 0.05\ndef helper():\n    return 'labtools'\n")
        (site / "labtools-1.2.dist-info").mkdir()
        (site / "labtools-1.2.dist-info" / "METADATA").write_text("Metadata-Version: 2.1\nName: labtools\nVersion: 1.2\n")
        (site / "leaky.py").write_text("import msgspec\n")
    for path in [root, *root.rglob("*")]:
        os.chmod(path, os.stat(path).st_mode | stat.S_IROTH | (stat.S_IXOTH if path.is_dir() else 0))
    return root / "env"


@pytest.fixture(scope="module")
def env():
    path = make_env()
    yield path
    shutil.rmtree(path.parent, ignore_errors=True)
