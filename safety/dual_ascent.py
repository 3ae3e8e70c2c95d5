"""Warm-started dual coordinate ascent (Hildreth's method) that predicts the active rows.

For the barrier QP ``min ½‖u − û‖²  s.t.  A u ≤ b,  ‖u_i‖ ≤ v_max`` (REFERENCE.md §3) the
dual function is ``g(λ) = min_{u ∈ D} ½‖u − û‖² + λᵀ(Au − b)``, maximised at the QP's
multipliers, with ``u(λ) = Π_D(û − Aᵀλ)`` (Π_D: every robot's velocity projected on its speed
disc). ``∂g/∂λ_k = a_kᵀu(λ) − b_k`` is Lipschitz with constant ‖a_k‖² (Π_D is non-expansive),
so the projected coordinate step ``λ_k ← max(0, λ_k + ω (a_kᵀu − b_k)/‖a_k‖²)`` (ω ∈ (0, 2),
over-relaxed) increases g and touches two robots: one sweep over the rows is O(rows).

Started from the previous tick's multipliers (rows keyed across ticks), a few hundred sweeps
find the rows held at equality even on the dense, degenerate scenes where an exact active-set
method started from last tick's rows needs many Gram factorisations. Its answer is *not*
used as the command: the rows it predicts start the certified active set
(``active_set.solve_active_set``), which returns an exact, KKT-checked optimum or nothing.

The sweeps are compiled by numba (``safety.compiled``; :func:`warm_up` compiles or loads them
once per process, outside any tick). Without an importable numba, :data:`AVAILABLE` is False and
the filter keeps its uncompiled paths. Problems on at most ``small_kernels.SMALL_ROBOTS`` robots run the same
sweeps in plain Python (``small_kernels.ascend``, the same bits), so a small run never imports numba.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiled import AVAILABLE, jit, warm_up_gram
from .constraints import Rows
from .distributed_kernel import warm_up_distributed
from .small_kernels import ascend as _ascend_small
from .small_kernels import small

OMEGA = 1.8  # over-relaxation of the coordinate steps (measured: ≈ 2× fewer sweeps than ω = 1)
RESTRICT_SLACK = 3e-3  # m/s: between full sweeps, only rows with λ > 0 or within this of their bound
FULL_EVERY = 20  # a full sweep over every row after this many restricted ones
# rows whose multiplier exceeds this fraction of the largest (or that were held at the start and
# still are) are predicted active: weakly active rows (at their bound with λ = 0, which the sweeps
# nudge to ~1e-12) stay out, so the prediction from an optimum's own multipliers is that optimum's
# active set and a second call on the same tick reproduces the answer to the last bit
PREDICT_REL = 1e-9


@jit
def _project_robot(w, u, r, vmax):  # pragma: no cover - compiled
    s = w[r, 0] * w[r, 0] + w[r, 1] * w[r, 1]
    if s > vmax * vmax:
        f = vmax / np.sqrt(s)
        u[r, 0] = w[r, 0] * f
        u[r, 1] = w[r, 1] * f
    else:
        u[r, 0] = w[r, 0]
        u[r, 1] = w[r, 1]


@jit
def _sweep(idx, ri, rj, ci, cj, b, inv_norm2, lam, w, u, vmax, omega, resid):  # pragma: no cover
    """One Gauss–Seidel pass over rows ``idx``; returns the largest complementarity residual."""
    worst = 0.0
    for t in range(idx.shape[0]):
        k = idx[t]
        i = ri[k]
        j = rj[k]
        res = ci[k, 0] * u[i, 0] + ci[k, 1] * u[i, 1] + cj[k, 0] * u[j, 0] + cj[k, 1] * u[j, 1] - b[k]
        resid[k] = res
        old = lam[k]
        new = old + omega * res * inv_norm2[k]
        if new < 0.0:
            new = 0.0
        e = abs(res) if old > 0.0 else max(res, 0.0)
        if e > worst:
            worst = e
        d = new - old
        if d != 0.0:
            lam[k] = new
            w[i, 0] -= d * ci[k, 0]
            w[i, 1] -= d * ci[k, 1]
            w[j, 0] -= d * cj[k, 0]
            w[j, 1] -= d * cj[k, 1]
            _project_robot(w, u, i, vmax)
            _project_robot(w, u, j, vmax)
    return worst


@jit
def _ascend(ri, rj, ci, cj, b, nominal, vmax, lam0, max_sweeps, tol, omega, slack, every):  # pragma: no cover
    m = b.shape[0]
    n = nominal.shape[0]
    lam = lam0.copy()
    w = nominal.copy()
    for k in range(m):
        lk = lam[k]
        if lk != 0.0:
            w[ri[k], 0] -= lk * ci[k, 0]
            w[ri[k], 1] -= lk * ci[k, 1]
            w[rj[k], 0] -= lk * cj[k, 0]
            w[rj[k], 1] -= lk * cj[k, 1]
    u = np.empty_like(w)
    for r in range(n):
        _project_robot(w, u, r, vmax)
    inv_norm2 = np.empty(m)
    for k in range(m):
        inv_norm2[k] = 1.0 / (ci[k, 0] ** 2 + ci[k, 1] ** 2 + cj[k, 0] ** 2 + cj[k, 1] ** 2)
    every_row = np.arange(m)
    resid = np.empty(m)
    sweeps = 0
    worst = np.inf
    while sweeps < max_sweeps:
        worst = _sweep(every_row, ri, rj, ci, cj, b, inv_norm2, lam, w, u, vmax, omega, resid)
        sweeps += 1
        if worst <= tol:
            break
        cand = np.flatnonzero((lam > 0.0) | (resid > -slack))
        for _ in range(every - 1):
            if sweeps >= max_sweeps:
                break
            sweeps += 1
            if _sweep(cand, ri, rj, ci, cj, b, inv_norm2, lam, w, u, vmax, omega, resid) <= tol:
                break
    return lam, u, sweeps, worst


@dataclass(frozen=True)
class DualAscent:
    """lam (m,) multipliers ≥ 0; u (N, 2) = Π_D(û − Aᵀλ); predicted (m,) bool rows likely held
    (λ > ``PREDICT_REL``·max λ, or λ > 0 where λ0 > 0); sweeps done; residual: the last full sweep's largest complementarity residual (m/s)."""

    lam: np.ndarray
    u: np.ndarray
    predicted: np.ndarray
    sweeps: int
    residual: float


