"""One tick's commands, the same for every driver (DESIGN.md "One tick", step 4).

:func:`certify` is the only place where nominal commands become the unicycle
commands a robot receives. The console's :class:`ControlLoop` (and so
``swarmdeck console`` with any robots) and the experiment API's
:meth:`Arena.step` (and so ``swarmdeck run`` and the rps facade) both call it,
so the same poses and nominal velocities give bit-identical wheel commands
whoever drives the robots.

The stages, for ``N`` robots:

1. nominal single-integrator velocities ``(N, 2)`` of the look-ahead points
   (m/s); rows that are NaN/inf (``invalid``) or belong to robots not seen this
   tick become zero;
2. the look-ahead map to unicycle ``(v, ω)`` (REFERENCE.md §1,
   v = cos θ u_x + sin θ u_y, ω = (−sin θ u_x + cos θ u_y)/ℓ);
3. the wheel limits by one uniform scale per robot (the curvature ω/v is kept;
   ``saturated`` marks the robots scaled down);
4. the barrier filter (optional): swarmdeck's unicycle barrier QP on the
   look-ahead points with each robot's four wheel-limit rows, so no later
   saturation can undo the certificate; any other filter on
   ``(points, velocities)`` is accepted and its answer limited again. Only
   robots seen this tick are filtered: unseen robots (their last known
   look-ahead point) and ``obstacles`` (M, 2) are fixed obstacles, and the
   diagnostics are mapped back to all N robots;
5. fail-stop: a filter that reports failure (``diag.ok`` False) or returns the
   wrong shape or non-finite values stops every robot (all commands zero).

Exceptions raised by a filter propagate: the caller decides (the console loop
counts them, alerts and stops the robots; an ``Arena`` script sees them).

A run whose barrier an operator let it bypass goes through :func:`certify_bypassed` instead: the
walls and obstacles stay hard (the same filter without pair rows), the full barrier watches in
monitor mode, and :mod:`swarmdeck.safety.guard` says when the barrier must come back; :func:`brake`
is its last resort (robots that would bring a pair closer than the guard distance stop).
"""
from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, Protocol, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, lookahead_points, si_to_unicycle, unicycle_to_si

if TYPE_CHECKING:
    from swarmdeck.core.bounds import Bounds
    from swarmdeck.safety import UnicycleSafetyFilter
    from swarmdeck.safety.guard import GuardCheck, GuardConfig

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class FilterDiagnostics(Protocol):
    """What a safety filter reports with its commands: at least ``ok`` (False: every robot was stopped) and
    ``status`` in words. swarmdeck's barrier returns :class:`~swarmdeck.safety.BarrierDiagnostics` (also
    ``active_pairs``, ``active_h``, ``intervention`` (N,) m/s, ``min_distance`` m, …), which :func:`certify` re-indexes
    over all robots and the console draws; a user's filter may report less (missing fields read as ok, "ok")."""

    @property
    def ok(self) -> bool: ...

    @property
    def status(self) -> str: ...


class CommandFilter(Protocol):
    """A safety filter on look-ahead points: ``filter(points (N, 2) m, nominal (N, 2) m/s, obstacles (M, 2) m or
    None) -> (safe (N, 2) m/s, diagnostics)`` (``Arena(safety=...)`` takes one; :func:`certify` maps to ``(v, ω)``)."""

    def filter(self, points: ArrayLike, nominal: ArrayLike, obstacles: ArrayLike | None = None
               ) -> tuple[FloatArray, FilterDiagnostics]: ...


class UnicycleCommandFilter(Protocol):
    """A safety filter on unicycle commands: ``filter(poses (N, 3), v (N,) m/s, w (N,) rad/s, obstacles (M, 2) m or
    None) -> (v, w, diagnostics)``; swarmdeck's barrier (:func:`barrier_filter`) is one."""

    def filter(self, poses: ArrayLike, v: ArrayLike, w: ArrayLike, obstacles: ArrayLike | None = None
               ) -> tuple[FloatArray, FloatArray, FilterDiagnostics]: ...


