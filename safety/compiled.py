"""The barrier's compiled Gram assembly (numba through :mod:`swarmdeck.core.compiled`, the one place that imports it).

numba is a dependency (pyproject), compiled with ``cache=True`` (the machine code is kept in
``__pycache__``; a process loads it in ≈ 0.5 s including numba's import, the first process
compiles in ≈ 6 s). A missing or broken numba leaves :data:`AVAILABLE` False and the filter on its numpy
paths: answers equal to 1e-9 (not to the last bit: the Gram matrices are summed in another
order), slower.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.core.compiled import AVAILABLE, jit  # the one place numba is imported


@jit
def gram_dense(ai, aj, aci, acj, J, use_j):  # pragma: no cover - compiled
    """Dense Gram matrix G = A J Aᵀ (w, w) of rows ``aci·u_ai + acj·u_aj`` (w rows on N robots).

    ai, aj (w,) robot indices; aci, acj (w, 2) coefficients (a zero acj: single-robot row);
    J (N, 2, 2) symmetric blocks, used when ``use_j`` (else the identity). Built per robot from
    the rows touching it: O(Σ_robots rows²), independent of N.
    """
    w = ai.shape[0]
    n = J.shape[0]
    count = np.zeros(n + 1, np.int64)
    for a in range(w):
        count[ai[a] + 1] += 1
        if acj[a, 0] != 0.0 or acj[a, 1] != 0.0:
            count[aj[a] + 1] += 1
    for r in range(n):
        count[r + 1] += count[r]
    fill = count[:-1].copy()
    ent_row = np.empty(count[n], np.int64)
    ent_c = np.empty((count[n], 2))
    for a in range(w):
        p = fill[ai[a]]
        ent_row[p] = a
        ent_c[p, 0] = aci[a, 0]
        ent_c[p, 1] = aci[a, 1]
        fill[ai[a]] += 1
        if acj[a, 0] != 0.0 or acj[a, 1] != 0.0:
            p = fill[aj[a]]
            ent_row[p] = a
            ent_c[p, 0] = acj[a, 0]
            ent_c[p, 1] = acj[a, 1]
            fill[aj[a]] += 1
    G = np.zeros((w, w))
    for r in range(n):
        for p in range(count[r], count[r + 1]):
            c0 = ent_c[p, 0]
            c1 = ent_c[p, 1]
            if use_j:
                d0 = J[r, 0, 0] * c0 + J[r, 0, 1] * c1
                d1 = J[r, 1, 0] * c0 + J[r, 1, 1] * c1
            else:
                d0 = c0
                d1 = c1
            a = ent_row[p]
            for q in range(count[r], count[r + 1]):
                G[a, ent_row[q]] += d0 * ent_c[q, 0] + d1 * ent_c[q, 1]
    return G


def warm_up_gram() -> None:
    """Compile (or load from the cache) :func:`gram_dense`; a no-op without numba."""
    if AVAILABLE:
        z = np.zeros((1, 2))
        gram_dense(np.zeros(1, np.int64), np.zeros(1, np.int64), np.ones((1, 2)), z,
                   np.zeros((1, 2, 2)), False)


__all__ = ["AVAILABLE", "jit", "gram_dense", "warm_up_gram"]
