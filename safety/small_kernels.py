"""The barrier's two compiled kernels in plain Python, for small problems: the same numbers without numba.

A small-N run (an rps 2.x script: 1–20 robots) calls the barrier a few hundred times on a few dozen rows; importing
numba and loading its cached kernels (≈ 0.5 s CPU per process) costs more than running the same arithmetic in
CPython. :func:`ascend` is :func:`swarmdeck.safety.dual_ascent._ascend` and :func:`gram_dense` is
:func:`swarmdeck.safety.compiled.gram_dense`, operation for operation in the same order on IEEE doubles (numba
compiles without fast-math: no reassociation, no fused multiply-add), so they return the same bits
(tests/safety/test_safety_small_kernels.py checks it against the compiled kernels). Problems with more than
:data:`SMALL_ROBOTS` robots, and every problem once numba is imported, use the compiled kernels; :func:`small` is
the one test.
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from swarmdeck.core.compiled import imported

#: robots up to which the barrier's kernels run in plain Python (no numba import); measured on rps 2.x's examples
#: (1–12 robots, 303 steps, two barriers a step): 0.002–0.28 s CPU of Python kernels a run against ≈ 0.5 s CPU of
#: numba's import and kernel load (and 0.003–0.02 s of compiled kernels); the Python cost grows ≈ N²
SMALL_ROBOTS = 12


def small(n: int) -> bool:
    """Whether a barrier problem on ``n`` robots uses these kernels instead of numba's: at most SMALL_ROBOTS
    robots while this process has not imported numba (once something has, its kernels are the faster way to the
    same bits)."""
    return n <= SMALL_ROBOTS and not imported()


def ascend(ri: np.ndarray, rj: np.ndarray, ci: np.ndarray, cj: np.ndarray, b: np.ndarray, nominal: np.ndarray,
           vmax: float, lam0: np.ndarray, max_sweeps: int, tol: float, omega: float, slack: float, every: int
           ) -> tuple[np.ndarray, np.ndarray, int, float]:
    """:func:`swarmdeck.safety.dual_ascent._ascend` (same arguments: rows' robots (m,), coefficients (m, 2),
    bounds (m,), nominal (N, 2) m/s, vmax m/s or inf, lam0 (m,)): (λ (m,), u (N, 2), sweeps, last full residual)."""
    m = int(b.shape[0])
    n = int(nominal.shape[0])
    RI = ri.tolist()
    RJ = rj.tolist()
    CI0, CI1 = ci[:, 0].tolist(), ci[:, 1].tolist()
    CJ0, CJ1 = cj[:, 0].tolist(), cj[:, 1].tolist()
    B = b.tolist()
    lam = lam0.tolist()
    wx, wy = nominal[:, 0].tolist(), nominal[:, 1].tolist()
    for k in range(m):
        lk = lam[k]
        if lk != 0.0:
            i, j = RI[k], RJ[k]
            wx[i] -= lk * CI0[k]
            wy[i] -= lk * CI1[k]
            wx[j] -= lk * CJ0[k]
            wy[j] -= lk * CJ1[k]
    vv = vmax * vmax
    ux = [0.0] * n
    uy = [0.0] * n
    for r in range(n):
        x, y = wx[r], wy[r]
        s = x * x + y * y
        if s > vv:
            f = vmax / math.sqrt(s)
            ux[r], uy[r] = x * f, y * f
        else:
            ux[r], uy[r] = x, y
    inv = [1.0 / (CI0[k] * CI0[k] + CI1[k] * CI1[k] + CJ0[k] * CJ0[k] + CJ1[k] * CJ1[k]) for k in range(m)]
    resid = [0.0] * m

    table = list(zip(RI, RJ, CI0, CI1, CJ0, CJ1, B, inv))  # one row's numbers, read by one index

    def sweep(idx: list[int], table: list = table, ux: list[float] = ux, uy: list[float] = uy,
              wx: list[float] = wx, wy: list[float] = wy, lam: list[float] = lam, resid: list[float] = resid,
              omega: float = omega, vv: float = vv, vmax: float = vmax,
              sqrt: Callable[[float], float] = math.sqrt) -> float:
        worst = 0.0
        for k in idx:
            i, j, c0, c1, d0, d1, bk, ik = table[k]
            res = c0 * ux[i] + c1 * uy[i] + d0 * ux[j] + d1 * uy[j] - bk
            resid[k] = res
            old = lam[k]
            new = old + omega * res * ik
            if new < 0.0:
                new = 0.0
            e = abs(res) if old > 0.0 else (0.0 if 0.0 > res else res)  # numba's max(res, 0.0)
            if e > worst:
                worst = e
            d = new - old
            if d != 0.0:
                lam[k] = new
                wx[i] -= d * c0
                wy[i] -= d * c1
                wx[j] -= d * d0
                wy[j] -= d * d1
                x, y = wx[i], wy[i]
                s = x * x + y * y
                if s > vv:
                    f = vmax / sqrt(s)
                    ux[i], uy[i] = x * f, y * f
                else:
                    ux[i], uy[i] = x, y
                if j != i:  # a single-robot row (j = i) has projected its robot already: the same numbers
                    x, y = wx[j], wy[j]
                    s = x * x + y * y
                    if s > vv:
                        f = vmax / sqrt(s)
                        ux[j], uy[j] = x * f, y * f
                    else:
                        ux[j], uy[j] = x, y
        return worst

    every_row = list(range(m))
    sweeps = 0
    worst = math.inf
    while sweeps < max_sweeps:
        worst = sweep(every_row)
        sweeps += 1
        if worst <= tol:
            break
        cand = [k for k in every_row if lam[k] > 0.0 or resid[k] > -slack]
        for _ in range(every - 1):
            if sweeps >= max_sweeps:
                break
            sweeps += 1
            if sweep(cand) <= tol:
                break
    u = np.empty((n, 2))
    u[:, 0] = ux
    u[:, 1] = uy
    return np.array(lam, dtype=float), u, sweeps, worst


def gram_dense(ai: np.ndarray, aj: np.ndarray, aci: np.ndarray, acj: np.ndarray, J: np.ndarray,
               use_j: bool) -> np.ndarray:
    """:func:`swarmdeck.safety.compiled.gram_dense`: the dense Gram matrix G = A J Aᵀ (w, w) of rows
    ``aci·u_ai + acj·u_aj`` (ai, aj (w,); aci, acj (w, 2)); J (N, 2, 2) used when ``use_j``."""
    w = int(ai.shape[0])
    n = int(J.shape[0])
    AI, AJ = ai.tolist(), aj.tolist()
    C = aci.tolist()
    D = acj.tolist()
    touching: list[list[tuple[int, float, float]]] = [[] for _ in range(n)]
    for a in range(w):
        touching[AI[a]].append((a, C[a][0], C[a][1]))
        if D[a][0] != 0.0 or D[a][1] != 0.0:
            touching[AJ[a]].append((a, D[a][0], D[a][1]))
    Jl = J.tolist() if use_j else None
    G = [[0.0] * w for _ in range(w)]
    for r in range(n):
        ent = touching[r]
        if not ent:
            continue
        if Jl is not None:
            (j00, j01), (j10, j11) = Jl[r]
        for a, c0, c1 in ent:
            if Jl is not None:
                e0 = j00 * c0 + j01 * c1
                e1 = j10 * c0 + j11 * c1
            else:
                e0, e1 = c0, c1
            row = G[a]
            for q, q0, q1 in ent:
                row[q] += e0 * q0 + e1 * q1
    return np.array(G, dtype=float).reshape(w, w)


__all__ = ["SMALL_ROBOTS", "ascend", "gram_dense", "small"]
