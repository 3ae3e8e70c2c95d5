"""numba, when importable: the one place that imports it (``jit``, ``AVAILABLE``), on the first kernel call.

numba is a dependency (pyproject); kernels are compiled with ``cache=True`` (the machine code is
kept in ``__pycache__``; a process loads it in ≈ 0.5 s including numba's import, the first process
compiles in a few seconds). numba is imported when a kernel is first called (or warmed up), not when a module
defining one is imported: a process whose problems are all small enough for the plain-Python kernels
(``swarmdeck.safety.small_kernels``: an rps 2.x script) never pays for it. :data:`AVAILABLE` says whether numba is
installed (found without importing it); a numba that is installed but fails to import runs each kernel's own
Python source instead (the same arithmetic, slowly). Used by ``swarmdeck.safety.compiled`` (the barrier's Gram
assembly), ``swarmdeck.safety.dual_ascent``, ``swarmdeck.sensing.kernels`` and ``swarmdeck.coverage.kernels``.
"""
from __future__ import annotations

import importlib.util
import sys
import threading
import types
from collections.abc import Callable
from typing import Any, TypeVar, cast

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


#: numba is installed (its import, and the kernels' compile or cache load, wait for the first kernel call)
AVAILABLE = importlib.util.find_spec("numba") is not None


class _Lazy:
    """A kernel compiled on its first call: ``numba.njit(cache=True, nogil=True)`` of ``py_func``, with the other
    lazy kernels it calls compiled first (numba resolves them from the function's globals), or ``py_func`` itself
    when numba does not import."""

    def __init__(self, fn: Callable[..., Any]) -> None:
        self.py_func = fn
        self.__name__ = fn.__name__
        self.__qualname__ = fn.__qualname__
        self.__doc__ = fn.__doc__
        self.__wrapped__ = fn
        self._lock = threading.Lock()
        self._compiled: Callable[..., Any] | None = None

    def target(self) -> Callable[..., Any]:
        """The callable this kernel runs: numba's dispatcher (created on the first call), or ``py_func``."""
        if self._compiled is None:
            with self._lock:
                if self._compiled is None:
                    numba = _import_numba()
                    fn = self.py_func
                    if numba is None:
                        self._compiled = fn
                    else:
                        names = fn.__code__.co_names
                        deps = {k: v.target() for k, v in fn.__globals__.items() if isinstance(v, _Lazy) and k in names}
                        if deps:  # numba types the called kernels from the globals it sees: give it theirs
                            fn = types.FunctionType(fn.__code__, {**fn.__globals__, **deps}, fn.__name__,
                                                    fn.__defaults__, fn.__closure__)
                            fn.__qualname__ = self.py_func.__qualname__
                        self._compiled = numba.njit(cache=True, nogil=True)(fn)
        return self._compiled

    def __call__(self, *args: Any) -> Any:
        return self.target()(*args)


def jit(fn: F) -> F:
    """``numba.njit(cache=True, nogil=True)(fn)`` on the first call (numba imported then), or ``fn`` itself
    without numba."""
    return cast(F, _Lazy(fn)) if AVAILABLE else fn


def imported() -> bool:
    """Whether this process has imported numba (a kernel was called or warmed up)."""
    return "numba" in sys.modules


__all__ = ["AVAILABLE", "imported", "jit"]
