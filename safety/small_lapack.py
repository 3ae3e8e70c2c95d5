"""Cholesky solves of small dense SPD systems through scipy's own LAPACK, without importing ``scipy.linalg``.

The active set solves (G + ridge·I) λ = r for a small Gram matrix G with ``scipy.linalg.cho_factor`` /
``cho_solve``, which are LAPACK's ``dpotrf`` / ``dpotrs`` of scipy's bundled library (``scipy.linalg._flapack``).
Importing ``scipy.linalg`` costs ≈ 0.3 s CPU (its array-API layer imports half of numpy's optional modules) — a third
of an rps-sized run's whole budget (issue 28). :func:`cho_solve` loads the same extension module alone (≈ 0.01 s)
and calls the same two routines with the arguments scipy passes (``lower``, ``clean=0``, no overwrite), so the
answers are the same bits (tests/safety/test_safety_small_lapack.py checks it against ``scipy.linalg``). The module
is registered under its own name (scipy's namespace is left alone: a later ``import scipy.linalg`` loads its own
copy of the same library); when scipy.linalg is already imported, its module is used. numpy's LAPACK is a
different build (and OpenBLAS's triangular solves use fused multiply-adds), not a same-bits substitute.
"""
from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

_NAME = "swarmdeck.safety._scipy_lapack._flapack"  # its own name: scipy.linalg, when imported, loads its own


def _flapack() -> ModuleType:
    """scipy's LAPACK wrappers: the module ``scipy.linalg`` imports, loaded on its own if scipy.linalg is not."""
    mod = sys.modules.get("scipy.linalg._flapack") or sys.modules.get(_NAME)
    if mod is not None:
        return mod
    spec = importlib.util.find_spec("scipy")  # a top-level find_spec does not import scipy
    for folder in (spec.submodule_search_locations or []) if spec is not None else []:
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = Path(folder) / "linalg" / f"_flapack{suffix}"
            ext = importlib.util.spec_from_file_location(_NAME, path)
            if path.is_file() and ext is not None and ext.loader is not None:
                mod = importlib.util.module_from_spec(ext)
                ext.loader.exec_module(mod)
                return sys.modules.setdefault(_NAME, mod)
    import scipy.linalg  # noqa: F401  # an unusual layout: the ordinary import

    return sys.modules["scipy.linalg._flapack"]


def cho_solve(G: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with G x = rhs for a symmetric positive definite ``G`` ``(w, w)`` (w ≥ 1) and ``rhs`` ``(w,)`` or
    ``(w, k)``: ``scipy.linalg.cho_solve(scipy.linalg.cho_factor(G, lower=True, check_finite=False), rhs,
    check_finite=False)``, the same bits. ``G`` and ``rhs`` are not modified.

    Raises ``numpy.linalg.LinAlgError`` when G is not numerically positive definite (as ``cho_factor``).
    """
    lapack = _flapack()
    c, info = lapack.dpotrf(G, lower=1, clean=0, overwrite_a=0)
    if info > 0:
        raise np.linalg.LinAlgError(f"{info}-th leading minor of the array is not positive definite")
    if info < 0:
        raise ValueError(f'LAPACK reported an illegal value in {-info}-th argument on entry to "POTRF".')
    x, info = lapack.dpotrs(c, rhs, lower=1, overwrite_b=0)
    if info != 0:
        raise ValueError(f"illegal value in {-info}th argument of internal potrs")
    return np.asarray(x)
