"""numba is importable from the repository root, where ``coverage`` names swarmdeck's own package.

Defect this guards: numba imports coverage.py when it can; a script or a Ray worker started in the
repository root found ``coverage/`` (swarmdeck.coverage) first, numba's import raised, and that
process filtered on the numpy paths — answers differing in the last bits from every other process
(tests/sandbox/test_sandbox_verify_determinism.py: serial and Ray verification JSON differed).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_compiled_kernels_available_with_the_repository_root_on_sys_path() -> None:
    assert (ROOT / "coverage" / "__init__.py").exists()
    code = ("import sys; sys.path.insert(0, '.'); import coverage; "
            "assert not hasattr(coverage, 'Coverage'), 'expected the shadowing package'; "
            "from swarmdeck.safety import compiled; print(compiled.AVAILABLE)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True", out.stdout + out.stderr