def ascend(rows: Rows, nominal: np.ndarray, max_speed: float | None, lam0: np.ndarray,
           max_sweeps: int, tol: float = 1e-5) -> DualAscent:
    """Dual coordinate ascent from multipliers ``lam0`` ((m,) ≥ 0, e.g. last tick's by row key).

    rows: the barrier rows; nominal (N, 2) m/s; max_speed m/s or None. Requires :data:`AVAILABLE`.
    """
    if not AVAILABLE:
        raise RuntimeError("dual ascent needs numba, which is not importable")
    vmax = np.inf if max_speed is None else float(max_speed)
    kernel = _ascend_small if small(int(np.shape(nominal)[0])) else _ascend
    lam, u, sweeps, worst = kernel(
        np.ascontiguousarray(rows.i, dtype=np.int64), np.ascontiguousarray(rows.jj, dtype=np.int64),
        np.ascontiguousarray(rows.ci, dtype=float), np.ascontiguousarray(rows.cj, dtype=float),
        np.ascontiguousarray(rows.b, dtype=float), np.ascontiguousarray(nominal, dtype=float), vmax,
        np.ascontiguousarray(lam0, dtype=float), int(max_sweeps), float(tol), OMEGA, RESTRICT_SLACK, FULL_EVERY)
    predicted = (lam > PREDICT_REL * float(lam.max(initial=0.0))) | ((lam0 > 0.0) & (lam > 0.0))
    return DualAscent(lam, u, predicted, int(sweeps), float(worst))


def warm_up(robots: int | None = None) -> None:
    """Compile (or load from numba's cache) the kernels on a two-robot problem, once per process;
    later calls cost microseconds. A no-op without numba, and when the caller's problems have ``robots`` robots
    and those are small (``small_kernels.small``: the plain-Python kernels, no numba)."""
    if not AVAILABLE or (robots is not None and small(robots)):
        return
    warm_up_gram()
    warm_up_distributed()  # the distributed filter's per-robot QPs (safety.distributed_kernel)
    rows = Rows(np.array([0]), np.array([1]), np.array([[-1.0, 0.0]]), np.array([[1.0, 0.0]]),
                np.array([0.0]), np.array([0.0]), np.array([0], dtype=np.int8), np.array([1]))
    _ascend(np.array([0]), np.array([1]), rows.ci, rows.cj, rows.b, np.array([[0.1, 0.0], [-0.1, 0.0]]), 0.2,
            np.zeros(1), 4, 1e-5, OMEGA, RESTRICT_SLACK, FULL_EVERY)  # the compiled kernel (2 robots are small)


__all__ = ["AVAILABLE", "DualAscent", "ascend", "warm_up"]
