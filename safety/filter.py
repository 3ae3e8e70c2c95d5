"""The single-integrator safety filter: one object, one call per tick.

``SafetyFilter(BarrierConfig()).filter(points, nominal, obstacles=None) -> (safe, diag)``
solves the barrier QP of REFERENCE.md §3 (paper §IV-B)::

    min Σ‖u_i − û_i‖²  s.t. pair, wall and obstacle rows,  ‖u_i‖ ≤ v_max

in stages, cheapest first:

1. validate the input (shapes, finiteness) — anything wrong stops the robots;
2. build only the rows that can bind (k-d tree, ``constraints.py``);
3. **pass-through**: if û satisfies every row (to the certification tolerance, 1e-10 m/s)
   and every speed bound, return a copy of û (bit-for-bit): the filter never perturbs a
   safe command, and every answer is a fixed point;
4. robots already inside the unsafe set (h < 0): their rows keep the plain barrier bound
   (the answer is then the plain QP's, as with the Robotarium's barrier), except that deep
   overlaps (``BarrierConfig.recovery_depth``) demand ``recovery_speed``; the clusters
   (connected components of the row graph) holding them are solved apart, and only if
   their rows are infeasible by the soft form ("no further approach" + separation targets);
5. everything is solved exactly. In closed loop first: the compiled dual coordinate ascent
   (``dual_ascent.py``) from the previous tick's multipliers predicts the active rows and the
   active set certifies the optimum from them (KKT). Otherwise (or if that does not certify): the
   active-set solver, warm-started from the previous tick's active rows and certified by the KKT
   conditions, when the starting working set is small (``BarrierConfig.active_set_max_rows``,
   ``warm_max_rows`` in closed loop); on a cold call the dual ascent from zero multipliers and the
   certified active set from its prediction (``BarrierConfig.cold_dual``); otherwise clarabel, whose answer is
   polished by the active set from clarabel's active rows (certified), or else projected
   onto the speed discs with robots no row touches given their nominal exactly.

Every solver status is checked. On any failure (infeasible, iteration limit,
numerical trouble, NaN/inf or malformed input) every robot gets a zero command
and ``diag.ok`` is False with the reason in ``diag.status``.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.graphs import nearest_pair_distance

from . import dual_ascent
from .active_set import FEAS_TOL, ActiveSetResult, clip_speed, solve_active_set
from .config import BarrierConfig
from .constraints import LIMIT, OBSTACLE, PAIR, SEGMENT, WALL, Rows, barrier_rows
from .diagnostics import BarrierDiagnostics
from .distributed import filter_distributed
from .qp_clarabel import QPResult, solve_qp

_ACTIVE_TOL = 1e-7  # m/s: a row within this of its bound counts as active in clarabel answers
# closed loop, pruned clarabel: speed cones only for robots whose nominal speed is at least this
# fraction of v_max (a robot pushed beyond the bound otherwise is caught by the certified polish)
_WARM_DISC_FRACTION = 0.8
# m: controlled points and obstacles farther than this from the origin are not positions (a
# tracking or units error); beyond ~1e154 m squared distances overflow and the k-d tree raises
MAX_COORDINATE = 1e6
_PASS_TOL = FEAS_TOL  # m/s: a row counts as met within the certification's tolerance (so answers are fixed points)
_CLARABEL_FEAS = 1e-7  # m/s: an interior-point answer violating a row by more than this is refused
# factorisations clarabel's polish may spend under an active-set cap: from clarabel's active rows it
# certifies in one or two iterations or not at all (bench_barrier_anytime: a capped polish that failed
# spent its whole cap on the worst ticks)
_POLISH_SOLVES = 4
# BarrierConfig.warm_share applies once last tick held more than this many active rows: on the dense
# crossing N = 100 holds 140-180 (small dense Gram matrices; a capped failure costs < ½ clarabel cold)
# and N = 200 holds 270-360, where one Gram factorisation costs about one clarabel iteration
# (bench_barrier_anytime; 300 left N = 200's first failing ticks uncapped at 1.8× clarabel's worst)
_SHARE_MIN_ROWS = 200
# factorisations an active-set stage may spend when BarrierConfig.active_set_max_solves is None (a plain
# BarrierConfig(), mode "centralised"): no stage runs away (the dense crossing's uncapped warm paths and
# polish spent up to 2 s on one tick at N = 1000, 13-27x clarabel's worst) while every stage that
# certifies in the pinned tests and benches keeps its answer bit for bit (successful ones spend < 60)
_RUNAWAY_SOLVES = 60
# clarabel's cold iteration count assumed before this filter has run it (the dense crossing: 13-28 at
# N = 100-5000): with warm_share, a cold call's dual prediction on more than _SHARE_MIN_ROWS predicted
# rows may spend warm_share of it (the crossing's first tick at N = 200 needs 20 Gram factorisations,
# 1.65x clarabel's worst with the fixed cap of 12)
_COLD_ITERS_GUESS = 25
_KIND_NAMES = {PAIR: "pair", WALL: "wall", OBSTACLE: "obstacle", LIMIT: "limit", SEGMENT: "segment"}


class InputError(ValueError, SwarmdeckError):
    """Malformed input to the filter (shape or non-finite values)."""


def as_points(x: ArrayLike, name: str, n: int | None = None) -> np.ndarray:
    """``x`` as a float (n, 2) array, or InputError naming what is wrong."""
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric (N, 2) array: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InputError(f"{name} must have shape (N, 2), got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name} must have shape ({n}, 2) like points, got {arr.shape}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        raise InputError(f"{name} contains NaN or inf in rows {bad[:10].tolist()}")
    return arr


def as_robot_bounds(x: ArrayLike, n: int) -> np.ndarray:
    """``x`` as per-robot wall rectangles, a float (n, 4) array of ``[x_min, x_max, y_min, y_max]`` (m) with
    finite values and min < max, or InputError naming what is wrong."""
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"robot_bounds must be a numeric (N, 4) array: {exc}") from None
    if arr.shape != (n, 4):
        raise InputError(f"robot_bounds must have shape ({n}, 4) like points, got {arr.shape}")
    bad = ~(np.all(np.isfinite(arr), axis=1) & (arr[:, 0] < arr[:, 1]) & (arr[:, 2] < arr[:, 3]))
    if bad.any():
        raise InputError(f"robot_bounds rows {np.flatnonzero(bad)[:10].tolist()} are not finite rectangles "
                         "[x_min, x_max, y_min, y_max] with min < max")
    return arr


def robot_count(points: ArrayLike, nominal: ArrayLike) -> int:
    """Best guess of N for a fail-stop answer to malformed input."""
    for x in (nominal, points):
        try:
            arr = np.asarray(x)
            if arr.ndim >= 1:
                return int(arr.shape[0])
        except Exception:  # noqa: BLE001 - anything unreadable gives no count
            pass
    return 0


def restrict(rows: Rows, robots: np.ndarray, n: int) -> tuple[Rows, np.ndarray]:
    """Rows whose first robot is in ``robots`` ((N,) bool), re-indexed to the subset."""
    remap = np.full(n, -1, dtype=np.int64)
    remap[robots] = np.arange(int(robots.sum()))
    keep = robots[rows.i]
    sub = rows.select(keep)
    j = np.where(sub.j >= 0, remap[np.maximum(sub.j, 0)], -1)
    return Rows(remap[sub.i], j, sub.ci, sub.cj, sub.b, sub.h, sub.kind, sub.key), keep


def _pair_columns(i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``np.stack([i, j], axis=1)`` (K, 2) for two (K,) index arrays, without stack's generality."""
    out = np.empty((i.shape[0], 2), dtype=np.result_type(i, j))
    out[:, 0] = i
    out[:, 1] = j
    return out


