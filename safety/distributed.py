"""The distributed barrier: every robot solves its own 2-variable QP (REFERENCE.md §12).

Wang, Ames, Egerstedt (T-RO 2017, §V), decentralised form. The pair row of the
centralised QP (REFERENCE.md §3, normalised as in :mod:`constraints`)::

    n_ijᵀ(u_j − u_i) ≤ b_ij,     b_ij = γκ(h_ij)/(2‖x_i − x_j‖)

is split half/half: robot i keeps ``−n_ijᵀu_i ≤ b_ij/2`` and robot j keeps
``n_ijᵀu_j ≤ b_ij/2``. Adding the two halves gives the pair row back, so any
set of commands that satisfies every robot's own rows satisfies every pair
row of the centralised QP: the closed loop stays safe exactly as under the
centralised filter, only more conservatively (each robot assumes its
neighbour does just its half). Single-robot rows (walls, obstacles, the
unicycle's wheel-limit rows) stay whole with their robot.

Each robot i then solves::

    min ‖u_i − û_i‖²  s.t.  a_kᵀu_i ≤ b_k (its rows),  ‖u_i‖ ≤ v_max (if a disc is given)

exactly, by enumerating the active sets of size ≤ 2 (in the plane, Carathéodory:
the normal cone at the optimum is spanned by at most two active constraints):
the unconstrained point, the projection on one line, the vertex of two lines,
the disc's radial point, the two points where a line meets the circle. A
candidate whose multipliers are ≥ 0 and which satisfies all of the robot's
rows is the (unique) optimum — the KKT conditions are sufficient for this
convex problem. Everything is vectorised across robots (padded arrays, one
numpy expression per candidate family); there is no general solver and no
per-robot Python loop. Rows with ``b ≥ reach`` (every feasible command has
‖u‖ ≤ reach) are redundant and left out of the enumeration; every answer is
checked against all rows afterwards.

A second pass gives each pair's unused half to the robot that needed it
(:func:`reallocate_halves`), and optional consensus passes share each pair's
remaining slack at the last answer equally (:func:`consensus_shares`,
``BarrierConfig.distributed_consensus_passes``): any split whose two shares add
up to the row is exactly as safe. With numba the per-robot QPs run in one
compiled kernel (:mod:`safety.distributed_kernel`), the same answers bit for bit.

Robots already inside the unsafe set (h < 0) aim at separating: their halves
ask for ``−recovery_speed/2`` each; a robot whose separation targets conflict
(its own QP is infeasible) falls back to "no further approach" (bounds
clipped at 0, where u = 0 is always feasible). The halves still add up to a
row no weaker than "no further approach".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarmdeck.core.compiled import AVAILABLE as _COMPILED

from .config import BarrierConfig
from .constraints import LIMIT, Rows
from .distributed_kernel import consensus_kernel, reallocate_kernel, solve_small_qps_kernel, split_kernel, worst_row
from .small_kernels import small

_SIGN_TOL = 1e-12  # multipliers ≥ −tol count as non-negative (m/s scale)
_FEAS_TOL = 1e-10  # m/s: a candidate satisfies a row when aᵀu ≤ b + tol
_DET_TOL = 1e-12  # |a_k × a_l| below this: (near-)parallel lines, no vertex


@dataclass(frozen=True)
class SplitRows:
    """Every robot's own rows ``a_kᵀu_owner ≤ b_k`` after the half/half split.

    owner (M,) robot index; a (M, 2); b (M,) m/s; source (M,) index of the
    centralised row each came from (a pair row gives two entries, one per robot).
    """

    owner: np.ndarray
    a: np.ndarray
    b: np.ndarray
    source: np.ndarray


def split_rows(rows: Rows, b: np.ndarray | None = None) -> SplitRows:
    """Half/half split of the pair rows (REFERENCE.md §12); single-robot rows are kept whole.

    ``b`` (m,) overrides ``rows.b`` (e.g. recovery targets). For a pair row k,
    the two halves are ``(ci_k, b_k/2)`` for robot i and ``(cj_k, b_k/2)`` for
    robot j, so their sum is exactly row k.
    """
    b = rows.b if b is None else b
    if _COMPILED and not small(rows.m):  # the same arrays, built by a compiled kernel
        f = np.ascontiguousarray
        return SplitRows(*split_kernel(f(rows.i, dtype=np.int64), f(rows.j, dtype=np.int64), f(rows.ci, dtype=float),
                                       f(rows.cj, dtype=float), f(b, dtype=float)))
    pair = np.flatnonzero(rows.j >= 0)
    single = np.flatnonzero(rows.j < 0)
    owner = np.concatenate([rows.i[pair], rows.j[pair], rows.i[single]])
    a = np.concatenate([rows.ci[pair], rows.cj[pair], rows.ci[single]])
    bb = np.concatenate([0.5 * b[pair], 0.5 * b[pair], b[single]])
    source = np.concatenate([pair, pair, single])
    return SplitRows(owner, a, bb, source)


@dataclass(frozen=True)
class SmallQPResult:
    """u (N, 2); solved (N,) robots with a certified optimum; active (M,) split rows at equality;
    on_disc (N,) robots on their speed bound."""

    u: np.ndarray
    solved: np.ndarray
    active: np.ndarray
    on_disc: np.ndarray


def _cross(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0]


@dataclass(frozen=True)
class _LineOptima:
    """The optimum on each line k of a robot: cand (S, H, 2), cost (S, H) (inf: no candidate),
    clamp (S, H) index of the row ending the segment there (−1: none), on_disc (S, H)."""

    cand: np.ndarray
    cost: np.ndarray
    clamp: np.ndarray
    on_disc: np.ndarray


def _line_optima(A: np.ndarray, B: np.ndarray, U: np.ndarray, kidx: np.ndarray, kval: np.ndarray,
                 vmax: float | None) -> _LineOptima:
    """For each robot s and each of its lines k = kidx[s, h] (where kval), the minimiser of
    ‖u − û_s‖² on the line within the segment all rows (and the disc) leave.

    A (S, K, 2) unit rows, B (S, K); the line is u(t) = b_k a_k + t a_k⊥, û projects to
    t_p = a_k⊥ᵀû, and row l reads b_k·a_lᵀa_k + t·a_lᵀa_k⊥ ≤ b_l: the answer is t_p
    clamped to [lo, hi]. Row k itself and padding rows (a = 0, b = 1) come out as
    harmless parallel rows. Every candidate satisfies all rows and the disc.
    """
    S, H = kidx.shape
    rs = np.arange(S)[:, None]
    Ak = A[rs, kidx]  # (S, H, 2)
    Bk = B[rs, kidx]
    Pk = np.stack([-Ak[..., 1], Ak[..., 0]], axis=-1)  # a_k⊥
    tp = np.einsum("shd,sd->sh", Pk, U)
    # (S, H, K): a_lᵀa_k⊥ and a_lᵀa_k, written out (a batched matmul of 2-vectors costs a call per robot)
    Ax, Ay = A[:, None, :, 0], A[:, None, :, 1]
    c = Pk[..., 0, None] * Ax + Pk[..., 1, None] * Ay
    rhs = B[:, None, :] - Bk[:, :, None] * (Ak[..., 0, None] * Ax + Ak[..., 1, None] * Ay)
    pos, neg = c > _DET_TOL, c < -_DET_TOL
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = rhs / c
    up = np.where(pos, bound, np.inf)  # t ≤ bound
    dn = np.where(neg, bound, -np.inf)  # t ≥ bound
    empty = np.any(~pos & ~neg & (rhs < -_FEAS_TOL), axis=2)  # a parallel row excludes the line
    hi_l = np.argmin(up, axis=2)
    lo_l = np.argmax(dn, axis=2)
    hi = np.take_along_axis(up, hi_l[..., None], axis=2)[..., 0]
    lo = np.take_along_axis(dn, lo_l[..., None], axis=2)[..., 0]
    hi_disc = np.zeros((S, H), dtype=bool)
    lo_disc = np.zeros((S, H), dtype=bool)
    if vmax is not None:
        half = np.sqrt(np.maximum(vmax * vmax - Bk * Bk, 0.0))
        empty |= np.abs(Bk) > vmax
        hi_disc, lo_disc = half < hi, -half > lo
        hi, lo = np.minimum(hi, half), np.maximum(lo, -half)
    empty |= lo > hi + _FEAS_TOL
    t = np.minimum(np.maximum(tp, lo), hi)
    cand = Bk[..., None] * Ak + t[..., None] * Pk
    d = cand - U[:, None, :]
    cost = np.where(kval & ~empty, np.einsum("shd,shd->sh", d, d), np.inf)
    at_hi = tp > hi
    at_lo = tp < lo
    clamp = np.where(at_hi & ~hi_disc, hi_l, np.where(at_lo & ~lo_disc, lo_l, -1))
    on_disc = (at_hi & hi_disc) | (at_lo & lo_disc)
    return _LineOptima(cand, cost, clamp, on_disc)


def solve_small_qps(owner: np.ndarray, a: np.ndarray, b: np.ndarray, nominal: np.ndarray,
                    max_speed: float | None, reach: float | None = None,
                    todo: np.ndarray | None = None) -> SmallQPResult:
    """Solve ``min ‖u_i − û_i‖² s.t. a_kᵀu_i ≤ b_k (owner_k = i), ‖u_i‖ ≤ max_speed`` for every robot.

    owner (M,) int, a (M, 2), b (M,) m/s; nominal (N, 2) m/s; max_speed m/s or
    None (no disc: the rows must bound the problem, e.g. wheel limits); reach:
    a bound on ‖u‖ over the feasible set (rows with b ≥ reach·‖a‖ are then
    implied and skipped); todo (N,) bool robots to solve (others keep û and
    count as solved). A robot whose û satisfies its rows and disc gets û back
    bit for bit. Robots without a certified optimum have solved False and u = 0.

    Candidates (all feasible by construction): Π_D(û) (û scaled into the disc),
    and for each *hot* line k (one that Π_D(û) violates) the optimum on line k.
    An optimum with a line active has a hot line active — two lines with λ_k,
    λ_l > 0 give (a_kᵀû − b_k) + (a_lᵀû − b_l) = (λ_k + λ_l)(1 + a_kᵀa_l) > 0, and a
    line k with the disc active is the optimum over D ∩ {row k}, so Π_D(û)
    violates row k — so the optimum is the cheapest candidate. Stage 1 tries
    the most violated line alone and accepts it when its KKT multipliers are
    ≥ 0 (then it is the optimum); stage 2 takes the cheapest over all hot lines.

    With numba (``core.compiled``) and more than ``small_kernels.SMALL_ROBOTS`` robots (or numba already
    imported) the compiled kernel :func:`safety.distributed_kernel.solve_small_qps_kernel` answers instead:
    the same answers bit for bit, without the GIL.
    """
    n = nominal.shape[0]
    if _COMPILED and not small(n):
        vm = np.inf if max_speed is None else float(max_speed)
        use_todo = todo is not None
        u_c, solved_c, active_c, disc_c, _ = solve_small_qps_kernel(
            np.ascontiguousarray(owner, dtype=np.int64), np.ascontiguousarray(a, dtype=float),
            np.ascontiguousarray(b, dtype=float), np.ascontiguousarray(nominal, dtype=float), max_speed is not None,
            vm, np.inf if reach is None else float(reach),
            np.ascontiguousarray(todo, dtype=np.bool_) if use_todo else np.zeros(0, dtype=np.bool_), use_todo)
        return SmallQPResult(u_c, solved_c, active_c, disc_c)
    return _solve_small_qps_numpy(owner, a, b, nominal, max_speed, reach, todo)


def _solve_small_qps_numpy(owner: np.ndarray, a: np.ndarray, b: np.ndarray, nominal: np.ndarray,
                           max_speed: float | None, reach: float | None = None,
                           todo: np.ndarray | None = None) -> SmallQPResult:
    """:func:`solve_small_qps` in numpy, vectorised across robots (padded arrays): the path without numba."""
    n = nominal.shape[0]
    m = b.shape[0]
    uh = nominal
    u = uh.copy()
    active = np.zeros(m, dtype=bool)
    on_disc = np.zeros(n, dtype=bool)
    solved = np.ones(n, dtype=bool)
    if n == 0:
        return SmallQPResult(u, solved, active, on_disc)
    lhs = np.einsum("kd,kd->k", a, uh[owner])
    bad = np.zeros(n, dtype=bool)
    bad[owner[lhs > b]] = True
    disc = max_speed is not None
    vmax = float(max_speed) if max_speed is not None else None
    speed = np.sqrt(np.einsum("kd,kd->k", uh, uh))
    if disc:
        bad |= speed > vmax
    if todo is not None:
        bad &= todo
    if not bad.any():
        return SmallQPResult(u, solved, active, on_disc)

    # ---- prune rows that cannot be active. (1) b ≥ reach·‖a‖: implied by ‖u‖ ≤ reach.
    # (2) where u = τ·û is feasible (τ ∈ [0, 1], all the robot's b ≥ 0), the optimum lies
    # within r = (1 − τ)‖û‖ of û, so rows with b − aᵀû > r‖a‖ hold strictly there.
    norm = np.sqrt(np.einsum("kd,kd->k", a, a))
    lim = np.inf if reach is None else float(reach)
    with np.errstate(divide="ignore", invalid="ignore"):  # a row with b < 0 excludes u = 0: no radius
        tau_row = np.where(b < 0, -1.0, np.where(lhs > 0, b / lhs, np.inf))
    tau = np.ones(n) if not disc else np.minimum(1.0, vmax / np.maximum(speed, 1e-300))
    np.minimum.at(tau, owner, tau_row)
    radius = np.where(tau >= 0, (1.0 - np.clip(tau, 0.0, 1.0)) * speed, np.inf)
    with np.errstate(invalid="ignore"):  # inf·0 for a zero row, which (norm > 0) leaves out
        idx = np.flatnonzero(bad[owner] & (norm > 0) & (b < lim * norm) & (b - lhs <= radius[owner] * norm))

    # ---- the rows of the robots to solve, normalised, padded to (S, K)
    robots = np.flatnonzero(bad)
    s = robots.size
    slot_of = np.full(n, -1, dtype=np.int64)
    slot_of[robots] = np.arange(s)
    # group by robot: a stable argsort of 16-bit keys is numpy's radix sort (≈ 10× the merge sort)
    keys = owner[idx].astype(np.uint16) if n <= np.iinfo(np.uint16).max else owner[idx]
    idx = idx[np.argsort(keys, kind="stable")]
    slot = slot_of[owner[idx]]
    counts = np.bincount(slot, minlength=s)
    K = int(counts.max(initial=0))
    col = np.arange(idx.size) - (np.cumsum(counts) - counts)[slot]
    A = np.zeros((s, K, 2))
    B = np.ones((s, K))  # padding rows 0ᵀu ≤ 1 hold everywhere
    valid = np.zeros((s, K), dtype=bool)
    A[slot, col] = a[idx] / norm[idx, None]
    B[slot, col] = b[idx] / norm[idx]
    valid[slot, col] = True
    where = np.full((s, K), -1, dtype=np.int64)  # position in the caller's arrays
    where[slot, col] = idx
    U = uh[robots]

    # Π_D(û): û itself, or its radial projection on the speed disc; optimal when feasible
    sp = speed[robots]
    scale = np.minimum(1.0, vmax / np.maximum(sp, 1e-300)) if disc else np.ones(s)
    R = U * scale[:, None]
    excess = np.einsum("skd,sd->sk", A, R) - B
    r_ok = np.all(excess <= _FEAS_TOL, axis=1)
    hot = valid & (excess > -_SIGN_TOL)

    best = np.where(r_ok[:, None], R, 0.0)
    got = r_ok.copy()
    best_k = np.full(s, -1, dtype=np.int64)
    best_l = np.full(s, -1, dtype=np.int64)
    best_disc = r_ok & (scale < 1.0)

    # ---- stage 1: the most violated line, accepted when its multipliers are ≥ 0
    open1 = np.flatnonzero(~r_ok & hot.any(axis=1))
    if open1.size:
        k1 = np.argmax(np.where(hot[open1], excess[open1], -np.inf), axis=1)
        lo1 = _line_optima(A[open1], B[open1], U[open1], k1[:, None], np.ones((open1.size, 1), bool), vmax)
        cand, l1, d1 = lo1.cand[:, 0], lo1.clamp[:, 0], lo1.on_disc[:, 0]
        ak = A[open1, k1]
        g = np.where((l1 >= 0)[:, None], A[open1, np.maximum(l1, 0)], np.where(d1[:, None], cand, 0.0))
        r = U[open1] - cand  # = λ a_k + ν g
        det = _cross(ak, g)
        two = (l1 >= 0) | d1
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.where(two, _cross(r, g) / det, np.einsum("sd,sd->s", r, ak))
            nu = np.where(two, _cross(ak, r) / det, 0.0)
        kkt = (np.isfinite(lo1.cost[:, 0]) & (~two | (np.abs(det) > _DET_TOL))
               & (lam >= -_SIGN_TOL) & (nu >= -_SIGN_TOL))
        acc = open1[kkt]
        best[acc] = cand[kkt]
        best_k[acc], best_l[acc], best_disc[acc] = k1[kkt], l1[kkt], d1[kkt]
        got[acc] = True

    # ---- stage 2: the robots still open, the cheapest optimum over all their hot lines
    open2 = np.flatnonzero(~got)
    if open2.size:
        hot2 = hot[open2]
        n_hot = hot2.sum(axis=1)
        H = max(int(n_hot.max(initial=0)), 1)
        hs, hk = np.nonzero(hot2)
        hcol = np.arange(hs.size) - (np.cumsum(n_hot) - n_hot)[hs]
        kidx = np.zeros((open2.size, H), dtype=np.int64)
        kidx[hs, hcol] = hk
        kval = np.zeros((open2.size, H), dtype=bool)
        kval[hs, hcol] = True
        lo2 = _line_optima(A[open2], B[open2], U[open2], kidx, kval, vmax)
        h = np.argmin(lo2.cost, axis=1)
        r2 = np.arange(open2.size)
        found = np.isfinite(lo2.cost[r2, h])
        acc = open2[found]
        best[acc] = lo2.cand[r2, h][found]
        best_k[acc] = kidx[r2, h][found]
        best_l[acc] = lo2.clamp[r2, h][found]
        best_disc[acc] = lo2.on_disc[r2, h][found]
        got[acc] = True

    # certify each robot's answer against all of its (kept) rows; the caller checks the rest
    got &= np.all(np.einsum("skd,sd->sk", A, best) <= B + _FEAS_TOL, axis=1)
    if vmax is not None:  # remove rounding beyond the disc (``disc``)
        sp2 = np.einsum("sd,sd->s", best, best)
        got &= sp2 <= (vmax * (1 + 1e-9)) ** 2
        over = sp2 > vmax * vmax
        best[over] *= (vmax / np.sqrt(sp2[over]))[:, None]
    u[robots] = np.where(got[:, None], best, 0.0)
    solved[robots] = got
    for sel in (best_k, best_l):
        have = got & (sel >= 0)
        active[where[np.flatnonzero(have), sel[have]]] = True
    on_disc[robots[got & best_disc]] = True
    return SmallQPResult(u, solved, active, on_disc)


def reallocate_halves(split: SplitRows, u: np.ndarray, n_pairs: int) -> tuple[np.ndarray, np.ndarray]:
    """Second pass's split: each pair row's unused half goes to the robot that needed it.

    split: a half/half split whose pair halves come first (robot i's ``[0, n_pairs)``, robot j's
    ``[n_pairs, 2·n_pairs)``, as :func:`split_rows` orders them); u (N, 2) the first pass's answer.
    Where robot i's half binds (usage ``a·u_i`` within 1e-10 m/s of ``b/2``) and robot j's does not,
    i gets ``b − c_j`` and j exactly its usage ``c_j`` (and symmetrically); otherwise both keep
    ``b/2``. The two bounds still add up to the row, and every robot's first answer is feasible for
    its new rows, so the second pass is certified as the first and no robot's intervention grows.
    Returns (b (M,) new bounds, loosened (N,) robots with a loosened half — the only ones to re-solve).
    """
    if _COMPILED and not small(u.shape[0]):  # the same arithmetic compiled (bit for bit)
        f = np.ascontiguousarray
        out, grown = reallocate_kernel(f(split.owner, dtype=np.int64), f(split.a, dtype=float),
                                       f(split.b, dtype=float), f(u, dtype=float), int(n_pairs))
        return out, grown
    b = split.b.copy()
    loosened = np.zeros(u.shape[0], dtype=bool)
    if n_pairs == 0:
        return b, loosened
    use = np.einsum("kd,kd->k", split.a[: 2 * n_pairs], u[split.owner[: 2 * n_pairs]])
    half = split.b[:n_pairs]  # = b/2 for both halves
    ci, cj = use[:n_pairs], use[n_pairs:]
    bind_i, bind_j = ci >= half - _FEAS_TOL, cj >= half - _FEAS_TOL
    give_i = bind_i & ~bind_j  # j's half is slack: i gets it
    give_j = bind_j & ~bind_i
    total = 2.0 * half
    b[:n_pairs] = np.where(give_i, total - cj, np.where(give_j, ci, half))
    b[n_pairs:2 * n_pairs] = np.where(give_j, total - ci, np.where(give_i, cj, half))
    loosened[split.owner[:n_pairs][give_i]] = True
    loosened[split.owner[n_pairs:2 * n_pairs][give_j]] = True
    return b, loosened


def consensus_shares(split: SplitRows, b: np.ndarray, u: np.ndarray, n_pairs: int) -> tuple[np.ndarray, np.ndarray]:
    """A consensus pass's split: each pair row's margin shared at the last answer, its slack halved.

    split: :func:`split_rows`'s split (pair halves first, as :func:`reallocate_halves`); b (M,) the last pass's
    bounds on it; u (N, 2) m/s that pass's answer. Robot i's share of pair row k becomes
    ``c_iᵀu_i + s_k/2`` and robot j's ``c_jᵀu_j + s_k/2``, s_k = b_k − c_iᵀu_i − c_jᵀu_j ≥ 0 the slack
    the answer leaves in the row (single-robot rows keep their bound). The shares add up to the row, so the
    pass is certified as the first; every robot's last answer satisfies its new shares, so no robot's
    intervention grows; and were u the joint optimum, every robot's own QP would return it. Returns (b (M,)
    new bounds, grown (N,) robots with a share larger than before — the only ones to re-solve: the others'
    answers stay optimal on a feasible set that shrank around them).
    """
    if _COMPILED and not small(u.shape[0]):  # the same arithmetic compiled (bit for bit)
        f = np.ascontiguousarray
        new, more = consensus_kernel(f(split.owner, dtype=np.int64), f(split.a, dtype=float), f(split.b, dtype=float),
                                     f(b, dtype=float), f(u, dtype=float), int(n_pairs))
        return new, more
    out = b.copy()
    grown = np.zeros(u.shape[0], dtype=bool)
    if n_pairs == 0:
        return out, grown
    p2 = 2 * n_pairs
    own = split.owner[:p2]
    use = np.einsum("kd,kd->k", split.a[:p2], u[own])
    total = split.b[:n_pairs] + split.b[n_pairs:p2]  # the row's bound (the halves of split_rows add up exactly)
    ci, cj = use[:n_pairs], use[n_pairs:]
    bi = ci + 0.5 * (total - ci - cj)
    out[:n_pairs], out[n_pairs:p2] = bi, total - bi
    grown[own[out[:p2] > b[:p2]]] = True
    return out, grown


def _worst_row(rows: Rows, u: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """(largest row excess ``lhs(u) − b`` m/s, its first row), compiled above the small sizes; (−inf, −1): no rows.
    A NaN excess is the largest (the first NaN row), so that the certificate fails closed."""
    if rows.m == 0:
        return -np.inf, -1
    if _COMPILED and not small(u.shape[0]):
        f = np.ascontiguousarray
        worst, k = worst_row(f(rows.i, dtype=np.int64), f(rows.jj, dtype=np.int64), f(rows.ci, dtype=float),
                             f(rows.cj, dtype=float), f(b, dtype=float), f(u, dtype=float))
        return float(worst), int(k)
    excess = rows.lhs(u) - b
    k = int(np.argmax(excess))
    return float(excess[k]), k


@dataclass(frozen=True)
class DistributedResult:
    """u (N, 2); ok; reason; active (m,) centralised rows with an active half (or whole row);
    n_speed robots on the speed bound; n_fallback robots that fell back to "no further approach"."""

    u: np.ndarray
    ok: bool
    reason: str
    active: np.ndarray
    n_speed: int
    n_fallback: int


def filter_distributed(rows: Rows, nominal: np.ndarray, max_speed: float | None,
                       cfg: BarrierConfig) -> DistributedResult:
    """Every robot's own QP on its half of each pair row; certified against the centralised rows.

    rows: the centralised candidate rows (pairs, walls, obstacles, limits);
    nominal (N, 2) m/s; max_speed: the speed disc (None: the rows bound u, and
    ``cfg.max_speed`` bounds every feasible ‖u‖). On success every centralised
    row holds (the halves add up) to 2·1e-10 m/s. Passes: half/half; with
    ``cfg.distributed_second_pass`` the reallocated split (:func:`reallocate_halves`);
    then ``cfg.distributed_consensus_passes`` consensus passes (:func:`consensus_shares`),
    each keeping the last certified answer if a robot's own QP fails.
    """
    n = nominal.shape[0]
    unsafe = (rows.h < 0) & (rows.kind != LIMIT)
    recovering = cfg.recovery and bool(unsafe.any())
    b_hard = np.where(unsafe, np.maximum(rows.b, 0.0), rows.b) if recovering else rows.b
    b_target = np.where(unsafe, -cfg.recovery_speed, rows.b) if recovering else rows.b
    reach = max_speed if max_speed is not None else cfg.max_speed
    split = split_rows(rows, b_target)
    res = solve_small_qps(split.owner, split.a, split.b, nominal, max_speed, reach)
    u, solved, act, on_disc = res.u, res.solved, res.active, res.on_disc
    n_fallback = 0
    if cfg.distributed_second_pass and not recovering and solved.all():
        # a second pass on a better split of each pair's margin (reallocate_halves): less invasive
        n_pairs = int(np.sum(rows.j >= 0))
        b2, again = reallocate_halves(split, u, n_pairs)
        res2 = None
        if again.any():
            res2 = solve_small_qps(split.owner, split.a, b2, nominal, max_speed, reach, todo=again)
            if res2.solved.all():
                u = np.where(again[:, None], res2.u, u)
                act = np.where(again[split.owner], res2.active, act)
                on_disc = np.where(again, res2.on_disc, on_disc)
        b_last = b2 if res2 is None or res2.solved.all() else split.b
        for _ in range(cfg.distributed_consensus_passes):
            # consensus passes: every pair's remaining slack shared equally at the last answer
            b3, grown = consensus_shares(split, b_last, u, n_pairs)
            if not grown.any():
                break
            res3 = solve_small_qps(split.owner, split.a, b3, nominal, max_speed, reach, todo=grown)
            if not res3.solved.all():  # rounding on a degenerate robot: the last certified answer stands
                break
            u = np.where(grown[:, None], res3.u, u)
            act = np.where(grown[split.owner], res3.active, act)
            on_disc = np.where(grown, res3.on_disc, on_disc)
            b_last = b3
    if recovering and not solved.all():
        # conflicting separation targets: those robots hold "no further approach" instead
        retry = ~solved
        n_fallback = int(retry.sum())
        hard = split_rows(rows, b_hard)
        res2 = solve_small_qps(hard.owner, hard.a, hard.b, nominal, max_speed, reach, todo=retry)
        u = np.where(retry[:, None], res2.u, u)
        solved = np.where(retry, res2.solved, solved)
        mine = retry[split.owner]
        act = np.where(mine, res2.active, act)
        on_disc = np.where(retry, res2.on_disc, on_disc)
    active = np.zeros(rows.m, dtype=bool)
    if not solved.all():
        bad = np.flatnonzero(~solved)
        return DistributedResult(np.zeros((n, 2)), False,
                                 f"no certified answer for robot(s) {bad[:10].tolist()} (infeasible own QP)",
                                 active, 0, n_fallback)
    # certificate: every centralised row (halves added up) and every speed bound
    worst, k = _worst_row(rows, u, b_hard)
    if rows.m and not worst <= 2 * _FEAS_TOL:  # a NaN excess fails the certificate (it never compares true)
        return DistributedResult(np.zeros((n, 2)), False,
                                 f"row {k} violated by {worst:.3g} m/s after the split", active, 0,
                                 n_fallback)
    if max_speed is not None and not np.all(np.einsum("kd,kd->k", u, u) <= (max_speed * (1 + 1e-9)) ** 2):
        return DistributedResult(np.zeros((n, 2)), False, "speed bound exceeded", active, 0, n_fallback)
    active[split.source[act]] = True
    return DistributedResult(u, True, "optimal per robot", active, int(on_disc.sum()), n_fallback)


__all__ = ["SplitRows", "split_rows", "reallocate_halves", "consensus_shares", "SmallQPResult", "solve_small_qps", "DistributedResult",
           "filter_distributed"]