#: What :func:`certify` accepts as its barrier (None: no barrier).
SafetyFilterLike = CommandFilter | UnicycleCommandFilter


@dataclasses.dataclass(frozen=True, eq=False)
class Certified:
    """The commands of one tick and how they came about (N robots).

    Attributes:
        v, w: ``(N,)`` commands to send, m/s and rad/s (zero for unseen robots, all zero on failure).
        safe: ``(N, 2)`` velocity of each look-ahead point under ``(v, w)``, m/s.
        v_nominal, w_nominal: ``(N,)`` the nominal after the wheel limits, before the barrier.
        saturated: ``(N,)`` nominal scaled down by the wheel limits.
        invalid: ``(N,)`` nominal rows that were NaN/inf (commanded zero).
        ok: False when the filter failed and every robot was stopped.
        status: the filter's status in words ("off" without a filter, "no robot seen", …).
        diagnostics: the filter's diagnostics with per-robot arrays over all N robots, or None
            (no filter, or no robot seen).
    """

    v: FloatArray
    w: FloatArray
    safe: FloatArray
    v_nominal: FloatArray
    w_nominal: FloatArray
    saturated: BoolArray
    invalid: BoolArray
    ok: bool
    status: str
    diagnostics: FilterDiagnostics | None

    def changed(self) -> BoolArray:
        """``(N,)`` robots whose command the filter changed (beyond round-off of a non-unicycle filter): not
        ``np.isclose(…, rtol=1e-9, atol=1e-12)`` in v or in ω (:func:`_close`, the same test)."""
        return ~(_close(self.v, self.v_nominal) & _close(self.w, self.w_nominal))


#: :meth:`Certified.changed`'s tolerances (np.isclose's rtol and atol)
_CHANGED_RTOL, _CHANGED_ATOL = 1e-9, 1e-12


def _close(x: Any, y: Any) -> BoolArray:
    """``np.isclose(x, y, rtol=1e-9, atol=1e-12)`` for float64 arrays of one shape, without its argument handling
    (its own expression: ``|x − y| ≤ atol + rtol·|y|`` where y is finite, or ``x == y``); anything else goes to
    ``np.isclose`` itself."""
    if not (type(x) is np.ndarray and type(y) is np.ndarray and x.dtype == np.float64 and y.dtype == np.float64
            and x.shape == y.shape):
        return np.asarray(np.isclose(x, y, rtol=_CHANGED_RTOL, atol=_CHANGED_ATOL))
    with np.errstate(invalid="ignore"):
        return (np.less_equal(np.abs(x - y), _CHANGED_ATOL + _CHANGED_RTOL * np.abs(y)) & np.isfinite(y)) | (x == y)


def barrier_filter(robot: GritsBotParams, bounds: Bounds, dt: float,
                   **barrier: Any) -> UnicycleSafetyFilter:
    """swarmdeck's unicycle barrier filter for this robot and arena.

    ``barrier``: further :class:`~swarmdeck.safety.BarrierConfig` fields (``safety_distance``,
    ``gamma``, ``class_k``, ``max_speed``); their defaults are REFERENCE.md's, and the mode and
    work caps default to ``safety.config.pipeline_defaults()`` (anytime, bounded work per tick). ``robots``
    (int, not a config field): the robot count it will filter, when known (a small one needs no numba:
    ``safety.small_kernels``).
    """
    from swarmdeck.safety import BarrierConfig, UnicycleSafetyFilter  # devices -> safety (one way)
    from swarmdeck.safety.config import pipeline_defaults

    options = dict(barrier)
    robots = options.pop("robots", None)
    return UnicycleSafetyFilter(BarrierConfig(bounds=bounds, dt=dt, **{**pipeline_defaults(), **options}), robot,
                                robots=None if robots is None else int(robots))


def is_unicycle_filter(filt: object) -> bool:
    """True for swarmdeck's unicycle barrier (poses, v, w); other filters take points and SI velocities."""
    from swarmdeck.safety import UnicycleSafetyFilter

    return isinstance(filt, UnicycleSafetyFilter)