@dataclass(frozen=True)
class _Solved:
    u: np.ndarray
    active: np.ndarray  # (m,) bool rows at equality
    n_speed: int
    method: str
    iterations: int
    lam: np.ndarray | None = None  # (m,) the rows' multipliers when the solver certified them


_BUDGET = "budget"  # reason prefix: the call's work cap or deadline ran out (anytime: the floor answers)


class _Budget:
    """One call's work tally against its caps; made per call, never shared or kept.

    total: factorisations (active-set Gram solves + clarabel iterations) the centralised QP may
    spend in this call (None: unlimited); warm: those the closed-loop warm paths may spend before
    the filter goes to clarabel cold (None: unlimited); deadline: ``time.perf_counter()`` value
    (None: none); polish: those clarabel's polish may spend on its own (None: ``warm``). ``spent``
    counts everything, ``warm_spent`` the warm paths' share.
    """

    def __init__(self, total: int | None, warm: int | None, deadline: float | None,
                 polish: int | None = None) -> None:
        self.total, self.warm, self.deadline = total, warm, deadline
        self.polish = warm if polish is None else polish
        self.spent = 0
        self.warm_spent = 0

    def left(self, warm: bool = False) -> int | None:
        """Factorisations still allowed (None: unlimited); 0 once the deadline has passed."""
        if self.deadline is not None and time.perf_counter() >= self.deadline:
            return 0
        caps = [] if self.total is None else [self.total - self.spent]
        if warm and self.warm is not None:
            caps.append(self.warm - self.warm_spent)
        return max(min(caps), 0) if caps else None

    def seconds_left(self) -> float | None:
        """Wall time left to the deadline in s (None: no deadline)."""
        return None if self.deadline is None else max(self.deadline - time.perf_counter(), 0.0)

    def spend(self, k: int, warm: bool = False) -> None:
        """Count ``k`` factorisations (also against the warm cap when ``warm``)."""
        self.spent += int(k)
        if warm:
            self.warm_spent += int(k)

    def out(self) -> bool:
        """The total cap or the deadline is reached (the warm cap only ends the warm paths)."""
        left = self.left()
        return left is not None and left <= 0


