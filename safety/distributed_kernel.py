"""The distributed barrier's per-robot QPs compiled: :func:`safety.distributed.solve_small_qps` robot by robot.

One numba kernel (``core.compiled.jit``: ``cache=True, nogil=True``, so a console worker thread running it does
not hold the GIL) does what ``solve_small_qps``'s numpy path does with padded (robots × rows) arrays, one robot at
a time over its own rows (grouped by a counting sort): the same pruning, the same stage 1 (the most violated line,
accepted on its KKT multipliers), the same stage 2 (the cheapest optimum over the hot lines), the same
certificate. Every floating-point expression is the numpy path's, term for term and in the same order (two-term
products and sums, no fused multiply-add: numba compiles without ``fastmath``), and ties are broken the same way
(the first row in the caller's order), so the answers are the numpy path's **bit for bit**
(``tests/safety/test_safety_distributed_compiled.py`` checks it on random and jammed problems).

Cost: O(Σ_robots rows_kept²) like the numpy path, without its padding, temporaries and per-call overhead
(bench/RESULTS.md, "distributed barrier", "Compiled, consensus passes").
"""
from __future__ import annotations

import numpy as np

from swarmdeck.core.compiled import AVAILABLE, jit

_SIGN_TOL = 1e-12  # the same tolerances as safety.distributed (m/s)
_FEAS_TOL = 1e-10
_DET_TOL = 1e-12