def certify(poses: ArrayLike, nominal: ArrayLike, robot: GritsBotParams, filt: SafetyFilterLike | None = None, *,
            seen: ArrayLike | None = None, obstacles: ArrayLike | None = None,
            robot_bounds: ArrayLike | None = None) -> Certified:
    """Nominal look-ahead velocities → the unicycle commands to send (see the module docstring).

    Args:
        poses: ``(N, 3)`` ``[x, y, θ]``, m/rad (rows of unseen robots may be NaN).
        nominal: ``(N, 2)`` single-integrator velocities of the look-ahead points, m/s.
        robot: the robot model (look-ahead ℓ, wheel radius, axle, wheel-speed limit).
        filt: None (no barrier), a unicycle filter ``filter(poses, v, w, obstacles) -> (v, w, diag)``
            or an SI filter ``filter(points, u[, obstacles]) -> (u, diag)``.
        seen: ``(N,)`` robots with a fresh pose (default: all).
        obstacles: ``(M, 2)`` further fixed points (e.g. robots excluded from control), m.
        robot_bounds: ``(N, 4)`` each robot's own wall rectangle ``[x_min, x_max, y_min, y_max]``, m (its
            region when several experiments share the floor, :mod:`swarmdeck.devices.fleet.regions`); None:
            the filter's bounds. Only swarmdeck's barrier filters take it.
    """
    poses = np.asarray(poses, dtype=float)
    nominal = np.asarray(nominal, dtype=float)
    n = len(poses)
    if poses.shape != (n, 3) or nominal.shape != (n, 2):
        raise ValueError(f"certify: poses {poses.shape} and nominal {nominal.shape} must be (N, 3) and (N, 2)")
    seen_mask = np.ones(n, dtype=bool) if seen is None else np.asarray(seen, dtype=bool).reshape(n)
    if robot_bounds is not None and np.shape(robot_bounds) != (n, 4):
        raise ValueError(f"certify: robot_bounds {np.shape(robot_bounds)} must be (N, 4) for {n} robots")
    invalid = ~np.all(np.isfinite(nominal), axis=1)
    all_seen = bool(seen_mask.all())
    zero = invalid if all_seen else invalid | ~seen_mask
    u = np.where(zero[:, None], 0.0, nominal) if zero.any() else nominal  # (nothing to zero: the nominal as it is)
    ell = robot.lookahead
    v0, w0, saturated = limit_unicycle(*si_to_unicycle(poses, u, ell), robot)
    if filt is None:
        v, w, ok, status, diag = v0, w0, True, "off", None
    else:
        v, w, ok, status, diag = _filter(filt, poses, v0, w0, seen_mask, obstacles, robot, robot_bounds)
    if not all_seen:
        v, w = np.where(seen_mask, v, 0.0), np.where(seen_mask, w, 0.0)
    safe = unicycle_to_si(poses if all_seen else np.where(seen_mask[:, None], poses, 0.0), v, w, ell)
    return Certified(v, w, safe, v0, w0, saturated, invalid, ok, status, diag)


