"""The barrier QP solved by clarabel (interior point): the fallback and the reference.

Problem (REFERENCE.md §3), variables u (N, 2) stacked row-major, plus one slack
s_k ≥ 0 per *soft* row::

    min  Σ ½‖u_i − û_i‖² + ½ ρ Σ s_k²
    s.t. ci·u_i + cj·u_j ≤ b_hard            (every row)
         ci·u_i + cj·u_j − s_k ≤ b_soft_k     (soft rows: separation targets)
         ‖u_i‖ ≤ v_max                        (second-order cones, if max_speed is given)

The matrices are assembled as CSC from COO triplets without per-robot loops.
The solver status is checked; anything but ``Solved`` with a finite answer is a
failure (never an unconverged iterate).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .constraints import Rows


@dataclass(frozen=True)
class QPResult:
    """Outcome of one QP solve: u (N, 2) (zeros when not ok), ok, reason, iterations."""

    u: np.ndarray
    ok: bool
    reason: str
    iterations: int


_STATUS_REASON = {
    "PrimalInfeasible": "infeasible",
    "DualInfeasible": "dual infeasible",
    "AlmostPrimalInfeasible": "infeasible",
    "AlmostDualInfeasible": "dual infeasible",
    "MaxIterations": "iteration limit",
    "MaxTime": "time limit",
    "NumericalError": "numerical trouble",
    "InsufficientProgress": "numerical trouble (insufficient progress)",
    "AlmostSolved": "not converged to tolerance (almost solved)",
    "Unsolved": "unsolved",
    "CallbackTerminated": "terminated",
}


def _row_triplets(rows: Rows, row_offset: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets of the rows' coefficients on the stacked u (2N columns)."""
    m = rows.m
    r = np.arange(m) + row_offset
    two = rows.j >= 0
    ri = np.concatenate([r, r, r[two], r[two]])
    ci = np.concatenate([2 * rows.i, 2 * rows.i + 1, 2 * rows.j[two], 2 * rows.j[two] + 1])
    v = np.concatenate([rows.ci[:, 0], rows.ci[:, 1], rows.cj[two, 0], rows.cj[two, 1]])
    return ri, ci, v


