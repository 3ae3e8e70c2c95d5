"""numba, when importable: the one place that imports it (``jit``, ``AVAILABLE``).

numba is a dependency (pyproject); kernels are compiled with ``cache=True`` (the machine code is
kept in ``__pycache__``; a process loads it in ≈ 0.5 s including numba's import, the first process
compiles in a few seconds). A missing or broken numba leaves :data:`AVAILABLE` False and every
compiled kernel's caller on its numpy path. Used by ``swarmdeck.safety.compiled`` (the barrier's
Gram assembly) and ``swarmdeck.coverage.kernels`` (the coverage sums).
"""
from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def _import_numba() -> Any:
    """numba, or None. numba imports ``coverage`` (coverage.py) if it can; with the repository
    root on sys.path (a script or Ray worker started there) that name is swarmdeck's own
    ``coverage/`` package and numba's import fails — so it is retried with ``coverage`` hidden."""
    try:
        import numba
        return numba
    except ImportError:
        return None
    except Exception:  # noqa: BLE001 - the shadowed coverage: AttributeError inside numba's import
        pass
    for name in [m for m in sys.modules if m == "numba" or m.startswith("numba.")]:
        del sys.modules[name]
    missing = object()
    saved = sys.modules.get("coverage", missing)
    sys.modules["coverage"] = None  # type: ignore[assignment]  # `import coverage` raises ImportError: numba runs without it
    try:
        import numba
        return numba
    except Exception:  # noqa: BLE001 - any other breakage: the numpy paths
        return None
    finally:
        if saved is missing:
            del sys.modules["coverage"]
        else:
            sys.modules["coverage"] = saved  # type: ignore[assignment]


_numba = _import_numba()
AVAILABLE = _numba is not None


def jit(fn: F) -> F:
    """``numba.njit(cache=True, nogil=True)(fn)``, or ``fn`` itself without numba."""
    return _numba.njit(cache=True, nogil=True)(fn) if AVAILABLE else fn


__all__ = ["AVAILABLE", "jit"]