def _filter(filt: SafetyFilterLike, poses: FloatArray, v: FloatArray, w: FloatArray, seen: BoolArray,
            obstacles: ArrayLike | None, robot: GritsBotParams, robot_bounds: ArrayLike | None = None
            ) -> tuple[FloatArray, FloatArray, bool, str, FilterDiagnostics | None]:
    """The barrier over the seen robots; unseen ones and ``obstacles`` are fixed points. Fail-stop."""
    walls: dict[str, Any] = {}
    if robot_bounds is not None:
        walls["robot_bounds"] = np.asarray(robot_bounds, dtype=float).reshape(-1, 4)[seen]
    n, ell = len(poses), robot.lookahead
    extra = None if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 2)
    extra = None if extra is None or len(extra) == 0 else extra
    idx = np.flatnonzero(seen)
    if len(idx) == 0:
        return np.zeros(n), np.zeros(n), True, "no robot seen", None
    if len(idx) < n:
        points = lookahead_points(poses, ell)
        known = ~seen & np.all(np.isfinite(points), axis=1)
        parts = [points[known]] + ([extra] if extra is not None else [])
        extra = np.concatenate(parts) if sum(len(p) for p in parts) else None
        poses, v, w = poses[idx], v[idx], w[idx]
    k = len(idx)
    if is_unicycle_filter(filt):
        vs, ws, diag = cast(Any, filt).filter(poses, v, w, extra, **walls)
        vs, ws = np.asarray(vs, dtype=float), np.asarray(ws, dtype=float)
    else:
        si = cast(CommandFilter, filt)
        u = unicycle_to_si(poses, v, w, ell)
        points = lookahead_points(poses, ell)
        safe_u, diag = (cast(Any, si).filter(points, u, extra, **walls) if walls else
                        si.filter(points, u) if extra is None else si.filter(points, u, extra))
        safe_u = np.asarray(safe_u, dtype=float)
        vs, ws = (np.zeros(0), np.zeros(0)) if safe_u.shape != (k, 2) else si_to_unicycle(poses, safe_u, ell)
        vs, ws, _ = limit_unicycle(vs, ws, robot)
    ok, status = bool(getattr(diag, "ok", True)), str(getattr(diag, "status", "ok"))
    if ok and not (vs.shape == (k,) and ws.shape == (k,) and np.all(np.isfinite(vs)) and np.all(np.isfinite(ws))):
        ok, status = False, f"filter returned the wrong shape or non-finite values for {k} robots"
    if not ok:
        return np.zeros(n), np.zeros(n), False, status, _remap(diag, idx, n)
    if k == n:
        return vs, ws, True, status, diag
    v_all, w_all = np.zeros(n), np.zeros(n)
    v_all[idx], w_all[idx] = vs, ws
    return v_all, w_all, True, status, _remap(diag, idx, n)


def _remap(diag: FilterDiagnostics | None, idx: NDArray[np.intp], n: int) -> FilterDiagnostics | None:
    """Diagnostics of the robots ``idx`` as diagnostics over all ``n``: intervention ``(n,)`` (zero
    for robots not filtered), active robot pairs in full indices (pairs with obstacles dropped)."""
    if len(idx) == n or not dataclasses.is_dataclass(diag) or not hasattr(diag, "active_pairs"):
        return diag
    inter = np.zeros(n)
    sub_inter = np.asarray(getattr(diag, "intervention", np.zeros(0)), dtype=float)
    if len(sub_inter) == len(idx):
        inter[idx] = sub_inter
    pairs = np.asarray(diag.active_pairs, dtype=np.int64).reshape(-1, 2)
    keep = np.all((pairs >= 0) & (pairs < len(idx)), axis=1)  # pairs among robots (not obstacles)
    return dataclasses.replace(diag, active_pairs=idx[pairs[keep]], active_h=np.asarray(diag.active_h)[keep],
                               intervention=inter)


def next_points(poses: ArrayLike, v: ArrayLike, w: ArrayLike, robot: GritsBotParams, dt: float) -> FloatArray:
    """``(N, 2)`` look-ahead points after one period ``dt`` (s) of ``(v, ω)``, m: the exact arc the simulator drives
    (:func:`~swarmdeck.core.kinematics.unicycle_step`; chord = v·dt·sinc(a/2) along the mean heading θ + a/2,
    a = ω·dt), then ℓ ahead along the new heading."""
    poses = np.asarray(poses, dtype=float)
    a = np.asarray(w, dtype=float) * dt
    half = poses[:, 2] + 0.5 * a
    chord = np.asarray(v, dtype=float) * dt * np.sinc(a / (2 * np.pi))
    end = poses[:, 2] + a
    return np.column_stack((poses[:, 0] + chord * np.cos(half) + robot.lookahead * np.cos(end),
                            poses[:, 1] + chord * np.sin(half) + robot.lookahead * np.sin(end)))


def _fixed_points(poses: FloatArray, seen: BoolArray, obstacles: ArrayLike | None, ell: float) -> FloatArray:
    """Points that do not move this tick: unseen robots' last look-ahead points and ``obstacles`` (M, 2), m."""
    if obstacles is None and seen.all():
        return np.zeros((0, 2))
    points = lookahead_points(poses[~seen], ell)
    parts = [points[np.all(np.isfinite(points), axis=1)]]
    if obstacles is not None:
        parts.append(np.asarray(obstacles, dtype=float).reshape(-1, 2))
    return np.concatenate(parts)