def solve_qp(rows: Rows, nominal: np.ndarray, max_speed: float | None, *,
             b_hard: np.ndarray | None = None, soft: np.ndarray | None = None,
             b_soft: np.ndarray | None = None, soft_weight: float = 100.0,
             max_iter: int = 100, tol: float = 1e-9, discs: np.ndarray | None = None,
             time_limit: float | None = None) -> QPResult:
    """Solve the barrier QP for nominal (N, 2) m/s.

    rows: the linear rows; b_hard: their bounds (default rows.b); soft: indices
    of rows that also get a slack-penalised target b_soft (m/s); discs: (N,) bool robots
    that get the speed cone (default all, when max_speed is given); time_limit: clarabel's own
    wall-time limit in s (None: none; the answer is then refused as "time limit" when reached).
    """
    import clarabel
    import scipy.sparse as sp  # lazy: see test_devices_rps_startup_imports

    n = nominal.shape[0]
    nv = 2 * n
    b_hard = rows.b if b_hard is None else b_hard
    soft = np.zeros(0, dtype=np.int64) if soft is None else np.asarray(soft, dtype=np.int64)
    k = soft.size
    m = rows.m
    if n == 0:
        return QPResult(np.zeros((0, 2)), True, "empty", 0)

    # objective ½xᵀPx + qᵀx, P upper triangular (diagonal here)
    p_diag = np.concatenate([np.ones(nv), np.full(k, float(soft_weight))])
    P = sp.diags(p_diag, format="csc")
    q = np.concatenate([-nominal.reshape(-1), np.zeros(k)])

    ri, ci, vals = _row_triplets(rows, 0)
    parts_r, parts_c, parts_v = [ri], [ci], [vals]
    b_parts = [b_hard]
    if k:
        sub = rows.select(soft)
        sr, sc, sv = _row_triplets(sub, m)
        s_rows = m + np.arange(k)
        parts_r += [sr, s_rows, m + k + np.arange(k)]
        parts_c += [sc, nv + np.arange(k), nv + np.arange(k)]
        parts_v += [sv, -np.ones(k), -np.ones(k)]
        b_parts += [b_soft, np.zeros(k)]  # type: ignore[list-item]
    n_lin = m + 2 * k
    cones: list = []
    if n_lin:
        cones.append(clarabel.NonnegativeConeT(n_lin))
    coned = np.zeros(0, dtype=np.int64)
    if max_speed is not None:
        coned = np.arange(n) if discs is None else np.flatnonzero(discs)
    nc = coned.size
    if nc:
        # s = b − A x = [v_max, u_x, u_y] ∈ SOC(3) for every robot with a disc
        base = n_lin + 3 * np.arange(nc)
        parts_r += [base + 1, base + 2]
        parts_c += [2 * coned, 2 * coned + 1]
        parts_v += [-np.ones(nc), -np.ones(nc)]
        soc_b = np.zeros((nc, 3))
        soc_b[:, 0] = max_speed
        b_parts.append(soc_b.reshape(-1))
        cones += [clarabel.SecondOrderConeT(3)] * nc
    n_con = n_lin + 3 * nc
    if n_con == 0:
        return QPResult(nominal.copy(), True, "unconstrained", 0)
    A = sp.csc_matrix(
        (np.concatenate(parts_v), (np.concatenate(parts_r), np.concatenate(parts_c))),
        shape=(n_con, nv + k),
    )
    b = np.concatenate(b_parts)
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(A.data)) and np.all(np.isfinite(q))):
        return QPResult(np.zeros((n, 2)), False, "non-finite QP data", 0)

    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_iter = int(max_iter)
    settings.tol_gap_abs = tol
    settings.tol_gap_rel = tol
    settings.tol_feas = tol
    settings.presolve_enable = False
    if time_limit is not None:
        settings.time_limit = max(float(time_limit), 1e-6)
    try:
        solver = clarabel.DefaultSolver(P, q, A, b, cones, settings)
        sol = solver.solve()
    except Exception as exc:  # clarabel raises on malformed data; never let it reach the loop
        return QPResult(np.zeros((n, 2)), False, f"solver error: {exc}", 0)
    status = str(sol.status)
    iters = int(getattr(sol, "iterations", 0))
    if status != "Solved":
        return QPResult(np.zeros((n, 2)), False, _STATUS_REASON.get(status, status), iters)
    x = np.asarray(sol.x, dtype=float)
    if x.shape != (nv + k,) or not np.all(np.isfinite(x)):
        return QPResult(np.zeros((n, 2)), False, "solver returned a non-finite answer", iters)
    return QPResult(x[:nv].reshape(n, 2), True, "solved", iters)


def project_onto_polytope(nominal: np.ndarray, a: np.ndarray, b: np.ndarray, *, max_iter: int = 100,
                          tol: float = 1e-9) -> QPResult:
    """The point nearest ``nominal`` (n,) within ``a x ≤ b`` (a: (m, n) dense, b: (m,)): min ½‖x − x̂‖².

    rps 2.x's ``_solve_qp`` and scripts that build their own barrier rows use it (a dense QP of a few
    variables). ``u`` of the result is the (n,) answer (zeros when not ok); the status is checked as in
    :func:`solve_qp`.
    """
    import clarabel
    import scipy.sparse as sp  # lazy: see test_devices_rps_startup_imports

    x_hat = np.asarray(nominal, dtype=float).reshape(-1)
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float).reshape(-1)
    n = x_hat.size
    if a.ndim != 2 or a.shape != (b.size, n):
        return QPResult(np.zeros(n), False, f"constraint shapes {a.shape} and {b.shape} do not fit {n} variables", 0)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and np.all(np.isfinite(x_hat))):
        return QPResult(np.zeros(n), False, "non-finite QP data", 0)
    if b.size == 0:
        return QPResult(x_hat.copy(), True, "unconstrained", 0)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_iter = int(max_iter)
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
    try:
        sol = clarabel.DefaultSolver(sp.identity(n, format="csc"), -x_hat, sp.csc_matrix(a), b,
                                     [clarabel.NonnegativeConeT(b.size)], settings).solve()
    except Exception as exc:  # clarabel raises on malformed data
        return QPResult(np.zeros(n), False, f"solver error: {exc}", 0)
    status = str(sol.status)
    iters = int(getattr(sol, "iterations", 0))
    x = np.asarray(sol.x, dtype=float)
    if status != "Solved":
        return QPResult(np.zeros(n), False, _STATUS_REASON.get(status, status), iters)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        return QPResult(np.zeros(n), False, "solver returned a non-finite answer", iters)
    return QPResult(x, True, "solved", iters)