class SafetyFilter:
    """Barrier-certificate filter for single-integrator controlled points.

    Holds only the warm start (the previous tick's active rows and their multipliers); call
    :meth:`reset` when the robot set changes meaning (it is also reset
    automatically when N or the obstacle count changes, and after a failure).
    """

    def __init__(self, config: BarrierConfig | None = None, *, robots: int | None = None) -> None:
        """``robots``: the robot count the caller will filter, when known: a small one (``small_kernels.small``)
        runs the kernels in plain Python, so numba is not loaded here (a larger problem later loads it then)."""
        self.config = BarrierConfig() if config is None else config
        self._warm_keys = np.zeros(0, dtype=np.int64)
        self._near_keys = np.zeros(0, dtype=np.int64)
        self._warm_shape: tuple[int, int] = (-1, -1)
        self._lam_keys = np.zeros(0, dtype=np.int64)
        self._lam = np.zeros(0)
        self._reset_backoff()
        self._walls: np.ndarray | None = None  # this call's per-robot wall rectangles (N, 4), for its diagnostics
        if self.config.solver == "auto":
            dual_ascent.warm_up(robots)  # numba's compile (or cache load) here, never in a tick

    def _dual_enabled(self) -> bool:
        cfg = self.config
        return cfg.solver == "auto" and cfg.warm_dual_sweeps > 0 and dual_ascent.AVAILABLE

    def reset(self) -> None:
        """Forget the warm start."""
        self._warm_keys = np.zeros(0, dtype=np.int64)
        self._near_keys = np.zeros(0, dtype=np.int64)
        self._warm_shape = (-1, -1)
        self._lam_keys = np.zeros(0, dtype=np.int64)
        self._lam = np.zeros(0)
        self._reset_backoff()

    def _reset_backoff(self) -> None:
        # capped stages that failed (BarrierConfig.warm_share): consecutive failures and calls left
        # to skip, for the warm paths and clarabel's polish; clarabel's last cold iteration count
        self._warm_fails = self._warm_wait = 0
        self._polish_fails = self._polish_wait = 0
        self._cold_iters = 0

    def _wait(self, fails: int) -> int:
        """Calls a capped stage is skipped after its ``fails``-th consecutive failure: 1 without
        ``warm_share``; with it 2^k − 1 (k = fails, at most 5): 1, 3, 7, 15, 31."""
        return 1 if self.config.warm_share is None else 2 ** min(fails, 5) - 1

    def _stage_cap(self) -> int:
        """Factorisations one active-set stage may spend: ``active_set_max_solves``, or ``_RUNAWAY_SOLVES``."""
        cap = self.config.active_set_max_solves
        return _RUNAWAY_SOLVES if cap is None else cap

    def _polish_cap(self) -> int:
        """Factorisations clarabel's polish may spend: ``active_set_max_solves`` but at most
        ``_POLISH_SOLVES``, or ``_RUNAWAY_SOLVES`` when that is None."""
        cap = self.config.active_set_max_solves
        return _RUNAWAY_SOLVES if cap is None else min(cap, _POLISH_SOLVES)

    def _warm_cap(self) -> int | None:
        """Factorisations the warm paths of this call may spend (``active_set_max_solves``, and, when
        last tick held more than ``_SHARE_MIN_ROWS`` active rows, at most ``warm_share`` of clarabel's
        last cold iteration count, at least 1). Clarabel's polish keeps its own allowance."""
        cfg = self.config
        cap = self._stage_cap()
        if (cfg.active_set_max_solves is None or cfg.warm_share is None or not self._cold_iters
                or self._warm_keys.size <= _SHARE_MIN_ROWS):
            return cap
        return min(cap, max(1, int(cfg.warm_share * self._cold_iters)))

    # ------------------------------------------------------------------ public
    def filter(self, points: ArrayLike, nominal: ArrayLike, obstacles: ArrayLike | None = None, *,
               robot_bounds: ArrayLike | None = None) -> tuple[np.ndarray, BarrierDiagnostics]:
        """Safe velocities for controlled points.

        points (N, 2) m, nominal (N, 2) m/s, obstacles (M, 2) m or None (fixed
        points every robot keeps D_s from), robot_bounds (N, 4) m or None: each robot's own wall
        rectangle ``[x_min, x_max, y_min, y_max]`` (its region of a shared floor) instead of
        ``config.bounds``. Returns (safe (N, 2) new array, diagnostics). Never raises for bad
        input: zeros and ``diag.ok`` False.
        """
        t0 = time.perf_counter()
        try:
            P = as_points(points, "points")
            U = as_points(nominal, "nominal", P.shape[0])
            O = None if obstacles is None else as_points(obstacles, "obstacles")
            W = None if robot_bounds is None else as_robot_bounds(robot_bounds, P.shape[0])
        except InputError as exc:
            return self.fail_stop(robot_count(points, nominal), nominal, f"invalid input: {exc}", t0)
        return self.solve(P, U, O, None, self.config.max_speed, t0, robot_bounds=W)

    @staticmethod
    def coordinate_problem(P: np.ndarray, O: np.ndarray | None) -> str | None:
        """Why the positions cannot be filtered (|coordinate| > MAX_COORDINATE), or None."""
        for name, arr in (("points", P), ("obstacles", O)):
            if arr is not None and arr.size and float(np.abs(arr).max()) > MAX_COORDINATE:
                bad = np.flatnonzero(np.max(np.abs(arr), axis=1) > MAX_COORDINATE)
                return (f"{name} coordinates beyond ±{MAX_COORDINATE:g} m in rows {bad[:10].tolist()} "
                        "(not a position: tracking or units error)")
        return None

    # ------------------------------------------------------------ for subclasses
    def fail_stop(self, n: int, nominal: ArrayLike, reason: str, t0: float, n_constraints: int = 0
                  ) -> tuple[np.ndarray, BarrierDiagnostics]:
        """Zero commands for every robot and a diagnostic saying why."""
        self.reset()
        try:
            nom = np.asarray(nominal, dtype=float).reshape(n, 2)
            inter = np.nan_to_num(np.linalg.norm(nom, axis=1), nan=0.0, posinf=0.0)
        except Exception:  # noqa: BLE001 - unreadable nominal: no intervention figure
            inter = np.zeros(n)
        diag = BarrierDiagnostics(
            ok=False, status=f"failed: {reason}", solve_time_s=time.perf_counter() - t0,
            n_constraints=n_constraints, n_active=0, active_pairs=np.zeros((0, 2), dtype=np.int64),
            active_h=np.zeros(0), min_distance=float("nan"), min_wall_clearance=float("nan"),
            intervention=inter, nominal_was_safe=False, method="fail-stop", answer="stopped",
        )
        return np.zeros((n, 2)), diag

    def solve(self, P: np.ndarray, U: np.ndarray, O: np.ndarray | None, extra: Rows | None,
              max_speed: float | None, t0: float, *, robot_bounds: np.ndarray | None = None
              ) -> tuple[np.ndarray, BarrierDiagnostics]:
        """Filter validated arrays; ``extra`` rows (e.g. wheel limits) are added to the barrier rows;
        ``robot_bounds`` (N, 4): per-robot wall rectangles (validated by :func:`as_robot_bounds`)."""
        cfg = self.config
        self._walls = robot_bounds
        n = P.shape[0]
        n_obs = 0 if O is None else O.shape[0]
        if n == 0:
            return np.zeros((0, 2)), self._diag(True, "no robots", t0, Rows.empty(), P, U, U, O,
                                                np.zeros(0, bool), 0, True, "pass-through", 0, 0, 0)
        problem = self.coordinate_problem(P, O)
        if problem is not None:
            return self.fail_stop(n, U, problem, t0)
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                rows = barrier_rows(P, cfg, O, None, robot_bounds)
        except (ValueError, FloatingPointError, OverflowError) as exc:  # never out of the filter
            return self.fail_stop(n, U, f"cannot build the barrier rows: {exc}", t0)
        if extra is not None and extra.m:
            rows = Rows.concat([rows, extra])
        if not np.isfinite(rows.b).all():
            # an overflowing bound (inf) or inf·0 (NaN) would silently drop its row from the QP
            bad = ~np.isfinite(rows.b)
            kinds = sorted({_KIND_NAMES[int(k)] for k in np.unique(rows.kind[bad])})
            return self.fail_stop(n, U, f"non-finite bound in {int(bad.sum())} {'/'.join(kinds)} row(s) "
                                  "(gains too large for these positions)", t0, rows.m)
        if cfg.distributed_for(n):
            return self._solve_distributed(P, U, O, rows, max_speed, t0)
        anytime = cfg.anytime_for(n)
        deadline = t0 + cfg.time_budget_s if anytime and cfg.time_budget_s is not None else None
        budget = _Budget(cfg.work_budget if anytime else None, self._warm_cap(), deadline,
                         self._polish_cap())
        unsafe = (rows.h < 0) & (rows.kind != LIMIT)
        n_unsafe = int(unsafe.sum())
        recovering = cfg.recovery and n_unsafe > 0
        plain = rows
        if recovering:
            # rows with h < 0 keep their plain barrier bound (with the cubic κ it already demands
            # separation; the answer is the plain QP's), capped at recovery_speed; deep overlaps
            # demand recovery_speed exactly, so they end in a bounded time. Only when those rows
            # are jointly infeasible does the soft form run (BarrierConfig.recovery)
            deep = unsafe & cfg.deep_overlap(rows.h, (rows.kind == WALL) | (rows.kind == SEGMENT))
            b = np.where(unsafe, np.maximum(rows.b, -cfg.recovery_speed), rows.b)
            rows = dataclasses.replace(rows, b=np.where(deep, -cfg.recovery_speed, b))

        # pass-through: û satisfies every row and speed bound → u* = û exactly
        if self._satisfies(rows, U, max_speed):
            none = np.zeros(rows.m, bool)
            self._remember_none(rows, n, n_obs)
            return U.copy(), self._diag(True, "nominal safe", t0, rows, P, U, U, O, none,
                                        0, True, "pass-through", 0, 0, n_unsafe, answer="optimum")

        if not recovering:  # one part, every robot: the loop below's answer without its copies
            solved = self._solve_plain(rows, U, max_speed, n, n_obs, budget)
            if isinstance(solved, str) and solved.startswith(_BUDGET):
                return self._solve_floor(P, U, O, plain, max_speed, t0, budget, solved)
            if isinstance(solved, str):
                return self.fail_stop(n, U, solved, t0, rows.m)
            lam = np.zeros(rows.m) if solved.lam is None else solved.lam
            self._remember(rows, solved.active, n, n_obs, solved.u, lam)
            return solved.u, self._diag(True, "optimal", t0, rows, P, U, solved.u, O, solved.active, solved.n_speed,
                                        False, solved.method, solved.iterations, 0, n_unsafe, answer="optimum",
                                        work=budget.spent)
        n_clusters = 0
        if recovering:  # clusters with unsafe rows are solved apart (their QP may be infeasible)
            n_clusters, labels = self._clusters(rows, n)
            in_bad = np.isin(labels, np.unique(labels[rows.i[unsafe]]))
        else:
            in_bad = np.zeros(n, dtype=bool)
        u = np.zeros((n, 2))
        active = np.zeros(rows.m, dtype=bool)
        lam = np.zeros(rows.m)
        methods, iterations, n_speed, soft_used = [], 0, 0, False
        for part in (in_bad, ~in_bad):
            if not part.any():
                continue
            if part.all():
                sub, keep = rows, np.ones(rows.m, dtype=bool)
            else:
                sub, keep = restrict(rows, part, n)
            solved = self._solve_plain(sub, U[part], max_speed, n, n_obs, budget)
            if isinstance(solved, str) and solved.startswith(_BUDGET):
                return self._solve_floor(P, U, O, plain, max_speed, t0, budget, solved)
            if isinstance(solved, str) and part is in_bad and solved.startswith("infeasible"):
                solved = self._solve_soft(restrict(plain, part, n)[0] if not part.all() else plain,
                                          unsafe[keep], U[part], max_speed, budget)
                soft_used = True
                if isinstance(solved, str) and solved.startswith(_BUDGET):
                    return self._solve_floor(P, U, O, plain, max_speed, t0, budget, solved)
            if isinstance(solved, str):
                detail = f" (recovering {n_unsafe} unsafe rows)" if recovering else ""
                return self.fail_stop(n, U, solved + detail, t0, rows.m)
            u[part] = solved.u
            active[keep] = solved.active
            if solved.lam is not None:
                lam[keep] = solved.lam
            methods.append(solved.method)
            iterations += solved.iterations
            n_speed += solved.n_speed
        self._remember(rows, active, n, n_obs, u, lam)
        method = methods[0] if len(methods) == 1 else "mixed"
        status = "optimal"
        if recovering:
            status = f"optimal (recovering {n_unsafe} unsafe rows{', soft separation' if soft_used else ''})"
        return u, self._diag(True, status, t0, rows, P, U, u, O, active, n_speed, False, method,
                             iterations, n_clusters, n_unsafe, answer="optimum", work=budget.spent)

    # ---------------------------------------------------------------- helpers
    @staticmethod
    def _satisfies(rows: Rows, U: np.ndarray, max_speed: float | None) -> bool:
        """û meets every row (to _PASS_TOL) and every speed bound (exactly)."""
        if max_speed is not None and not bool((np.einsum("kd,kd->k", U, U) <= max_speed**2).all()):
            return False
        return bool((rows.lhs(U) <= rows.b + _PASS_TOL).all())

    @staticmethod
    def _active_set(rows: Rows, U: np.ndarray, max_speed: float | None, warm_rows: np.ndarray | None,
                    max_iter: int, budget: _Budget, warm: bool = False, multipliers: np.ndarray | None = None,
                    polish: bool = False) -> ActiveSetResult:
        """``solve_active_set`` within what ``budget`` has left (the warm cap too when ``warm``; for
        clarabel's ``polish`` its own allowance, ``_polish_cap``), tallied."""
        left = budget.left(warm)
        if polish and budget.polish is not None:
            left = budget.polish if left is None else min(left, budget.polish)
        res = solve_active_set(rows, U, max_speed, warm_rows, max_iter, multipliers=multipliers,
                               max_solves=left, deadline=budget.deadline)
        budget.spend(res.solves, warm)
        return res

    @staticmethod
    def _clarabel(rows: Rows, U: np.ndarray, max_speed: float | None, max_iter: int, tol: float,
                  budget: _Budget, discs: np.ndarray | None = None, warm: bool = False) -> QPResult | None:
        """``solve_qp`` with at most the iterations (and wall time) ``budget`` has left, tallied."""
        left = budget.left(warm)
        if left is not None:
            max_iter = min(max_iter, left)
        if max_iter <= 0:
            return None
        qp = solve_qp(rows, U, max_speed, max_iter=max_iter, tol=tol, discs=discs,
                      time_limit=budget.seconds_left())
        budget.spend(qp.iterations, warm)
        return qp

    def _solve_plain(self, rows: Rows, U: np.ndarray, max_speed: float | None, n: int, n_obs: int,
                     budget: _Budget) -> _Solved | str:
        """Exact QP on hard rows: warm active set (certified), else clarabel (polished), with retries.

        The warm paths stop at the budget's warm cap and go to clarabel cold at once; a reason
        starting with ``_BUDGET`` says the total cap (or the deadline) ran out before a certified optimum.
        """
        cfg = self.config
        iterations = 0
        if cfg.solver == "auto":
            solved, iterations = self._solve_warm(rows, U, max_speed, n, n_obs, budget)
            if solved is not None:
                self._warm_fails = 0
                return solved
        if budget.warm is not None and budget.warm_spent >= budget.warm:
            # the warm paths spent the whole active-set cap and gave up: skip them for a while
            self._warm_fails += 1
            self._warm_wait = self._wait(self._warm_fails)
        if budget.out():
            return f"{_BUDGET}: work cap reached before clarabel"
        qp = self._clarabel(rows, U, max_speed, cfg.clarabel_max_iter, cfg.clarabel_tol, budget)
        if qp is None:  # the deadline passed in between
            return f"{_BUDGET}: deadline reached before clarabel"
        if not qp.ok and budget.out():
            return f"{_BUDGET}: work cap reached in clarabel ({qp.reason})"
        if not qp.ok and not qp.reason.startswith("infeasible"):
            # numerical trouble at the tight tolerance: a longer cold active-set run (certified),
            # then clarabel at a 10× looser tolerance; still only a "Solved" answer is used
            if cfg.solver == "auto":
                res = self._active_set(rows, U, max_speed, None, 4 * cfg.max_active_set_iterations, budget,
                                       polish=True)
                iterations += res.iterations
                if res.ok:
                    return _Solved(res.u, res.active, int(res.speed_active.sum()), "active-set", iterations,
                                   res.multipliers)
            retry = self._clarabel(rows, U, max_speed, cfg.clarabel_max_iter, 10 * cfg.clarabel_tol, budget)
            if retry is None or (not retry.ok and budget.out()):
                return f"{_BUDGET}: work cap reached in the retries ({qp.reason})"
            qp = retry if retry.ok else qp
        if not qp.ok:
            return qp.reason
        self._cold_iters = qp.iterations
        return self._finish_clarabel(rows, U, qp.u, max_speed, iterations + qp.iterations, budget)

    def _solve_warm(self, rows: Rows, U: np.ndarray, max_speed: float | None, n: int, n_obs: int,
                    budget: _Budget) -> tuple[_Solved | None, int]:
        """The closed-loop warm paths and the small cold active set (certified), within the budget's
        warm cap: (the answer or None, active-set iterations spent)."""
        cfg = self.config
        iterations = 0
        warm = None
        if self._warm_shape == (n, n_obs) and self._warm_keys.size:
            # rows.key in the sorted unique _warm_keys (np.isin's answer, by one binary search)
            keys = self._warm_keys
            warm = keys[np.minimum(keys.searchsorted(rows.key), keys.size - 1)] == rows.key
        closed_loop = warm is not None and bool(warm.any())
        if closed_loop and self._warm_wait > 0:
            # a recent tick's warm paths spent the whole active-set cap and gave up: this tick goes to
            # clarabel cold at once (its polished answer warm-starts the next tick, which may try again)
            self._warm_wait -= 1
            closed_loop, warm, skipped = False, None, True
        else:
            skipped = False
        if closed_loop and self._dual_enabled():
            solved = self._solve_dual(rows, U, max_speed, budget)
            if solved is not None:
                return solved, iterations
        if closed_loop and warm is not None:  # the previous tick's active rows: few iterations while they are few
            start, limit, method = int(warm.sum()), cfg.warm_max_rows, "warm active-set"
        else:
            start, limit, method = int(np.sum(rows.lhs(U) > rows.b)), cfg.active_set_max_rows, "active-set"
        if start <= limit and budget.left(True) != 0 and not skipped:
            res = self._active_set(rows, U, max_speed, warm, cfg.max_active_set_iterations, budget, True)
            iterations += res.iterations
            if res.ok:
                return _Solved(res.u, res.active, int(res.speed_active.sum()), method, iterations,
                               res.multipliers), iterations
        elif start > limit and closed_loop and self._near_keys.size:
            solved = self._solve_pruned(rows, U, max_speed, budget)
            if solved is not None:
                return solved, iterations
        if not closed_loop and not skipped and cfg.cold_dual and self._dual_enabled() and budget.left(True) != 0:
            # cold: the dual ascent from zero multipliers predicts the active rows and the active set
            # certifies from them, before clarabel (random scenes: every call certified, the same bits
            # as clarabel + polish, 1/5 of the time at N = 100; bench/RESULTS.md "cold calls")
            solved = self._solve_dual(rows, U, max_speed, budget, cold=True)
            if solved is not None:
                return solved, iterations
        return None, iterations

    def _solve_pruned(self, rows: Rows, U: np.ndarray, max_speed: float | None, budget: _Budget
                      ) -> _Solved | None:
        """Closed loop beyond ``warm_max_rows``: clarabel on the rows that were within ``warm_slack``
        of their bound last tick (and those û violates), speed cones only for robots whose nominal is
        near the bound, then the active set from its active rows on *all* rows (certified: KKT, every
        row, every speed bound). None when either step fails: the caller solves everything cold."""
        cfg = self.config
        at = np.minimum(np.searchsorted(self._near_keys, rows.key), self._near_keys.size - 1)
        keep = (self._near_keys[at] == rows.key) | (rows.lhs(U) > rows.b)
        discs = None
        if max_speed is not None:
            discs = np.einsum("kd,kd->k", U, U) >= (_WARM_DISC_FRACTION * max_speed) ** 2
        qp = self._clarabel(rows.select(keep), U, max_speed, cfg.clarabel_max_iter, cfg.clarabel_tol, budget,
                            discs=discs, warm=True)
        if qp is None or not qp.ok:
            return None
        near = rows.lhs(qp.u) >= rows.b - _ACTIVE_TOL
        res = self._active_set(rows, U, max_speed, near, cfg.max_active_set_iterations, budget, True)
        if not res.ok:
            return None
        return _Solved(res.u, res.active, int(res.speed_active.sum()), "warm clarabel+active-set",
                       qp.iterations + res.iterations, res.multipliers)

    def _solve_dual(self, rows: Rows, U: np.ndarray, max_speed: float | None, budget: _Budget,
                    cold: bool = False) -> _Solved | None:
        """Closed loop: the compiled dual coordinate ascent from last tick's multipliers (by row key;
        ``cold``: from zero) predicts the active rows; the active set from them certifies the exact
        optimum (KKT, every row, every speed bound) within ``warm_dual_iterations``. None otherwise
        (the caller goes on)."""
        cfg = self.config
        lam0 = np.zeros(rows.m)
        if self._lam_keys.size and not cold:
            at = np.minimum(self._lam_keys.searchsorted(rows.key), self._lam_keys.size - 1)
            hit = self._lam_keys[at] == rows.key
            lam0[hit] = self._lam[at[hit]]
        method = "dual+active-set" if cold else "warm dual+active-set"
        guess = dual_ascent.ascend(rows, U, max_speed, lam0, cfg.warm_dual_sweeps)
        if (cold and cfg.warm_share is not None and budget.warm is not None
                and int(guess.predicted.sum()) > _SHARE_MIN_ROWS):
            share = max(1, int(cfg.warm_share * (self._cold_iters or _COLD_ITERS_GUESS)))
            budget.warm = min(budget.warm, budget.warm_spent + share)
        res = self._active_set(rows, U, max_speed, guess.predicted, cfg.warm_dual_iterations, budget, True,
                               multipliers=guess.lam)
        if not res.ok:
            return None
        if not np.array_equal(res.active, guess.predicted):
            # reproducible to the last bit whatever the warm history: the answer is the one the
            # active set gives from the optimum's own active rows (as every other warm path and a
            # second call on the same tick do), not one that depends on which wrong rows left when
            again = self._active_set(rows, U, max_speed, res.active, cfg.max_active_set_iterations, budget, True)
            if again.ok:
                return _Solved(again.u, again.active, int(again.speed_active.sum()), method,
                               res.iterations + again.iterations, again.multipliers)
        return _Solved(res.u, res.active, int(res.speed_active.sum()), method, res.iterations, res.multipliers)

    def _finish_clarabel(self, rows: Rows, U: np.ndarray, u: np.ndarray, max_speed: float | None,
                         iterations: int, budget: _Budget) -> _Solved | str:
        """Make an interior-point answer exact where possible.

        "auto": the active set started from clarabel's active rows usually certifies the exact
        optimum in one or two iterations (KKT checked). Otherwise clarabel's answer is kept,
        projected onto the speed discs, and robots with no row near its bound and a nominal
        inside the disc get their nominal back bit for bit (the exact optimum leaves them alone).
        """
        cfg = self.config
        near = rows.lhs(u) >= rows.b - _ACTIVE_TOL
        shared = budget.warm is not None and cfg.warm_share is not None
        if cfg.solver == "auto" and shared and self._polish_wait > 0:
            self._polish_wait -= 1  # the polish spent its cap and failed recently: clarabel's answer
        elif cfg.solver == "auto":
            if shared and cfg.warm_share is not None and int(near.sum()) > _SHARE_MIN_ROWS and budget.polish is not None:
                # many rows: the polish too gets at most warm_share of this cold solve's iterations (≥ 1);
                # on the dense crossing at N = 200 it needs 56-128 factorisations or certifies in one
                budget.polish = min(budget.polish, max(1, int(cfg.warm_share * self._cold_iters)))
            res = self._active_set(rows, U, max_speed, near, cfg.max_active_set_iterations, budget, polish=True)
            iterations += res.iterations
            if res.ok:
                self._polish_fails = 0
                return _Solved(res.u, res.active, int(res.speed_active.sum()), "clarabel+active-set", iterations,
                               res.multipliers)
            if shared and res.reason == "work cap":
                self._polish_fails += 1
                self._polish_wait = self._wait(self._polish_fails)
        vmax = np.inf if max_speed is None else float(max_speed)
        out = clip_speed(u, vmax)
        touched = np.zeros(U.shape[0], dtype=bool)
        touched[rows.i[near]] = True
        touched[rows.jj[near]] = True
        free = ~touched & (np.einsum("kd,kd->k", U, U) < (vmax - _ACTIVE_TOL) ** 2)
        if free.any():
            trial = out.copy()
            trial[free] = U[free]
            if np.all(rows.lhs(trial) <= np.maximum(rows.b, rows.lhs(out))):
                out = trial
        viol = float(np.max(rows.lhs(out) - rows.b, initial=0.0))
        if viol > _CLARABEL_FEAS:
            return f"solver answer violates a row by {viol:.2e} m/s"
        speed = 0 if max_speed is None else int(np.sum(np.linalg.norm(out, axis=1) >= max_speed - _ACTIVE_TOL))
        return _Solved(out, rows.lhs(out) >= rows.b - _ACTIVE_TOL, speed, "clarabel", iterations)

    def _solve_soft(self, rows: Rows, unsafe: np.ndarray, U: np.ndarray, max_speed: float | None,
                    budget: _Budget | None = None) -> _Solved | str:
        """Recovery when the capped plain rows are infeasible: hard "no further approach" rows
        (b = max(b, 0), always feasible: u = 0 meets them) and slack-penalised separation
        targets at the capped bound, by clarabel, retried at a 10× looser tolerance; within what
        ``budget`` has left (a reason starting with ``_BUDGET`` when it runs out: anytime's floor)."""
        cfg = self.config
        soft = np.flatnonzero(unsafe)
        b_hard = np.where(unsafe, np.maximum(rows.b, 0.0), rows.b)
        b_soft = np.maximum(rows.b[soft], -cfg.recovery_speed)
        iterations = 0
        for tol in (cfg.clarabel_tol, 10 * cfg.clarabel_tol):
            left = None if budget is None else budget.left()
            if left is not None and left <= 0:
                return f"{_BUDGET}: work cap reached in the soft recovery"
            res = solve_qp(rows, U, max_speed, b_hard=b_hard, soft=soft, b_soft=b_soft,
                           soft_weight=cfg.recovery_weight,
                           max_iter=cfg.clarabel_max_iter if left is None else min(cfg.clarabel_max_iter, left),
                           tol=tol, time_limit=None if budget is None else budget.seconds_left())
            iterations += res.iterations
            if budget is not None:
                budget.spend(res.iterations)
            if res.ok:
                break
        if not res.ok and budget is not None and budget.out():
            return f"{_BUDGET}: work cap reached in the soft recovery ({res.reason})"
        if not res.ok:
            return res.reason
        hard = dataclasses.replace(rows, b=b_hard)
        out = clip_speed(res.u, np.inf if max_speed is None else float(max_speed))
        viol = float(np.max(hard.lhs(out) - b_hard, initial=0.0))
        if viol > _CLARABEL_FEAS:
            return f"solver answer violates a row by {viol:.2e} m/s"
        speed = 0 if max_speed is None else int(np.sum(np.linalg.norm(out, axis=1) >= max_speed - _ACTIVE_TOL))
        return _Solved(out, hard.lhs(out) >= b_hard - _ACTIVE_TOL, speed, "clarabel", iterations)

    def _solve_distributed(self, P: np.ndarray, U: np.ndarray, O: np.ndarray | None, rows: Rows, max_speed: float | None, t0: float
                           ) -> tuple[np.ndarray, BarrierDiagnostics]:
        """Every robot's own QP on half of each pair row (``safety.distributed``, REFERENCE.md §12)."""
        res = filter_distributed(rows, U, max_speed, self.config)
        n = P.shape[0]
        if not res.ok:
            return self.fail_stop(n, U, f"distributed: {res.reason}", t0, rows.m)
        n_unsafe = int(np.sum((rows.h < 0) & (rows.kind != LIMIT)))
        was_safe = bool(np.array_equal(res.u, U))
        status = "nominal safe" if was_safe else "optimal per robot"
        if n_unsafe:
            status += f" (recovering {n_unsafe} unsafe rows, {res.n_fallback} robots holding)"
        return res.u, self._diag(True, status, t0, rows, P, U, res.u, O, res.active, res.n_speed, was_safe,
                                 "distributed", 0, 0, n_unsafe, answer="distributed")

    def _solve_floor(self, P: np.ndarray, U: np.ndarray, O: np.ndarray | None, rows: Rows, max_speed: float | None, t0: float, budget: _Budget,
                     reason: str) -> tuple[np.ndarray, BarrierDiagnostics]:
        """Anytime mode, the budget spent before a certified optimum: the distributed answer on the
        same rows (every row certified, ``safety.distributed``) with ``answer == "floor"``. The warm
        start is forgotten (the next tick starts cold, whose work is bounded by clarabel's)."""
        res = filter_distributed(rows, U, max_speed, self.config)
        n = P.shape[0]
        if not res.ok:
            return self.fail_stop(n, U, f"{reason}; distributed floor: {res.reason}", t0, rows.m)
        self.reset()
        u = res.u if max_speed is None else clip_speed(res.u, float(max_speed))  # exactly inside the discs
        n_unsafe = int(np.sum((rows.h < 0) & (rows.kind != LIMIT)))
        return u, self._diag(True, f"distributed floor ({reason})", t0, rows, P, U, res.u, O, res.active,
                                 res.n_speed, False, "distributed floor", 0, 0, n_unsafe, answer="floor",
                                 work=budget.spent)

    def _remember(self, rows: Rows, active: np.ndarray, n: int, n_obs: int, u: np.ndarray,
                  lam: np.ndarray | None = None) -> None:
        """Keep the active rows' keys (and their multipliers, (m,) ``lam``) for the next tick's warm
        start and, when they are too many for the warm active set, the keys of every row within
        ``warm_slack`` of its bound at ``u``."""
        self._warm_keys = np.sort(rows.key[active])
        held = (lam > 0).nonzero()[0] if lam is not None else np.zeros(0, dtype=np.int64)
        order = np.argsort(rows.key[held])
        self._lam_keys = rows.key[held][order]
        self._lam = lam[held][order] if lam is not None else np.zeros(0)
        self._near_keys = np.zeros(0, dtype=np.int64)
        if self._warm_keys.size > self.config.warm_max_rows:
            self._near_keys = np.sort(rows.key[rows.lhs(u) >= rows.b - self.config.warm_slack])
        self._warm_shape = (n, n_obs)

    def _remember_none(self, rows: Rows, n: int, n_obs: int) -> None:
        """:meth:`_remember` of no active row and no multipliers (the pass-through): empty keys of ``rows.key``'s
        dtype, no multipliers."""
        self._warm_keys = rows.key[:0].copy()
        self._lam_keys = rows.key[:0].copy()
        self._lam = np.zeros(0)
        self._near_keys = np.zeros(0, dtype=np.int64)
        self._warm_shape = (n, n_obs)

    @staticmethod
    def _clusters(rows: Rows, n: int) -> tuple[int, np.ndarray]:
        two = rows.j >= 0
        if not two.any():
            return n, np.arange(n)
        import scipy.sparse as sp  # lazy: see test_devices_rps_startup_imports
        from scipy.sparse.csgraph import connected_components

        graph = sp.coo_matrix((np.ones(int(two.sum())), (rows.i[two], rows.j[two])), shape=(n, n))
        return connected_components(graph, directed=False)

    def _diag(self, ok: bool, status: str, t0: float, rows: Rows, P: np.ndarray, U: np.ndarray, u: np.ndarray,
              O: np.ndarray | None, active: np.ndarray, n_speed: int, was_safe: bool, method: str,
              iterations: int, n_clusters: int, n_unsafe: int, answer: str = "", work: int = 0) -> BarrierDiagnostics:
        cfg = self.config
        n = P.shape[0]
        pair = rows.kind == PAIR
        act_pair = pair & active
        if pair.any():  # h + D_s² ≥ 0 (h = d² − D_s² rounds to ≥ −D_s²): math.sqrt, the same IEEE root as np.sqrt
            min_d = math.sqrt(float(rows.h[pair].min()) + cfg.safety_distance**2)
        elif n >= 2:
            min_d = nearest_pair_distance(P)
        else:
            min_d = float("inf")
        walls = self._walls
        if not n:
            min_wall = float("inf")
        elif walls is None:
            # one rectangle: min(x − c) = min(x) − c and min(c − x) = c − max(x) exactly (rounding is monotonic)
            left, right, bottom, top = (float(v) for v in cfg.bounds)
            lo, hi = P.min(axis=0).tolist(), P.max(axis=0).tolist()
            min_wall = min(lo[0] - left, right - hi[0], lo[1] - bottom, top - hi[1])
        else:
            x_min, x_max, y_min, y_max = walls.T
            clear = np.stack([P[:, 0] - x_min, x_max - P[:, 0], P[:, 1] - y_min, y_max - P[:, 1]], axis=1)
            min_wall = float(clear.min())
        obs = rows.kind == OBSTACLE
        if obs.any():
            min_obs = float(np.sqrt(np.min(rows.h[obs]) + cfg.safety_distance**2))
        elif O is not None and O.shape[0] and n:
            from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

            min_obs = float(cKDTree(O).query(P, k=1)[0].min())
        else:
            min_obs = float("inf")
        if was_safe:
            inter = np.zeros(n)
        else:
            du = u - U
            inter = np.sqrt(np.einsum("kd,kd->k", du, du))
        return BarrierDiagnostics(
            ok=ok, status=status, solve_time_s=time.perf_counter() - t0, n_constraints=rows.m,
            n_active=int(active.sum()) + int(n_speed),
            active_pairs=_pair_columns(rows.i[act_pair], rows.j[act_pair]),
            active_h=rows.h[act_pair], min_distance=min_d, min_wall_clearance=min_wall,  # (indexing copies h)
            intervention=inter, nominal_was_safe=was_safe, method=method, iterations=iterations,
            n_clusters=int(n_clusters), n_unsafe=n_unsafe, min_obstacle_distance=min_obs,
            answer=answer, work=int(work), gap=0.0 if answer == "optimum" else None,
        )


__all__ = ["SafetyFilter", "InputError", "as_points", "as_robot_bounds", "robot_count", "restrict"]
