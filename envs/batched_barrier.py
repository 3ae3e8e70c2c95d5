"""The distributed barrier over E swarms at once (REFERENCE.md §12), bit for bit one filter per swarm.

E swarms of N unicycles, flattened to E·N robots: robot ``e·N + i`` is robot i of swarm e. The
rows are the unicycle filter's (:class:`swarmdeck.safety.UnicycleSafetyFilter` in
``mode="distributed"``): pair rows (:func:`swarmdeck.safety.constraints.pair_rows`) from one compiled
sweep over all swarms (:class:`swarmdeck.envs.neighbours.SwarmPairs`; without numba one k-d tree over
all swarms lifted apart, :func:`swarmdeck.envs.neighbours.lifted_tree`), so no row ever joins two swarms, wall rows, and the four wheel-limit rows of each robot. Each robot's own QP is
solved by :func:`swarmdeck.safety.distributed.solve_small_qps` — the same code, on rows in the same
order per robot — for all E·N robots in one vectorised call. The certificate, the recovery retry and
the fail-stop are decided per swarm: a swarm whose answer does not certify stops (all its commands
zero), the others carry on.

Equal to E separate ``UnicycleSafetyFilter(BarrierConfig(mode="distributed"))`` calls bit for bit
(tests/envs/test_envs_batched_equal.py), except for exactly coincident look-ahead points, whose fallback
direction is seeded from the row key (a different key here).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmdeck.core.kinematics import (
    UnicycleParams,
    lookahead_points,
    si_to_unicycle,
    unicycle_to_si,
    unicycle_to_wheels,
)
from swarmdeck.envs.batched_kernels import use_compiled
from swarmdeck.envs.neighbours import SwarmPairs, lifted_tree
from swarmdeck.safety import BarrierConfig
from swarmdeck.safety.constraints import LIMIT, Rows, pair_rows, wall_rows
from swarmdeck.safety.distributed import reallocate_halves, solve_small_qps, split_rows
from swarmdeck.safety.filter import MAX_COORDINATE
from swarmdeck.safety.unicycle import max_point_speed, wheel_limit_rows

FloatArray = NDArray[np.float64]
_FEAS_TOL = 1e-10  # m/s, safety.distributed's: the halves add up to every row within 2·this


@dataclass(frozen=True)
class BatchedFilterResult:
    """One tick of :class:`BatchedDistributedBarrier` over E swarms of N robots.

    v, w: ``(E·N,)`` safe commands, m/s and rad/s (zero in failed swarms); ok: ``(E,)``;
    intervention: ``(E·N,)`` ‖u*_i − û_i‖ of the look-ahead velocity, m/s (‖û_i‖ in failed swarms);
    reason: ``(E,)`` why a swarm failed ("" where ok).
    """

    v: FloatArray
    w: FloatArray
    ok: NDArray[np.bool_]
    intervention: FloatArray
    reason: tuple[str, ...]


class BatchedDistributedBarrier:
    """The unicycle distributed barrier for E swarms (module docstring).

    ``config``: the barrier (its ``mode`` is ignored: always distributed); ``params``: the robot.
    As in :class:`~swarmdeck.safety.UnicycleSafetyFilter`, ``max_speed`` becomes the fastest
    look-ahead speed the wheels allow.
    """

    def __init__(self, config: BarrierConfig | None = None, params: UnicycleParams | None = None) -> None:
        self.params = UnicycleParams() if params is None else params
        base = BarrierConfig() if config is None else config
        self.config = dataclasses.replace(base, max_speed=max_point_speed(self.params), mode="distributed")

    def filter(self, poses: FloatArray, v: FloatArray, w: FloatArray, n_swarms: int, *,
               trig: tuple[FloatArray, FloatArray] | None = None, points: FloatArray | None = None
               ) -> BatchedFilterResult:
        """Safe ``(v, ω)`` for poses ``(E·N, 3)`` and nominal ``v, w`` ``(E·N,)`` (finite; see the module docstring).

        ``trig``: (cos θ, sin θ) ``(E·N,)`` of these poses and ``points`` their look-ahead points ``(E·N, 2)`` m, when
        the caller has them (:class:`~swarmdeck.envs.batched_swarm.BatchedSwarm` keeps them per pose update): the
        same numbers, not computed again."""
        cfg, params = self.config, self.params
        total = poses.shape[0]
        n = total // n_swarms
        ell = params.lookahead
        P = lookahead_points(poses, ell) if points is None else points
        U = unicycle_to_si(poses, v, w, ell) if trig is None else _to_si(trig, v, w, ell)
        swarm_of = np.repeat(np.arange(n_swarms), n)
        fail = np.zeros(n_swarms, dtype=bool)
        reasons = [""] * n_swarms
        far = np.max(np.abs(P), axis=1) > MAX_COORDINATE
        for e in np.unique(swarm_of[far]) if far.any() else ():
            fail[e], reasons[e] = True, f"points beyond ±{MAX_COORDINATE:g} m"
        with np.errstate(over="ignore", invalid="ignore"):
            points = P.reshape(n_swarms, n, 2)
            # pair_rows asks only query_pairs: the compiled sweep answers it (the same pairs) without a tree
            tree = cast(cKDTree, SwarmPairs(points)) if use_compiled(total) else lifted_tree(points)
            parts = ([pair_rows(P, cfg, tree)] if cfg.pairs else []) + [wall_rows(P, cfg)]
            rows = Rows.concat(parts + [wheel_limit_rows(poses, params)])
        row_swarm = swarm_of[rows.i]
        bad_b = ~np.isfinite(rows.b)
        if bad_b.any():  # that swarm stops; a finite stand-in keeps the others' arithmetic clean
            for e in np.unique(row_swarm[bad_b]):
                fail[e], reasons[e] = True, "non-finite bound (gains too large for these positions)"
            rows = dataclasses.replace(rows, b=np.where(bad_b, 0.0, rows.b))

        # safety.distributed.filter_distributed, with recovery and certificate per swarm
        unsafe = (rows.h < 0) & (rows.kind != LIMIT)
        recovering = np.zeros(n_swarms, dtype=bool)
        if cfg.recovery:
            recovering[row_swarm[unsafe]] = True
        b_hard = np.where(unsafe & cfg.recovery, np.maximum(rows.b, 0.0), rows.b)
        b_target = np.where(unsafe & cfg.recovery, -cfg.recovery_speed, rows.b)
        reach = cfg.max_speed
        split = split_rows(rows, b_target)
        res = solve_small_qps(split.owner, split.a, split.b, U, None, reach)
        u, solved = res.u, res.solved
        if cfg.distributed_second_pass:
            # filter_distributed's second pass (reallocate_halves), per swarm: a swarm that is not recovering
            # and solved every robot re-solves its loosened robots, and keeps the answer if all of them solved
            whole = np.ones(n_swarms, dtype=bool)
            whole[swarm_of[~solved]] = False
            b2, again = reallocate_halves(split, u, int(np.sum(rows.j >= 0)))
            again &= (whole & ~recovering)[swarm_of]
            if again.any():
                res2 = solve_small_qps(split.owner, split.a, b2, U, None, reach, todo=again)
                kept = np.ones(n_swarms, dtype=bool)
                kept[swarm_of[again & ~res2.solved]] = False
                take = again & kept[swarm_of]
                u = np.where(take[:, None], res2.u, u)
        retry = ~solved & recovering[swarm_of]
        if retry.any():
            hard = split_rows(rows, b_hard)
            res2 = solve_small_qps(hard.owner, hard.a, hard.b, U, None, reach, todo=retry)
            u = np.where(retry[:, None], res2.u, u)
            solved = np.where(retry, res2.solved, solved)
        for e in np.unique(swarm_of[~solved]) if not solved.all() else ():
            if not fail[e]:
                fail[e], reasons[e] = True, "distributed: no certified answer (infeasible own QP)"
        over = rows.lhs(u) - b_hard > 2 * _FEAS_TOL
        for e in np.unique(row_swarm[over]) if over.any() else ():
            if not fail[e]:
                fail[e], reasons[e] = True, "distributed: a row is violated after the split"

        vs, ws = si_to_unicycle(poses, u, ell) if trig is None else _to_unicycle(trig, u, ell)
        wr, wl = unicycle_to_wheels(vs, ws, params)
        peak = np.maximum(np.abs(wr), np.abs(wl))
        scale = np.minimum(1.0, params.max_wheel_speed / np.maximum(peak, 1e-300))
        untouched = np.all(u == U, axis=1)
        v_out = np.where(untouched, v, vs * scale)
        w_out = np.where(untouched, w, ws * scale)
        failed = fail[swarm_of]
        d = u - U
        inter = np.where(failed, np.linalg.norm(U, axis=1), np.sqrt(np.einsum("kd,kd->k", d, d)))  # as fail_stop, _diag
        return BatchedFilterResult(np.where(failed, 0.0, v_out), np.where(failed, 0.0, w_out), ~fail, inter,
                                   tuple(reasons))


def _to_si(trig: tuple[FloatArray, FloatArray], v: FloatArray, w: FloatArray, ell: float) -> FloatArray:
    """:func:`~swarmdeck.core.kinematics.unicycle_to_si` from its cos θ, sin θ (the same expression, the same bits)."""
    c, s = trig
    return np.column_stack((c * v - ell * s * w, s * v + ell * c * w))


def _to_unicycle(trig: tuple[FloatArray, FloatArray], u: FloatArray, ell: float) -> tuple[FloatArray, FloatArray]:
    """:func:`~swarmdeck.core.kinematics.si_to_unicycle` from its cos θ, sin θ (the same expression, the same bits)."""
    c, s = trig
    return c * u[:, 0] + s * u[:, 1], (-s * u[:, 0] + c * u[:, 1]) / ell
