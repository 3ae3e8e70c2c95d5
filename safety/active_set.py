"""Active-set solver for the barrier QP, certified by the KKT conditions.

The QP ``min ½‖u − û‖²  s.t.  A u ≤ b,  ‖u_i‖ ≤ v_max`` has an identity Hessian,
so for a working set W of rows held at equality the KKT system reduces to the
small sparse SPD system::

    (A_W A_Wᵀ) λ = A_W û − b_W,     u = û − A_Wᵀ λ.

The speed discs enter as tangent cuts ``n_iᵀu_i ≤ v_max`` whose normals are
rotated to ``u_i/‖u_i‖`` until they stop moving: at that fixed point the cut's
multiplier is the disc's (∇‖u_i‖ = n_i), so the KKT conditions of the conic
problem hold. Iterations add every violated row and drop every row with a
negative multiplier; the answer is returned only when it is certified:
λ ≥ 0, every built row satisfied to ``feas_tol`` (m/s), every speed ≤ v_max,
and the linear system solved to a small residual. Otherwise ``ok`` is False
and the caller falls back to clarabel.

Robots that no row touches are solved in closed form (û scaled into the disc).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .constraints import Rows

_DENSE_LIMIT = 250_000  # use a dense Cholesky while w × 2N stays below this
# Tikhonov term on the Gram matrix: working sets can hold linearly dependent rows
# (more rows than relative degrees of freedom in a cluster); the ridge selects the
# least-norm multipliers, and errors along null(A_Wᵀ) do not change u = û − A_Wᵀλ.
_RIDGE = 1e-11
_DEBUG = False
_AGGRESSIVE_ITERS = 8  # drop every negative multiplier at once, then switch to Lawson–Hanson steps


@dataclass(frozen=True)
class ActiveSetResult:
    """u (N, 2); ok; reason; active (m,) rows with a positive multiplier; speed_active (N,); iterations."""

    u: np.ndarray
    ok: bool
    reason: str
    active: np.ndarray
    speed_active: np.ndarray
    iterations: int


def _gram_solve(ai, ajj, aci, acj, rhs, n_robots):
    """Solve (A_W A_Wᵀ) λ = rhs for rows with coefficients aci on robot ai and acj on robot ajj."""
    w = ai.shape[0]
    if w * 2 * n_robots <= _DENSE_LIMIT:
        Ad = np.zeros((w, 2 * n_robots))
        r = np.arange(w)
        Ad[r, 2 * ajj] = acj[:, 0]
        Ad[r, 2 * ajj + 1] = acj[:, 1]
        Ad[r, 2 * ai] += aci[:, 0]
        Ad[r, 2 * ai + 1] += aci[:, 1]
        G = Ad @ Ad.T
        G[np.diag_indices_from(G)] += _RIDGE
        try:
            lam = sla.cho_solve(sla.cho_factor(G, check_finite=False), rhs, check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            return None
        return lam
    indptr = np.arange(0, 4 * w + 1, 4)
    cols = np.stack([2 * ai, 2 * ai + 1, 2 * ajj, 2 * ajj + 1], axis=1).reshape(-1)
    data = np.concatenate([aci, acj], axis=1).reshape(-1)
    A = sp.csr_matrix((data, cols, indptr), shape=(w, 2 * n_robots))
    G = (A @ A.T + _RIDGE * sp.identity(w, format="csr")).tocsc()
    try:
        lam = spla.splu(G, permc_spec="MMD_AT_PLUS_A").solve(rhs)
    except RuntimeError:  # exactly singular
        return None
    return lam


def solve_active_set(rows: Rows, nominal: np.ndarray, max_speed: float | None,
                     warm: np.ndarray | None = None, max_iter: int = 40,
                     feas_tol: float = 1e-10) -> ActiveSetResult:
    """Solve the barrier QP for nominal (N, 2) from working set ``warm`` ((m,) bool or None)."""
    n = nominal.shape[0]
    m = rows.m
    uh = nominal
    jj = rows.jj
    involved = np.zeros(n, dtype=bool)
    involved[rows.i] = True
    involved[jj] = True
    speed2 = np.einsum("kd,kd->k", uh, uh)
    vmax = np.inf if max_speed is None else float(max_speed)

    # closed form for robots without rows: û scaled into the speed disc
    base = uh.copy()
    free_fast = (~involved) & (speed2 > vmax * vmax)
    if free_fast.any():
        base[free_fast] *= (vmax / np.sqrt(speed2[free_fast]))[:, None]

    if warm is not None and warm.any():
        W = warm.copy()  # last tick's active rows; violated rows join after the first solve
    else:
        W = rows.lhs(uh) > rows.b
    cut = involved & (speed2 > vmax * vmax)
    normals = np.zeros((n, 2))
    if cut.any():
        normals[cut] = uh[cut] / np.sqrt(speed2[cut])[:, None]

    lam_rows = np.zeros(m)
    lam_cut = np.zeros(n)
    fail = lambda reason, it: ActiveSetResult(np.zeros((n, 2)), False, reason, W, cut, it)
    for it in range(1, max_iter + 1):
        aggressive = it <= _AGGRESSIVE_ITERS
        # subspace minimiser over the working set, stepping back along the segment from the
        # previous (non-negative) multipliers whenever one turns negative (Lawson–Hanson),
        # so the dual objective decreases monotonically and the iteration cannot cycle
        while True:
            idx = np.flatnonzero(W)
            cidx = np.flatnonzero(cut)
            ai = np.concatenate([rows.i[idx], cidx])
            aj = np.concatenate([jj[idx], cidx])
            aci = np.concatenate([rows.ci[idx], normals[cidx]])
            acj = np.concatenate([rows.cj[idx], np.zeros((cidx.size, 2))])
            ab = np.concatenate([rows.b[idx], np.full(cidx.size, vmax)])
            if ai.size == 0:
                lam, rhs = np.zeros(0), np.zeros(0)
                break
            rhs = np.einsum("kd,kd->k", aci, uh[ai]) + np.einsum("kd,kd->k", acj, uh[aj]) - ab
            lam = _gram_solve(ai, aj, aci, acj, rhs, n)
            if lam is None or not np.all(np.isfinite(lam)):
                return fail("singular working set", it)
            neg = lam < 0
            if _DEBUG: print('   inner', idx.size, cidx.size, int(neg.sum()), int(neg[idx.size:].sum()))
            if not neg.any():
                break
            old = np.concatenate([lam_rows[idx], lam_cut[cidx]])
            alpha = float(np.min(old[neg] / (old[neg] - lam[neg])))
            step = old + alpha * (lam - old)
            drop = neg & (step <= 1e-15 * max(1.0, float(np.max(old))))
            if aggressive:
                drop = neg
            if not drop.any():  # rounding: drop the most negative
                drop = lam == lam.min()
            step[drop] = 0.0
            lam_rows[idx] = step[: idx.size]
            lam_cut[cidx] = step[idx.size:]
            W[idx[drop[: idx.size]]] = False
            cut[cidx[drop[idx.size:]]] = False
        lam_rows[:] = 0.0
        lam_cut[:] = 0.0
        lam_rows[idx] = lam[: idx.size]
        lam_cut[cidx] = lam[idx.size:]
        u = base.copy()
        if ai.size:
            wx = lam[:, None] * aci
            wy = lam[:, None] * acj
            u[:, 0] -= np.bincount(ai, wx[:, 0], n) + np.bincount(aj, wy[:, 0], n)
            u[:, 1] -= np.bincount(ai, wx[:, 1], n) + np.bincount(aj, wy[:, 1], n)
        viol = (rows.lhs(u) - rows.b > feas_tol) & ~W
        sp2 = np.einsum("kd,kd->k", u, u)
        new_cut = involved & ~cut & (sp2 > vmax * vmax * (1 + 1e-12))
        moved = 0.0
        if cidx.size:
            sc = np.sqrt(sp2[cidx])
            if np.any(sc == 0):
                return fail("degenerate speed cut", it)
            nn = u[cidx] / sc[:, None]
            moved = float(np.max(np.abs(nn - normals[cidx])))
            normals[cidx] = nn
        if _DEBUG: print(it, int(W.sum()), int(cut.sum()), int(viol.sum()), int(new_cut.sum()), moved)
        if not viol.any() and not new_cut.any() and moved <= 1e-10:
            if ai.size:
                # complementarity: rows with a positive multiplier hold at equality
                eq = np.einsum("kd,kd->k", aci, u[ai]) + np.einsum("kd,kd->k", acj, u[aj]) - ab
                if float(np.max(np.abs(eq[lam > 0]), initial=0.0)) > 1e-8:
                    return fail("inaccurate linear solve", it)
            # the rotated cuts are tangent: bring the last rounding error inside the disc
            over = sp2 > vmax * vmax
            if over.any():
                s = np.sqrt(sp2[over])
                if np.any(s > vmax * (1 + 1e-7)):
                    return fail("speed bound not certified", it)
                u[over] *= (vmax / s)[:, None]
            if np.any(rows.lhs(u) - rows.b > 1e-8):
                return fail("rows not certified", it)
            return ActiveSetResult(u, True, "certified", W & (lam_rows > 0), cut & (lam_cut > 0), it)
        W |= viol
        if new_cut.any():
            normals[new_cut] = u[new_cut] / np.sqrt(sp2[new_cut])[:, None]
            cut |= new_cut
    return fail("active-set iteration limit", max_iter)
