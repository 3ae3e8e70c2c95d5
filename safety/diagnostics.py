"""Per-tick diagnostics of the safety filter (cheap: computed from arrays the filter already has)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def _num(x: float) -> float | None:
    """JSON-safe float: inf/nan → None."""
    x = float(x)
    return x if math.isfinite(x) else None


@dataclass(frozen=True)
class BarrierDiagnostics:
    """What the filter did on one call.

    ok: False when the robots were stopped (fail-stop); status: why, in words
    ("nominal safe", "optimal", "optimal (recovering …)", "failed: infeasible", …).
    solve_time_s: wall time of the whole call, s. n_constraints: rows built
    (pairs, walls, obstacles, limits; speed discs not counted). n_active: rows
    at equality in the answer (plus robots on their speed bound).
    active_pairs (K, 2) int robot pairs i < j with an active pair row, active_h
    (K,) their h = ‖x_i − x_j‖² − D_s² in m². min_distance: smallest distance
    between controlled points, m (inf for N < 2). min_wall_clearance: smallest
    distance of a controlled point to the arena boundary, m (negative outside).
    intervention (N,): ‖u*_i − û_i‖ in m/s. nominal_was_safe: û satisfied every
    row, so u* = û exactly.
    method: "pass-through", "active-set", "warm active-set" (from the previous tick's active
    rows), "clarabel", "clarabel+active-set" (polished), "mixed" or "fail-stop".
    iterations: active-set iterations (+ clarabel's). n_clusters: connected
    components of the candidate-row graph, computed only when some robots are
    inside the unsafe set (their clusters are solved apart); 0 otherwise. n_unsafe: rows with h < 0 (robots
    already inside the unsafe set). min_obstacle_distance: m (inf without obstacles).
    answer: which answer this is — "optimum" (the centralised QP's certified optimum, or the
    nominal when it is safe), "floor" (anytime mode: the budget ran out first, so the distributed
    answer on the same rows; certified, more invasive), "distributed" (distributed mode), "stopped"
    (fail-stop). gap: how far the answer's cost ½Σ‖u − û‖² (m²/s²) is above the centralised
    optimum's when known (0.0 for the optimum), None when unknown. work: factorisations spent on
    the centralised QP (active-set Gram solves + clarabel iterations), the unit of ``work_budget``.
    """

    ok: bool
    status: str
    solve_time_s: float
    n_constraints: int
    n_active: int
    active_pairs: np.ndarray
    active_h: np.ndarray
    min_distance: float
    min_wall_clearance: float
    intervention: np.ndarray
    nominal_was_safe: bool
    method: str = ""
    iterations: int = 0
    n_clusters: int = 0
    n_unsafe: int = 0
    min_obstacle_distance: float = field(default=math.inf)
    answer: str = ""
    gap: float | None = None
    work: int = 0

    def to_dict(self) -> dict:
        """JSON-able dict (lists for arrays, None for infinities)."""
        return {
            "ok": bool(self.ok),
            "status": self.status,
            "solve_time_s": float(self.solve_time_s),
            "n_constraints": int(self.n_constraints),
            "n_active": int(self.n_active),
            "active_pairs": np.asarray(self.active_pairs, dtype=int).tolist(),
            "active_h": [float(v) for v in np.asarray(self.active_h, dtype=float)],
            "min_distance": _num(self.min_distance),
            "min_wall_clearance": _num(self.min_wall_clearance),
            "intervention": [float(v) for v in np.asarray(self.intervention, dtype=float)],
            "nominal_was_safe": bool(self.nominal_was_safe),
            "method": self.method,
            "iterations": int(self.iterations),
            "n_clusters": int(self.n_clusters),
            "n_unsafe": int(self.n_unsafe),
            "min_obstacle_distance": _num(self.min_obstacle_distance),
            "answer": self.answer,
            "gap": None if self.gap is None else _num(self.gap),
            "work": int(self.work),
        }