def brake(cert: Certified, poses: ArrayLike, robot: GritsBotParams, dt: float, distance: float, *,
          seen: ArrayLike | None = None, obstacles: ArrayLike | None = None) -> tuple[Certified, BoolArray]:
    """The guard's last resort: ``cert`` with every robot stopped that would bring a pair of look-ahead
    points closer than ``distance`` (m, and closer than they are) during the next ``dt`` (s)
    (:func:`swarmdeck.safety.guard.brake`); and the ``(N,)`` robots stopped."""
    poses = np.asarray(poses, dtype=float)
    n = len(poses)
    seen_mask = np.ones(n, dtype=bool) if seen is None else np.asarray(seen, dtype=bool).reshape(n)
    stopped = np.zeros(n, dtype=bool)
    idx = np.flatnonzero(seen_mask)
    if len(idx) == 0:
        return cert, stopped
    ell = robot.lookahead
    p0 = lookahead_points(poses[idx], ell)
    p1 = next_points(poses[idx], cert.v[idx], cert.w[idx], robot, dt)
    from swarmdeck.safety.guard import brake as guard_brake  # devices -> safety (one way)

    stopped[idx] = guard_brake(p0, p1, distance, _fixed_points(poses, seen_mask, obstacles, ell))
    if not stopped.any():
        return cert, stopped
    v, w = np.where(stopped, 0.0, cert.v), np.where(stopped, 0.0, cert.w)
    safe = unicycle_to_si(np.where(seen_mask[:, None], poses, 0.0), v, w, ell)
    return dataclasses.replace(cert, v=v, w=w, safe=safe), stopped


def certify_bypassed(poses: ArrayLike, nominal: ArrayLike, robot: GritsBotParams, hard: SafetyFilterLike,
                     monitor: SafetyFilterLike,
                     guard: GuardConfig, dt: float, *, seen: ArrayLike | None = None,
                     obstacles: ArrayLike | None = None, names: ArrayLike | None = None
                     ) -> tuple[Certified, Certified, GuardCheck, BoolArray]:
    """One tick of a bypassed barrier (module docstring): ``(commands to send, the full barrier's answer, the
    guard's verdict, (N,) robots the brake stopped)``. The commands are ``hard``'s (walls and obstacles only) unless
    the guard trips, then the full barrier's (``monitor``); the brake is applied to them.

    Without pair rows the QP falls apart into one small QP per robot, and a robot none of whose pair rows is active
    in the full barrier has the same optimum in both (its pair rows' multipliers are zero): ``hard`` is solved only
    for the robots of active pair rows (all seen robots when the full barrier needed its soft recovery form), the
    others keep the full barrier's answer.

    Args:
        hard: the filter without pair rows (``BarrierConfig(pairs=False)``); monitor: the full barrier.
        guard: guard distance and intervention threshold; dt: control period, s.
        names: ``(N,)`` robot ids the guard's reason names (default 0…N−1).
    """
    from swarmdeck.safety.guard import assess

    poses = np.asarray(poses, dtype=float)
    n = len(poses)
    seen_mask = np.ones(n, dtype=bool) if seen is None else np.asarray(seen, dtype=bool).reshape(n)
    full = certify(poses, nominal, robot, monitor, seen=seen_mask, obstacles=obstacles)
    ell = robot.lookahead
    fixed = _fixed_points(poses, seen_mask, obstacles, ell)
    kept = _without_pairs(full, poses, nominal, robot, hard, seen_mask, fixed) if full.ok else full
    idx = np.flatnonzero(seen_mask)
    p0 = lookahead_points(poses[idx], ell)
    p1 = next_points(poses[idx], kept.v[idx], kept.w[idx], robot, dt)
    extra = np.zeros(len(idx)) if kept is full else np.linalg.norm(full.safe[idx] - kept.safe[idx], axis=1)
    labels = np.arange(n) if names is None else np.asarray(names).reshape(n)
    verdict, stops = assess(guard, p0, p1, extra, fixed, full.ok, full.status, labels[idx])
    if verdict.trip:
        out, stopped = brake(full, poses, robot, dt, guard.guard_distance, seen=seen_mask, obstacles=obstacles)
        return out, full, verdict, stopped
    stopped = np.zeros(n, dtype=bool)
    stopped[idx] = stops
    if not stopped.any():
        return kept, full, verdict, stopped
    v, w = np.where(stopped, 0.0, kept.v), np.where(stopped, 0.0, kept.w)
    safe = unicycle_to_si(np.where(seen_mask[:, None], poses, 0.0), v, w, ell)
    return dataclasses.replace(kept, v=v, w=w, safe=safe), full, verdict, stopped


