"""Active-set solver for the barrier QP, certified by the KKT conditions.

The QP ``min ½‖u − û‖²  s.t.  A u ≤ b,  ‖u_i‖ ≤ v_max`` has an identity Hessian,
so for a working set W of rows held at equality the KKT system reduces to the
small sparse SPD system::

    (A_W A_Wᵀ) λ = A_W û − b_W,     u = û − A_Wᵀ λ.

Speed discs first enter as tangent cuts ``n_iᵀu_i ≤ v_max`` (normals rotated to
``u_i/‖u_i‖``) while the row working set settles: violated rows are added and
rows with negative multipliers dropped (all at once for the first iterations,
then by Lawson–Hanson ratio steps so the dual objective increases
monotonically and the iteration cannot cycle). Once the rows stop changing the
discs are handled exactly: with u(λ) = Π_D(û − A_Wᵀλ) (Π_D the projection on
the speed discs) the equations A_W u(λ) = b_W are solved by semismooth Newton
steps with the generalised Hessian A_W J A_Wᵀ, J = ∂Π_D (quadratic convergence
where the cut rotation alone converges linearly).

An answer is returned only when it is certified: λ ≥ 0, every built row
satisfied to ``feas_tol`` (m/s), rows with λ > 0 at equality, speeds ≤ v_max;
stationarity holds by construction. Otherwise ``ok`` is False and the caller
falls back to clarabel. Robots no row touches are solved in closed form.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from . import small_lapack
from .compiled import AVAILABLE as _COMPILED
from .compiled import gram_dense
from .constraints import Rows
from .small_kernels import gram_dense as _gram_small
from .small_kernels import small

_DENSE_ROWS = 400  # dense Cholesky of the Gram matrix up to this many working rows
_DIRECT_LIMIT = 40_000  # below this (rows × 2N) the dense A_W is formed directly
# Tikhonov term on the Gram matrix: working sets can hold linearly dependent rows
# (more rows than relative degrees of freedom in a cluster); the ridge selects the
# least-norm multipliers, and errors along null(A_Wᵀ) do not change u = û − A_Wᵀλ.
_RIDGE = 1e-11
_AGGRESSIVE_ITERS = 8  # drop every negative multiplier at once, then switch to Lawson–Hanson steps
_NEWTON_STEPS = 15
_EYE = np.eye(2)
FEAS_TOL = 1e-10  # m/s: a certified answer meets every row to this


@dataclass(frozen=True)
class ActiveSetResult:
    """u (N, 2); ok; reason; active (m,) rows with a positive multiplier; speed_active (N,); iterations;
    multipliers (m,) the rows' λ ≥ 0 of a certified answer (None otherwise)."""

    u: np.ndarray
    ok: bool
    reason: str
    active: np.ndarray
    speed_active: np.ndarray
    iterations: int
    multipliers: np.ndarray | None = None
    solves: int = 0  # factorisations of the working set's Gram matrix (the unit of the work cap)


