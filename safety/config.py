"""Configuration of the barrier certificates (REFERENCE.md §1, §3).

Everything is in metres, seconds and radians. The safety distance ``D_s`` is
applied to the *controlled points* handed to the filter (the look-ahead points
of the robots): the default 0.17 m is rps's ``0.12 + ℓ`` with ℓ = 0.05, and
also ``0.11 + 2·0.03``: two GRITSBots (Ø 0.11 m) whose look-ahead points
(ℓ = 0.03 m) are 0.17 m apart cannot touch.

Discrete-time note: the certificates are continuous-time conditions applied
once per control period ``dt``. With the cubic class-K function the closed loop
``x ← x + u·dt`` keeps ``h ≥ 0`` exactly as long as ``γ·dt·h² ≤ 1`` wherever a
row can bind (true for the defaults by a factor > 10); with the linear one it
needs ``γ·dt ≤ 1`` (e.g. γ ≤ 30 at dt = 0.033 s).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields
from functools import cached_property
from typing import TYPE_CHECKING, Any, Literal

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.config import floats, from_mapping
from swarmdeck.core.constants import CONTROL_PERIOD, MAX_LINEAR_SPEED, SAFETY_DISTANCE
from swarmdeck.core.obstacles import Obstacles

if TYPE_CHECKING:
    import numpy as np


def _real(owner: object, name: str, value: Any, lower: float | None = None, strict: bool = False,
          upper: float | None = None) -> None:
    """Refuse a setting that is not a finite real number in range (ValueError naming it)."""
    cls = type(owner).__name__
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{cls}: {name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{cls}: {name} must be finite, got {value!r}")
    if lower is not None and (value <= lower if strict else value < lower):
        raise ValueError(f"{cls}: {name} must be {'>' if strict else '>='} {lower:g}, got {value!r}")
    if upper is not None and value >= upper:  # type: ignore[operator]  # numbers.Real declares no operators
        raise ValueError(f"{cls}: {name} must be < {upper:g}, got {value!r}")


def pipeline_defaults() -> dict[str, object]:
    """The barrier settings the pipelines default to (``Arena``, ``swarmdeck run``, the console,
    verification and the learning environments, through ``devices.pipeline.barrier_filter``):
    ``mode="auto"`` (distributed above ``distributed_above`` robots, anytime at or below) with a
    bounded amount of work per call — at most 12 factorisations per active-set stage, the warm
    paths at most a tenth of clarabel's last cold iteration count (``warm_share``), then clarabel cold, and 120
    in all, then the distributed floor (bench/RESULTS.md, "barrier: anytime").
    A fresh dict; a ``BarrierConfig()`` built directly keeps ``mode="centralised"`` and no caps."""
    return {"mode": "auto", "work_budget": 120, "active_set_max_solves": 12, "warm_share": 0.1}


@dataclass(frozen=True)
class BarrierConfig:
    """Parameters of the single-integrator barrier QP (REFERENCE.md §3).

    safety_distance: D_s in m between controlled points (rps classic: 0.17).
    gamma: barrier gain γ (rps: 100).
    class_k: ``"cubic"`` κ(h) = h³ (rps) or ``"linear"`` κ(h) = h (paper).
    max_speed: bound on the *solution's* speed ‖u_i‖ ≤ v_max in m/s (0.2).
    bounds: arena rectangle (x_min, x_max, y_min, y_max) in m.
    wall_margin: distance the controlled point keeps from each wall, m; None → D_s/2 (rps).
    wall_gain: wall rows use ``wall_gain·γ·κ(δ)`` with δ the clearance beyond the margin (rps 0.4).
    dt: control period in s; widens the neighbour radius by 2·v_max·dt so the
        candidate set also covers the next tick (REFERENCE.md §1: 0.033).
    recovery: robots already inside the unsafe set (h < 0) get separating
        commands: a row with h < 0 keeps its plain barrier bound (with the cubic κ it
        already demands separation, and the answer is the Robotarium's), except that
        *deep* overlaps — pairs/obstacles closer than D_s − recovery_depth, points more
        than recovery_depth beyond the wall margin — demand exactly ``recovery_speed``
        (and no row demands more). If those rows are jointly infeasible, hard "no further
        approach" rows plus soft separation targets are used. False keeps the plain
        rows, which can be infeasible.
    recovery_speed: separation speed (m/s) demanded along each deep overlap's row.
    recovery_depth: overlap (m) beyond which a row is deep; 0.03 puts the line at 0.14 m
        for D_s = 0.17, just beyond the rps validator's 0.135 m collision distance.
    recovery_weight: penalty weight of the soft separation rows relative to ‖u − û‖².
    solver: ``"auto"`` (pass-through check, active set certified by KKT, clarabel
        fallback) or ``"clarabel"`` (always the interior-point solver).
    max_active_set_iterations: active-set iterations before falling back to clarabel.
    active_set_max_rows: "auto" uses the active set only when the starting working set
        (last tick's active rows, or the rows û violates) has at most this many rows;
        larger, degenerate working sets go to clarabel directly (measured faster).
    warm_max_rows: in closed loop (the same filter, N and obstacle count as the previous
        tick) the active set starts from the previous tick's active rows when they are at
        most this many, whatever ``active_set_max_rows`` says: N = 100 (≈ 150 rows) is then
        ≈ 2× faster than clarabel; from ≈ 500 rows (N = 200) the warm start needs 4–15
        iterations and clarabel is faster (bench/RESULTS.md, "safety: closed loop").
    warm_slack: in closed loop beyond ``warm_max_rows`` active rows, clarabel solves only the rows
        that were within this many m/s of their bound at the previous tick's answer (plus those
        the nominal violates), and the certified active set finishes on all rows (KKT checked; any
        failure solves everything cold). 0.01 m/s keeps ≈ 1/3 of the rows at N = 1000.
    warm_dual_sweeps: in closed loop, at most this many sweeps of the compiled dual coordinate
        ascent (:mod:`safety.dual_ascent`) started from the previous tick's multipliers predict the
        active rows, and the certified active set starts from them (≤ ``warm_dual_iterations``
        iterations); if it does not certify, the paths above run. 0 turns the prediction off (it is
        off anyway when numba cannot be imported).
    warm_dual_iterations: active-set iterations allowed after the dual-ascent prediction.
    cold_dual: on a cold call (no warm start, or one that cannot serve), when the active set from
        the rows û violates does not apply or certify, the same prediction from zero multipliers
        and the certified active set run before clarabel (random scenes: every call certified, the
        same bits as clarabel + polish, ≈ 1/4 of the time at N = 100–1000; bench/RESULTS.md "barrier:
        anytime"). Within ``active_set_max_solves``; False goes to clarabel at once as before.
    clarabel_max_iter, clarabel_tol: clarabel's max_iter and tol_gap_abs/rel/tol_feas.
    mode: ``"centralised"`` (one QP over all robots), ``"distributed"`` (every robot
        solves its own QP on half of each pair row, REFERENCE.md §12,
        :mod:`safety.distributed`), ``"anytime"`` (the centralised optimum within
        ``work_budget``/``time_budget_s``; when the budget runs out the distributed answer on
        the same rows, which is certified and cheap, is returned instead — ``diag.answer`` says
        which) or ``"auto"`` (distributed above ``distributed_above`` robots, anytime at or below;
        with both budgets None that is exactly the centralised filter there).
    distributed_above: robot count above which "auto" filters distributed (from
        ``bench/bench_safety.py``: where the centralised filter stops holding a 33 ms tick).
    work_budget: anytime/auto: factorisations one call may spend on the centralised QP (each
        active-set iteration or disc Newton step is one Gram factorisation, each clarabel
        iteration one KKT factorisation); None is unlimited. Deterministic (a count, never time).
    time_budget_s: anytime/auto: wall-time budget of the centralised part of one call, s (for the
        live console; None is unlimited). Depends on the machine's load: tests use ``work_budget``.
    active_set_max_solves: every mode: factorisations each active-set stage of one call may spend —
        the closed-loop warm paths together (dual prediction, warm active set, pruned clarabel's
        polish), and clarabel's polish (at most 4 of them); beyond it the warm paths go straight to
        clarabel cold and the polish keeps clarabel's answer (the active set's inner Lawson–Hanson steps have no other
        bound on their work). None is unlimited.
    warm_share: with ``active_set_max_solves`` set, once last tick held more than 200 active
        rows (below that the Gram matrices are small and dense, and cheap), the warm paths of
        one call may also spend at most this fraction of the iterations (KKT factorisations) clarabel
        cold took the last time this filter ran it (at least 1), so a tick whose warm paths fail costs
        about (1 + share·c) clarabel solves plus the polish, c the cost of a Gram factorisation over a
        clarabel iteration (≈ 0.6 at N = 1000, ≈ 2 at N = 200 where the Gram matrices are larger
        than clarabel's per-iteration work). Clarabel's polish likewise, once its answer holds more than
        200 rows near their bound: at most this fraction of that cold solve's iterations (≥ 1; ≤ 4 as
        before). The warm paths and clarabel's polish, when they spent
        their cap and failed, are skipped on the next 1, 3, 7, … 31 calls (doubling per consecutive
        failure, reset by a success). Deterministic: counts, never time. None: only ``active_set_max_solves``
        (and the warm stage skipped on the one call after a capped failure).
    distributed_second_pass: the distributed filter solves a second pass in which each pair row's
        margin unused by one robot goes to the other (:func:`safety.distributed.reallocate_halves`;
        certified as the first, never more invasive for any robot, ≈ 2× the distributed cost).
    distributed_consensus_passes: (from Python or ``from_dict``) after the second pass, this many consensus passes: each pair row's
        remaining slack at the last answer is shared equally between its two robots, and the robots given
        more margin solve again (:func:`safety.distributed.consensus_shares`; certified as the first pass, no
        robot's intervention grows; each pass costs about one more distributed solve). bench/RESULTS.md
        ("distributed barrier", "Compiled, consensus passes") has cost/optimum and time per pass count.
    pairs: False builds no pair rows: the filter keeps the walls and the fixed obstacles
        (e.g. docked robots) only — the hard layer of a bypassed run (:mod:`safety.guard`).
    obstacles: line-segment obstacles on the floor (:class:`~swarmdeck.core.obstacles.Obstacles`, or
        anything ``Obstacles.of`` reads), or None. Each controlled point keeps the wall margin from every
        segment (segment rows, :func:`safety.constraints.segment_rows`). None (the default) builds
        exactly the rows it always did.
    """

    safety_distance: float = SAFETY_DISTANCE
    gamma: float = 100.0
    class_k: Literal["cubic", "linear"] = "cubic"
    max_speed: float = MAX_LINEAR_SPEED
    bounds: Bounds = DEFAULT_BOUNDS
    wall_margin: float | None = None
    wall_gain: float = 0.4
    dt: float = CONTROL_PERIOD
    recovery: bool = True
    recovery_speed: float = 0.05
    recovery_depth: float = 0.03
    recovery_weight: float = 1e4
    solver: Literal["auto", "clarabel"] = "auto"
    max_active_set_iterations: int = 15
    active_set_max_rows: int = 100
    warm_max_rows: int = 300
    warm_slack: float = 0.01
    warm_dual_sweeps: int = 200
    warm_dual_iterations: int = 4
    cold_dual: bool = True
    clarabel_max_iter: int = 100
    clarabel_tol: float = 1e-9
    mode: Literal["centralised", "distributed", "anytime", "auto"] = "centralised"
    distributed_above: int = 200
    work_budget: int | None = None
    time_budget_s: float | None = None
    active_set_max_solves: int | None = None
    warm_share: float | None = None
    distributed_second_pass: bool = True
    distributed_consensus_passes: int = 0
    sensing_radius: float | None = None
    pairs: bool = True
    obstacles: Obstacles | None = None

    def __post_init__(self) -> None:
        if self.obstacles is not None:
            try:
                object.__setattr__(self, "obstacles", Obstacles.of(self.obstacles) or None)
            except ValueError as exc:
                raise ValueError(f"BarrierConfig: {exc}") from None
        # every gain, distance and speed finite and in range: TOML can say inf and nan, and an
        # infinite gain turns a row bound into inf·0 = NaN, which a QP silently drops
        positive = ("safety_distance", "gamma", "max_speed", "wall_gain", "recovery_weight")
        for name in positive:
            _real(self, name, getattr(self, name), lower=0.0, strict=True)
        for name in ("dt", "recovery_speed", "recovery_depth", "warm_slack"):
            _real(self, name, getattr(self, name), lower=0.0, strict=False)
        if self.wall_margin is not None:
            _real(self, "wall_margin", self.wall_margin, lower=0.0, strict=False)
        if self.sensing_radius is not None:
            _real(self, "sensing_radius", self.sensing_radius, lower=0.0, strict=True)
        if self.warm_share is not None:
            _real(self, "warm_share", self.warm_share, lower=0.0, strict=True)
        if self.time_budget_s is not None:
            _real(self, "time_budget_s", self.time_budget_s, lower=0.0, strict=True)
        for name in ("work_budget", "active_set_max_solves"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Integral)
                                      or value < 1):
                raise ValueError(f"BarrierConfig: {name} must be an integer >= 1 or None (unlimited), "
                                 f"got {value!r}")
        _real(self, "clarabel_tol", self.clarabel_tol, lower=0.0, strict=True, upper=1e-3)
        for name, lower in (("max_active_set_iterations", 1), ("active_set_max_rows", 0), ("warm_max_rows", 0),
                            ("warm_dual_sweeps", 0), ("warm_dual_iterations", 1), ("clarabel_max_iter", 1),
                            ("distributed_above", 0), ("distributed_consensus_passes", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < lower:
                raise ValueError(f"BarrierConfig: {name} must be an integer >= {lower}, got {value!r}")
        for name in ("recovery", "pairs", "distributed_second_pass", "cold_dual"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"BarrierConfig: {name} must be true or false, got {getattr(self, name)!r}")
        checks = [
            (self.class_k in ("cubic", "linear"), "class_k must be 'cubic' or 'linear'"),
            (self.solver in ("auto", "clarabel"), "solver must be 'auto' or 'clarabel'"),
            (isinstance(self.bounds, (tuple, list)) and len(self.bounds) == 4,
             "bounds must be (x_min, x_max, y_min, y_max)"),
            (self.mode in ("centralised", "distributed", "anytime", "auto"),
             "mode must be 'centralised', 'distributed', 'anytime' or 'auto'"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(f"BarrierConfig: {message}")
        for v in self.bounds:
            _real(self, "bounds", v)
        if self.recovery_depth >= self.safety_distance:
            raise ValueError("BarrierConfig: recovery_depth must be < safety_distance")
        b = Bounds(*(float(v) for v in self.bounds))
        m = self.margin
        if m < 0 or b.width <= 2 * m or b.height <= 2 * m:
            raise ValueError(
                f"BarrierConfig: bounds {self.bounds} leave no room inside the wall margin {m} m"
            )
        if self.sensing_radius is not None and self.mode != "centralised":
            need = self.pair_bind_distance()
            if not self.sensing_radius >= need:
                raise ValueError(
                    f"BarrierConfig: sensing_radius {self.sensing_radius} m is too small for the "
                    f"distributed filter: at max_speed {self.max_speed} m/s with gamma {self.gamma} "
                    f"({self.class_k} κ) a pair row can bind up to {need:.3f} m apart, and a robot "
                    f"that cannot see such a neighbour cannot hold its half of the row"
                )

    def distributed_for(self, n: int) -> bool:
        """Whether N robots are filtered by the distributed filter under this config's ``mode``."""
        return self.mode == "distributed" or (self.mode == "auto" and n > self.distributed_above)

    def anytime_for(self, n: int) -> bool:
        """Whether N robots are filtered in anytime mode (centralised within the budget, distributed floor)."""
        return self.mode == "anytime" or (self.mode == "auto" and n <= self.distributed_above)

    @classmethod
    def from_dict(cls, data: dict) -> BarrierConfig:
        """Build from a plain mapping (e.g. a TOML ``[safety]`` table); unknown keys are refused."""
        return from_mapping(cls, data, "BarrierConfig", error=ValueError, convert={"bounds": floats},
                            template="{what}: unknown setting(s) {unknown}; known: {known}")

    def to_dict(self) -> dict:
        """Plain dict of the settings (JSON/TOML-able)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["bounds"] = list(self.bounds)
        if self.obstacles is None:
            del out["obstacles"]  # the table reads as it always did
        else:
            out["obstacles"] = self.obstacles.to_list()
        return out

    @property
    def margin(self) -> float:
        """Wall margin in m (``wall_margin`` or D_s/2)."""
        return self.safety_distance / 2 if self.wall_margin is None else float(self.wall_margin)

    def deep_overlap(self, h: np.ndarray, kind_is_wall: np.ndarray) -> np.ndarray:
        """(m,) bool: rows whose h (pairs/obstacles m², walls and segments m: ``kind_is_wall``) is a deep
        overlap (see ``recovery_depth``)."""
        d = self.safety_distance - self.recovery_depth
        return (h < 0) & (((h < -self.recovery_depth) & kind_is_wall)
                          | ((h < d * d - self.safety_distance**2) & ~kind_is_wall))

    def kappa(self, h: Any) -> Any:
        """Class-K function κ(h) (elementwise, keeps the sign of h)."""
        return h * h * h if self.class_k == "cubic" else h

    def pair_bind_distance(self) -> float:
        """Largest distance d at which a pair row can bind with ‖u‖ ≤ v_max.

        The row −2eᵀ(u_i − u_j) ≤ γκ(d² − D_s²) has a left side of at most
        4·d·v_max, so it binds only where γκ(d² − D_s²) ≤ 4·d·v_max. Solved by
        bisection (the gap is increasing in d for d > D_s).
        """
        d_lo, d_hi = self.safety_distance, self.safety_distance + 1.0

        def gap(d: float) -> float:
            return self.gamma * self.kappa(d * d - self.safety_distance**2) - 4 * d * self.max_speed

        while gap(d_hi) < 0:
            d_hi *= 2
        for _ in range(80):
            mid = 0.5 * (d_lo + d_hi)
            if gap(mid) < 0:
                d_lo = mid
            else:
                d_hi = mid
        return d_hi

    @cached_property
    def _radii(self) -> tuple[float, float]:
        # computed once per config (the bisection is not free at 30 Hz)
        wall = self.margin + self.wall_bind_clearance() + self.max_speed * self.dt
        pair = self.pair_bind_distance() + 2 * self.max_speed * self.dt
        if self.sensing_radius is not None and self.mode != "centralised":
            pair = float(self.sensing_radius)  # rows for exactly the neighbours a robot senses
        return pair, wall

    def neighbour_radius(self) -> float:
        """k-d tree radius (m): binding distance plus 2·v_max·dt for the next tick."""
        return self._radii[0]

    def wall_bind_clearance(self) -> float:
        """Clearance δ beyond the margin where a wall row can bind: wall_gain·γ·κ(δ) = v_max."""
        c = self.max_speed / (self.wall_gain * self.gamma)
        return c ** (1.0 / 3.0) if self.class_k == "cubic" else c

    def wall_radius(self) -> float:
        """Distance from a wall (m) within which its row is built."""
        return self._radii[1]