@jit
def _line_optimum(A: np.ndarray, B: np.ndarray, lo_row: int, hi_row: int, k: int, ux: float, uy: float,
                  disc: bool, vmax: float, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """The optimum on line ``k`` of one robot (rows ``lo_row:hi_row`` of A (·, 2), B): writes
    out[0:2] the candidate, out[2] its cost (inf: none), out[3] the clamping row (−1: none, else its
    position), out[4] 1.0 when it ends on the disc. ``safety.distributed._line_optima`` for one (s, h)."""
    ak0 = A[k, 0]
    ak1 = A[k, 1]
    bk = B[k]
    pk0 = -ak1
    pk1 = ak0
    tp = pk0 * ux + pk1 * uy
    hi = np.inf
    lo = -np.inf
    hi_l = lo_row  # np.argmin of an all-inf row is its first entry
    lo_l = lo_row
    empty = False
    for l in range(lo_row, hi_row):
        ax = A[l, 0]
        ay = A[l, 1]
        c = pk0 * ax + pk1 * ay
        rhs = B[l] - bk * (ak0 * ax + ak1 * ay)
        if c > _DET_TOL:
            bound = rhs / c
            if bound < hi:
                hi = bound
                hi_l = l
        elif c < -_DET_TOL:
            bound = rhs / c
            if bound > lo:
                lo = bound
                lo_l = l
        elif rhs < -_FEAS_TOL:
            empty = True
    hi_disc = False
    lo_disc = False
    if disc:
        half = np.sqrt(max(vmax * vmax - bk * bk, 0.0))
        if abs(bk) > vmax:
            empty = True
        hi_disc = half < hi
        lo_disc = -half > lo
        hi = min(hi, half)
        lo = max(lo, -half)
    if lo > hi + _FEAS_TOL:
        empty = True
    t = min(max(tp, lo), hi)
    c0 = bk * ak0 + t * pk0
    c1 = bk * ak1 + t * pk1
    d0 = c0 - ux
    d1 = c1 - uy
    out[0] = c0
    out[1] = c1
    out[2] = np.inf if empty else d0 * d0 + d1 * d1
    at_hi = tp > hi
    at_lo = tp < lo
    if at_hi and not hi_disc:
        out[3] = float(hi_l)
    elif at_lo and not lo_disc:
        out[3] = float(lo_l)
    else:
        out[3] = -1.0
    out[4] = 1.0 if (at_hi and hi_disc) or (at_lo and lo_disc) else 0.0


@jit
def solve_small_qps_kernel(owner: np.ndarray, a: np.ndarray, b: np.ndarray, nominal: np.ndarray, disc: bool,
                           vmax: float, lim: float, todo: np.ndarray, use_todo: bool
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:  # pragma: no cover
    """Every robot's own QP; the arguments and results of ``safety.distributed.solve_small_qps``
    (``disc``/``vmax`` its ``max_speed``, ``lim`` its ``reach`` or inf, ``todo`` used when ``use_todo``).

    Returns (u (N, 2), solved (N,), active (M,), on_disc (N,), n_bad): n_bad 0 means every robot's
    nominal was feasible (u is a copy of the nominal)."""
    n = nominal.shape[0]
    m = b.shape[0]
    u = nominal.copy()
    active = np.zeros(m, np.bool_)
    on_disc = np.zeros(n, np.bool_)
    solved = np.ones(n, np.bool_)
    if n == 0:
        return u, solved, active, on_disc, 0
    lhs = np.empty(m)
    bad = np.zeros(n, np.bool_)
    for k in range(m):
        o = owner[k]
        lhs[k] = a[k, 0] * nominal[o, 0] + a[k, 1] * nominal[o, 1]
        if lhs[k] > b[k]:
            bad[o] = True
    speed = np.empty(n)
    tau = np.empty(n)
    n_bad = 0
    for r in range(n):
        speed[r] = np.sqrt(nominal[r, 0] * nominal[r, 0] + nominal[r, 1] * nominal[r, 1])
        if disc and speed[r] > vmax:
            bad[r] = True
        if use_todo and not todo[r]:
            bad[r] = False
        if bad[r]:
            n_bad += 1
        tau[r] = min(1.0, vmax / max(speed[r], 1e-300)) if disc else 1.0
    if n_bad == 0:
        return u, solved, active, on_disc, 0
    # the pruning radius (solve_small_qps: where u = τ·û is feasible, rows farther than (1 − τ)‖û‖ hold)
    for k in range(m):
        if b[k] < 0:
            tr = -1.0
        elif lhs[k] > 0:
            tr = b[k] / lhs[k]
        else:
            tr = np.inf
        o = owner[k]
        if tr < tau[o]:
            tau[o] = tr
    radius = np.empty(n)
    for r in range(n):
        radius[r] = (1.0 - min(max(tau[r], 0.0), 1.0)) * speed[r] if tau[r] >= 0 else np.inf
    # the kept rows of the robots to solve, grouped by robot in the caller's order (a counting sort)
    ptr = np.zeros(n + 1, np.int64)
    keep = np.zeros(m, np.bool_)
    norm = np.empty(m)
    for k in range(m):
        o = owner[k]
        nk = np.sqrt(a[k, 0] * a[k, 0] + a[k, 1] * a[k, 1])
        norm[k] = nk
        if bad[o] and nk > 0 and b[k] < lim * nk and b[k] - lhs[k] <= radius[o] * nk:
            keep[k] = True
            ptr[o + 1] += 1
    for r in range(n):
        ptr[r + 1] += ptr[r]
    fill = ptr[:-1].copy()
    total = ptr[n]
    A = np.empty((total, 2))
    B = np.empty(total)
    where = np.empty(total, np.int64)
    for k in range(m):
        if keep[k]:
            o = owner[k]
            p = fill[o]
            fill[o] += 1
            A[p, 0] = a[k, 0] / norm[k]
            A[p, 1] = a[k, 1] / norm[k]
            B[p] = b[k] / norm[k]
            where[p] = k
    excess = np.empty(total)
    out = np.empty(5)
    for r in range(n):
        if not bad[r]:
            continue
        r0 = ptr[r]
        r1 = ptr[r + 1]
        ux = nominal[r, 0]
        uy = nominal[r, 1]
        scale = min(1.0, vmax / max(speed[r], 1e-300)) if disc else 1.0
        rx = ux * scale
        ry = uy * scale
        r_ok = True
        k1 = -1
        worst = -np.inf
        any_hot = False
        for p in range(r0, r1):
            e = A[p, 0] * rx + A[p, 1] * ry - B[p]
            excess[p] = e
            if e > _FEAS_TOL:
                r_ok = False
            if e > -_SIGN_TOL:
                any_hot = True
                if e > worst:
                    worst = e
                    k1 = p
        got = False
        bx = 0.0
        by = 0.0
        best_k = -1
        best_l = -1
        best_disc = False
        if r_ok:
            bx = rx
            by = ry
            got = True
            best_disc = scale < 1.0
        elif any_hot:
            # stage 1: the most violated line, accepted when its multipliers are ≥ 0
            _line_optimum(A, B, r0, r1, k1, ux, uy, disc, vmax, out)
            cx = out[0]
            cy = out[1]
            l1 = int(out[3])
            d1 = out[4] != 0.0
            ak0 = A[k1, 0]
            ak1 = A[k1, 1]
            if l1 >= 0:
                g0 = A[l1, 0]
                g1 = A[l1, 1]
            elif d1:
                g0 = cx
                g1 = cy
            else:
                g0 = 0.0
                g1 = 0.0
            q0 = ux - cx
            q1 = uy - cy
            det = ak0 * g1 - ak1 * g0
            two = l1 >= 0 or d1
            if two:
                lam = (q0 * g1 - q1 * g0) / det if det != 0.0 else np.nan
                nu = (ak0 * q1 - ak1 * q0) / det if det != 0.0 else np.nan
            else:
                lam = q0 * ak0 + q1 * ak1
                nu = 0.0
            if (np.isfinite(out[2]) and (not two or abs(det) > _DET_TOL)
                    and lam >= -_SIGN_TOL and nu >= -_SIGN_TOL):
                bx = cx
                by = cy
                best_k = k1
                best_l = l1
                best_disc = d1
                got = True
            if not got:
                # stage 2: the cheapest optimum over all hot lines (the first of equal costs)
                cost = np.inf
                for p in range(r0, r1):
                    if excess[p] > -_SIGN_TOL:
                        _line_optimum(A, B, r0, r1, p, ux, uy, disc, vmax, out)
                        if out[2] < cost:
                            cost = out[2]
                            bx = out[0]
                            by = out[1]
                            best_k = p
                            best_l = int(out[3])
                            best_disc = out[4] != 0.0
                got = np.isfinite(cost)
        # certify against all of the robot's kept rows, and the disc
        if got:
            for p in range(r0, r1):
                if not (A[p, 0] * bx + A[p, 1] * by <= B[p] + _FEAS_TOL):
                    got = False
                    break
        if got and disc:
            sp2 = bx * bx + by * by
            lim2 = vmax * (1 + 1e-9)
            if not (sp2 <= lim2 * lim2):
                got = False
            elif sp2 > vmax * vmax:
                f = vmax / np.sqrt(sp2)
                bx = bx * f
                by = by * f
        if got:
            u[r, 0] = bx
            u[r, 1] = by
            if best_k >= 0:
                active[where[best_k]] = True
            if best_l >= 0:
                active[where[best_l]] = True
            if best_disc:
                on_disc[r] = True
        else:
            u[r, 0] = 0.0
            u[r, 1] = 0.0
            solved[r] = False
    return u, solved, active, on_disc, n_bad






@jit
def reallocate_kernel(owner: np.ndarray, a: np.ndarray, b: np.ndarray, u: np.ndarray,
                      n_pairs: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """``safety.distributed.reallocate_halves`` robot pair by robot pair, the same arithmetic (bit for bit)."""
    out = b.copy()
    loosened = np.zeros(u.shape[0], np.bool_)
    for k in range(n_pairs):
        oi = owner[k]
        oj = owner[n_pairs + k]
        ci = a[k, 0] * u[oi, 0] + a[k, 1] * u[oi, 1]
        cj = a[n_pairs + k, 0] * u[oj, 0] + a[n_pairs + k, 1] * u[oj, 1]
        half = b[k]
        bind_i = ci >= half - _FEAS_TOL
        bind_j = cj >= half - _FEAS_TOL
        total = 2.0 * half
        if bind_i and not bind_j:
            out[k] = total - cj
            out[n_pairs + k] = cj
            loosened[oi] = True
        elif bind_j and not bind_i:
            out[k] = ci
            out[n_pairs + k] = total - ci
            loosened[oj] = True
        else:
            out[k] = half
            out[n_pairs + k] = half
    return out, loosened


@jit
def worst_row(ri: np.ndarray, rj: np.ndarray, ci: np.ndarray, cj: np.ndarray, b: np.ndarray,
              u: np.ndarray) -> tuple[float, int]:  # pragma: no cover - compiled
    """(largest ``ci·u_ri + cj·u_rj − b`` over the rows, its first row; −inf, −1 without rows): ``Rows.lhs``'s
    arithmetic (rj = ri and cj = 0 for single-robot rows); a NaN excess is returned at once, at its row."""
    worst = -np.inf
    at = -1
    for k in range(b.shape[0]):
        i = ri[k]
        j = rj[k]
        e = (ci[k, 0] * u[i, 0] + ci[k, 1] * u[i, 1]) + (cj[k, 0] * u[j, 0] + cj[k, 1] * u[j, 1]) - b[k]
        if e != e:  # NaN: the worst there is (np.argmax's first NaN), so the certificate fails closed
            return e, k
        if e > worst or at < 0:
            worst = e
            at = k
    return worst, at


@jit
def consensus_kernel(owner: np.ndarray, a: np.ndarray, half: np.ndarray, b: np.ndarray, u: np.ndarray,
                     n_pairs: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """``safety.distributed.consensus_shares`` pair by pair, the same arithmetic (bit for bit); ``half`` (M,) the
    half/half split's bounds (``split.b``), ``b`` (M,) the last pass's."""
    out = b.copy()
    grown = np.zeros(u.shape[0], np.bool_)
    for k in range(n_pairs):
        oi = owner[k]
        oj = owner[n_pairs + k]
        ci = a[k, 0] * u[oi, 0] + a[k, 1] * u[oi, 1]
        cj = a[n_pairs + k, 0] * u[oj, 0] + a[n_pairs + k, 1] * u[oj, 1]
        total = half[k] + half[n_pairs + k]
        bi = ci + 0.5 * (total - ci - cj)
        bj = total - bi
        out[k] = bi
        out[n_pairs + k] = bj
        if bi > b[k]:
            grown[oi] = True
        if bj > b[n_pairs + k]:
            grown[oj] = True
    return out, grown



@jit
def split_kernel(ri: np.ndarray, rj: np.ndarray, ci: np.ndarray, cj: np.ndarray,
                 b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """``safety.distributed.split_rows``'s arrays (owner, a, b, source): the pair rows' i halves, their j halves,
    then the single-robot rows, each in row order (the same values: copies and exact halvings)."""
    m = b.shape[0]
    n_pairs = 0
    for k in range(m):
        if rj[k] >= 0:
            n_pairs += 1
    total = m + n_pairs
    owner = np.empty(total, np.int64)
    a = np.empty((total, 2))
    bb = np.empty(total)
    source = np.empty(total, np.int64)
    p = 0
    q = n_pairs
    s = 2 * n_pairs
    for k in range(m):
        if rj[k] >= 0:
            owner[p] = ri[k]
            a[p, 0] = ci[k, 0]
            a[p, 1] = ci[k, 1]
            bb[p] = 0.5 * b[k]
            source[p] = k
            owner[q] = rj[k]
            a[q, 0] = cj[k, 0]
            a[q, 1] = cj[k, 1]
            bb[q] = 0.5 * b[k]
            source[q] = k
            p += 1
            q += 1
        else:
            owner[s] = ri[k]
            a[s, 0] = ci[k, 0]
            a[s, 1] = ci[k, 1]
            bb[s] = b[k]
            source[s] = k
            s += 1
    return owner, a, bb, source


def warm_up_distributed() -> None:
    """Compile (or load from numba's cache) the kernels above on a two-robot problem, once per process (called by
    ``dual_ascent.warm_up``, i.e. by ``SafetyFilter()``, never inside a tick); a no-op without numba."""
    if not AVAILABLE:
        return
    owner = np.array([0, 1], dtype=np.int64)
    a = np.array([[-1.0, 0.0], [1.0, 0.0]])
    b = np.array([0.01, 0.01])
    u = np.array([[0.1, 0.0], [-0.1, 0.0]])
    solve_small_qps_kernel(owner, a, b, u, True, 0.2, 0.2, np.zeros(0, np.bool_), False)
    reallocate_kernel(owner, a, b, u, 1)
    consensus_kernel(owner, a, b, b, u, 1)
    split_kernel(np.array([0]), np.array([1]), a[:1], a[1:], b[:1])
    worst_row(np.array([0]), np.array([1]), a[:1], a[1:], b[:1], u)


__all__ = ["consensus_kernel", "reallocate_kernel", "solve_small_qps_kernel", "split_kernel", "warm_up_distributed",
           "worst_row"]