def _project(w: np.ndarray, vmax: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Π_D(w) per robot; also the mask of robots outside the disc and their norms."""
    if vmax == math.inf:  # no disc: s2 > inf holds for no robot (not even s2 = inf)
        return w.copy(), np.zeros(w.shape[0], dtype=bool), np.zeros(0)
    s2 = np.einsum("kd,kd->k", w, w)
    over = s2 > vmax * vmax
    u = w.copy()
    norms = np.sqrt(s2[over])
    if over.any():
        u[over] *= (vmax / norms)[:, None]
    return u, over, norms


def clip_speed(u: np.ndarray, vmax: float) -> np.ndarray:
    """u (N, 2) with every robot's speed scaled onto ‖u_i‖ ≤ v_max *exactly* in floating point.

    Robots within the bound are returned bit for bit (a new array either way); the
    radial projection alone can land one ulp outside, so those are nudged inwards.
    """
    out = np.array(u, dtype=float, copy=True)
    if not np.isfinite(vmax):
        return out
    return _clip_into(out, vmax, np.einsum("kd,kd->k", out, out))


def _clip_into(out: np.ndarray, vmax: float, s2: np.ndarray) -> np.ndarray:
    """:func:`clip_speed`'s scaling of ``out`` (N, 2) (a float array of the caller's own, changed in place and
    returned) whose squared speeds are ``s2`` (N,) (``einsum("kd,kd->k", out, out)``), finite ``vmax`` m/s."""
    limit = vmax * vmax
    over = (s2 > limit).nonzero()[0]
    if over.size:
        out[over] *= (vmax / np.sqrt(s2[over]))[:, None]
        for _ in range(8):
            still = over[np.einsum("kd,kd->k", out[over], out[over]) > limit]
            if not still.size:
                break
            out[still] *= 1.0 - 4.0 * np.finfo(float).eps
    return out


def _dense_spd_solve(G: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """Solve (G + ridge·I) x = rhs for a small dense Gram matrix (LAPACK, little call overhead).

    Cholesky (half the work of LU; :mod:`~swarmdeck.safety.small_lapack`); a Gram matrix that is not
    numerically positive definite
    (dependent rows beyond what the ridge covers) goes through LU.
    """
    G.flat[:: G.shape[0] + 1] += _RIDGE  # the diagonal (np.diag_indices_from's elements, the same additions)
    try:
        return small_lapack.cho_solve(G, rhs)  # scipy.linalg's cho_factor/cho_solve without importing scipy.linalg
    except np.linalg.LinAlgError:
        pass
    try:
        return np.linalg.solve(G, rhs)
    except np.linalg.LinAlgError:
        return None


class _Working:
    """Rows held at equality, as flat arrays (single-robot rows have cj = 0, aj = ai)."""

    def __init__(self, ai: np.ndarray, aj: np.ndarray, aci: np.ndarray, acj: np.ndarray, b: np.ndarray, n: int) -> None:
        self.ai, self.aj, self.aci, self.acj, self.b, self.n = ai, aj, aci, acj, b, n

    def At(self, lam: np.ndarray) -> np.ndarray:
        """A_Wᵀλ as (N, 2)."""
        n = self.n
        out = np.empty((n, 2))
        wi = lam[:, None] * self.aci
        wj = lam[:, None] * self.acj
        out[:, 0] = np.bincount(self.ai, wi[:, 0], n) + np.bincount(self.aj, wj[:, 0], n)
        out[:, 1] = np.bincount(self.ai, wi[:, 1], n) + np.bincount(self.aj, wj[:, 1], n)
        return out

    def A(self, u: np.ndarray) -> np.ndarray:
        return np.einsum("kd,kd->k", self.aci, u[self.ai]) + np.einsum("kd,kd->k", self.acj, u[self.aj])

    def solve(self, J: np.ndarray | None, rhs: np.ndarray) -> np.ndarray | None:
        """Solve (A_W J A_Wᵀ + ridge·I) δ = rhs; J (N, 2, 2) blocks or None for the identity.

        A_W is assembled as CSR straight from the row arrays (four entries per row);
        the Gram matrix is formed sparse, then factorised densely (Cholesky) while
        small, by sparse LU beyond.
        """
        w, n = self.ai.shape[0], self.n
        if _COMPILED and w <= _DENSE_ROWS:  # compiled: per robot, independent of N
            use_j = J is not None
            Jc = np.ascontiguousarray(J, dtype=float) if use_j else np.zeros((n, 2, 2))
            gram = _gram_small if small(n) else gram_dense  # the same bits; plain Python needs no numba
            G = gram(np.ascontiguousarray(self.ai, dtype=np.int64), np.ascontiguousarray(self.aj, dtype=np.int64),
                           np.ascontiguousarray(self.aci, dtype=float), np.ascontiguousarray(self.acj, dtype=float),
                           Jc, use_j)
            return _dense_spd_solve(G, rhs)
        if w * 2 * n <= _DIRECT_LIMIT:  # small: dense A_W straight from the rows
            Ad = np.zeros((w, n, 2))
            r = np.arange(w)
            Ad[r, self.aj] = self.acj
            Ad[r, self.ai] += self.aci
            B = Ad if J is None else np.einsum("wnd,nde->wne", Ad, J)
            Gd = B.reshape(w, 2 * n) @ Ad.reshape(w, 2 * n).T
            return _dense_spd_solve(Gd, rhs)
        import scipy.sparse as sp  # lazy: see test_devices_rps_startup_imports
        import scipy.sparse.linalg as spla

        indptr = np.arange(0, 4 * w + 1, 4)
        cols = np.stack([2 * self.ai, 2 * self.ai + 1, 2 * self.aj, 2 * self.aj + 1], axis=1).reshape(-1)
        data = np.concatenate([self.aci, self.acj], axis=1).reshape(-1)
        A = sp.csr_matrix((data, cols, indptr), shape=(w, 2 * n))
        if J is None:
            G = A @ A.T
        else:
            Jb = sp.bsr_matrix((J, np.arange(n), np.arange(n + 1)), shape=(2 * n, 2 * n)).tocsr()
            G = A @ (Jb @ A.T)
        if w <= _DENSE_ROWS:
            return _dense_spd_solve(G.toarray(), rhs)
        G = (G + _RIDGE * sp.identity(w, format="csr")).tocsc()
        try:
            # symmetric mode (diagonal pivots, the ordering of G + Gᵀ): half the time of the default
            return spla.splu(G, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve(rhs)
        except RuntimeError:  # exactly singular
            return None


def _newton_discs(work: _Working, uh: np.ndarray, vmax: float, lam0: np.ndarray, count: list[int],
                  cap: int | None) -> tuple[np.ndarray, np.ndarray] | None:
    """Solve A_W Π_D(û − A_Wᵀλ) = b_W for λ (consistent working set), or None.

    ``count`` (one int, this call's own tally) gains one per factorisation; None once it reaches ``cap``."""
    lam = lam0.copy()
    for _ in range(_NEWTON_STEPS):
        w = uh - work.At(lam)
        u, over, norms = _project(w, vmax)
        F = work.A(u) - work.b
        if float(np.max(np.abs(F), initial=0.0)) <= 1e-12:
            return lam, u
        if cap is not None and count[0] >= cap:
            return None
        count[0] += 1
        J = np.broadcast_to(_EYE, (work.n, 2, 2)).copy()
        if over.any():
            wh = w[over] / norms[:, None]
            J[over] = (vmax / norms)[:, None, None] * (_EYE - wh[:, :, None] * wh[:, None, :])
        delta = work.solve(J, F)
        if delta is None or not np.all(np.isfinite(delta)):
            return None
        lam = lam + delta
    return None


def solve_active_set(rows: Rows, nominal: np.ndarray, max_speed: float | None,
                     warm: np.ndarray | None = None, max_iter: int = 40,
                     feas_tol: float = FEAS_TOL, multipliers: np.ndarray | None = None,
                     max_solves: int | None = None, deadline: float | None = None) -> ActiveSetResult:
    """Solve the barrier QP for nominal (N, 2) from working set ``warm`` ((m,) bool or None).

    ``max_solves``: the work cap, factorisations of the working set's Gram matrix (each iteration
    and each disc Newton step is one); once it is reached the call fails at once with reason
    "work cap" (deterministic: counts, never time). ``solves`` in the result is the count spent.
    ``deadline`` (a ``time.perf_counter()`` value, for the live console only): the same, by wall time.

    ``multipliers`` ((m,) ≥ 0, e.g. a dual ascent's, positive on ``warm``): a dual-feasible start.
    Rows then leave the working set by Lawson–Hanson steps from it from the first iteration (the
    row whose multiplier reaches zero first — a wrongly predicted row has a small one), never by
    dropping every negative multiplier at once, which on degenerate working sets (dependent rows,
    non-unique multipliers) also drops rows that belong.
    """
    n = nominal.shape[0]
    m = rows.m
    uh = nominal
    jj = rows.jj
    involved = np.zeros(n, dtype=bool)
    involved[rows.i] = True
    involved[jj] = True
    vmax = np.inf if max_speed is None else float(max_speed)
    finite = math.isfinite(vmax)

    # closed form for robots without rows: û scaled into the speed disc
    base, _, _ = _project(uh, vmax)
    base[involved] = uh[involved]

    if warm is not None and warm.any():
        W = warm.copy()  # last tick's active rows; violated rows join after the first solve
    else:
        W = rows.lhs(uh) > rows.b
    # speed cuts join after the first solve, in the direction of the answer (û's is often poor)
    cut = np.zeros(n, dtype=bool)
    normals = np.zeros((n, 2))
    lam_rows = np.zeros(m) if multipliers is None else np.where(W, multipliers, 0.0)
    first_aggressive = 0 if multipliers is not None else _AGGRESSIVE_ITERS
    lam_cut = np.zeros(n)
    count = [0]  # this call's factorisations

    def fail(reason: str, it: int) -> ActiveSetResult:
        return ActiveSetResult(np.zeros((n, 2)), False, reason, W, cut, it, solves=count[0])

    def certify(u: np.ndarray, work: _Working | None, lam: np.ndarray, it: int,
                slack: np.ndarray | None = None, rows_of_work: np.ndarray | None = None,
                squared: np.ndarray | None = None) -> ActiveSetResult | None:
        # slack: rows.lhs(u) − rows.b when the caller has it for this u already; rows_of_work: the rows ``work``
        # holds, when it holds rows only (no speed cut): its residuals are then those rows' slack (the same
        # products and sums row by row; at most the sign of a zero differs, which |·| below cannot see);
        # squared: einsum("kd,kd->k", u, u) when the caller has it
        if ((rows.lhs(u) - rows.b if slack is None else slack) > feas_tol).any():
            return None
        if work is not None and lam.size:
            eq = work.A(u) - work.b if slack is None or rows_of_work is None else slack[rows_of_work]
            if float(np.abs(eq[lam > 0]).max(initial=0.0)) > 1e-8:
                return None
        speed = np.einsum("kd,kd->k", u, u) if squared is None else squared
        if (speed > (vmax * (1 + 1e-9)) ** 2).any():
            return None
        u = u.astype(float) if not finite else _clip_into(u.astype(float), vmax, speed)  # rounding only (clip_speed)
        held = W & (lam_rows > 0)
        return ActiveSetResult(u, True, "certified", held, speed >= vmax * vmax * (1 - 1e-9), it,
                               np.where(held, lam_rows, 0.0), count[0])

    for it in range(1, max_iter + 1):
        aggressive = it <= first_aggressive
        while True:
            idx = W.nonzero()[0]  # np.flatnonzero of a 1-D array
            cidx = cut.nonzero()[0]
            if cidx.size:
                work = _Working(np.concatenate([rows.i[idx], cidx]), np.concatenate([jj[idx], cidx]),
                                np.concatenate([rows.ci[idx], normals[cidx]]),
                                np.concatenate([rows.cj[idx], np.zeros((cidx.size, 2))]),
                                np.concatenate([rows.b[idx], np.full(cidx.size, vmax)]), n)
            else:  # no speed cut: the working rows alone (what the concatenations give, without copying twice)
                work = _Working(rows.i[idx], jj[idx], rows.ci[idx], rows.cj[idx], rows.b[idx], n)
            if work.ai.size == 0:
                lam = np.zeros(0)
                break
            rhs = work.A(uh) - work.b
            if (max_solves is not None and count[0] >= max_solves) or (
                    deadline is not None and time.perf_counter() >= deadline):
                return fail("work cap", it)
            count[0] += 1
            lam = work.solve(None, rhs)  # type: ignore[assignment]
            if lam is None or not np.isfinite(lam).all():
                return fail("singular working set", it)
            neg = lam < 0
            if not neg.any():
                break
            old = np.concatenate([lam_rows[idx], lam_cut[cidx]])
            if aggressive:
                drop = neg
                step = np.where(neg, 0.0, lam)
            else:  # Lawson–Hanson: step back to the first multiplier that reaches zero
                alpha = float(np.min(old[neg] / (old[neg] - lam[neg])))
                step = old + alpha * (lam - old)
                drop = neg & (step <= 1e-15 * max(1.0, float(np.max(old))))
                if not drop.any():
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
        u = base - work.At(lam) if lam.size else base.copy()
        slack = rows.lhs(u) - rows.b
        viol = (slack > feas_tol) & ~W
        sp2 = np.einsum("kd,kd->k", u, u)
        # no speed bound (vmax = inf): sp2 > inf holds for no robot, no cut is ever made
        new_cut = involved & ~cut & (sp2 > vmax * vmax * (1 + 1e-12)) if finite else None
        if not viol.any() and (new_cut is None or not new_cut.any()):
            if cidx.size == 0:
                done = certify(u, work, lam, it, slack, idx, sp2)
                return done if done is not None else fail("not certified", it)
            # the rows have settled: solve the discs exactly (Newton on u(λ) = Π_D(û − Aᵀλ))
            rw = _Working(rows.i[idx], jj[idx], rows.ci[idx], rows.cj[idx], rows.b[idx], n)
            sol = (_newton_discs(rw, uh, vmax, lam[: idx.size], count, max_solves) if idx.size
                   else (np.zeros(0), _project(uh, vmax)[0]))
            if sol is None and max_solves is not None and count[0] >= max_solves:
                return fail("work cap", it)
            if sol is not None and np.all(sol[0] >= 0):
                lam_rows[:] = 0.0
                lam_rows[idx] = sol[0]
                done = certify(sol[1], rw if idx.size else None, sol[0], it)
                if done is not None:
                    return done
                viol = (rows.lhs(sol[1]) - rows.b > feas_tol) & ~W
                if viol.any():
                    u = sol[1]
                    sp2 = np.einsum("kd,kd->k", u, u)
        if cidx.size:  # rotate the cuts to the answer's direction
            sc = np.sqrt(sp2[cidx])
            if np.any(sc == 0):
                return fail("degenerate speed cut", it)
            normals[cidx] = u[cidx] / sc[:, None]
        W |= viol
        if new_cut is not None and new_cut.any():
            normals[new_cut] = u[new_cut] / np.sqrt(sp2[new_cut])[:, None]
            cut |= new_cut
    return fail("active-set iteration limit", max_iter)