def _without_pairs(full: Certified, poses: FloatArray, nominal: ArrayLike, robot: GritsBotParams,
                   hard: SafetyFilterLike,
                   seen: BoolArray, fixed: FloatArray) -> Certified:
    """The walls-and-obstacles answer from the full barrier's (see :func:`certify_bypassed`): ``hard`` on the robots
    of active pair rows only, with ``fixed`` (the unseen robots and the obstacles, :func:`_fixed_points`) as its fixed
    points."""
    diag = full.diagnostics
    pairs = np.asarray(getattr(diag, "active_pairs", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2)
    if "soft" in str(getattr(diag, "status", "")):  # the soft recovery form is not the QP's optimum: all of them
        rows = np.flatnonzero(seen)
    else:
        rows = np.unique(pairs)
    if rows.size == 0:
        return full
    ell = robot.lookahead
    v, w = full.v.copy(), full.w.copy()
    free = _no_rows(hard, lookahead_points(poses[rows], ell), fixed)
    v[rows[free]], w[rows[free]] = full.v_nominal[rows[free]], full.w_nominal[rows[free]]  # nothing to change
    rows = rows[~free]
    if rows.size:
        sub = certify(poses[rows], np.asarray(nominal, dtype=float)[rows], robot, hard,
                      obstacles=fixed if len(fixed) else None)
        if not sub.ok:
            n = len(poses)
            zero = np.zeros(n)
            return dataclasses.replace(full, v=zero, w=zero, safe=np.zeros((n, 2)), ok=False, status=sub.status)
        v[rows], w[rows] = sub.v, sub.w
    safe = unicycle_to_si(np.where(seen[:, None], poses, 0.0), v, w, ell)
    return dataclasses.replace(full, v=v, w=w, safe=safe)


def _no_rows(filt: SafetyFilterLike, points: FloatArray, fixed: FloatArray) -> BoolArray:
    """``(K,)`` controlled points for which ``filt`` (a barrier without pair rows) builds no row but the wheel limits:
    farther from every wall than its wall radius and from every fixed point than its neighbour radius
    (``BarrierConfig.wall_radius``/``neighbour_radius``: beyond them no row can bind, so the filter is not built
    there). Their wheel-limited nominal is the filter's answer. All False for a filter without that configuration."""
    cfg = getattr(filt, "config", None)
    if cfg is None or not hasattr(cfg, "wall_radius"):
        return np.zeros(len(points), dtype=bool)
    x0, x1, y0, y1 = cfg.bounds
    m = cfg.margin
    x, y = points[:, 0], points[:, 1]
    clearance = np.minimum(np.minimum(x1 - m - x, x - x0 - m), np.minimum(y1 - m - y, y - y0 - m))
    free = clearance > cfg.wall_radius() - m
    obstacles = getattr(cfg, "obstacles", None)
    if obstacles is not None and obstacles.m and free.any():  # segment rows are built within the wall radius
        from swarmdeck.core.obstacles import segments_near

        free[segments_near(points, obstacles.segments, cfg.wall_radius())[0]] = False
    if len(fixed) and free.any():
        from scipy.spatial import cKDTree  # here, not at import (see devices.validation)

        reach = cfg.neighbour_radius()
        dist, _ = cKDTree(fixed).query(points, k=1, distance_upper_bound=reach)
        free &= dist > reach
    return free
