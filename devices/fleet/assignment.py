"""Which robots take part: N charged, healthy robots mapped to the experiment's ids 0…N−1.

Paper §III-A/§III-C: the back end assigns charged robots to a user's experiment; the others stay
on their chargers (and remain fixed obstacles for the safety filter). A robot is *eligible* when

* its state of charge is known (not NaN) and at least ``min_charge``,
* tracking saw it within ``max_pose_age`` s, and
* its firmware answered (a status report) within ``max_status_age`` s.

Of the eligible robots, :func:`assign` picks N and decides which one plays experiment robot k:
with start poses it minimises the total straight-line distance from the robots to their start
positions (a rectangular linear assignment, :func:`scipy.optimize.linear_sum_assignment`; the
optimal matching of a Euclidean cost has no crossing paths, which keeps setup free of head-on
meetings); without start poses it takes the N best charged (ties by id).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import require_in_range, require_positive
from swarmdeck.core.errors import SwarmdeckError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


class AssignmentError(ValueError, SwarmdeckError):
    """Not enough eligible robots; the message names every robot left out and why."""


@dataclass(frozen=True)
class AssignmentPolicy:
    """When a robot may take part in an experiment.

    Attributes:
        min_charge: least state of charge ∈ [0, 1] (0.5: half the capacity, ≈ 2 h of driving).
        max_pose_age: tracking must have seen the robot within this many s.
        max_status_age: the firmware must have reported within this many s (GRITSBot X reports
            once a second, REFERENCE.md §9 / notes/robotarium.md §4.3).
    """

    min_charge: float = 0.5
    max_pose_age: float = 1.0
    max_status_age: float = 3.0

    def __post_init__(self) -> None:
        require_in_range(self.min_charge, "AssignmentPolicy.min_charge", 0.0, 1.0)
        require_positive(self, ("max_pose_age", "max_status_age"), "s")


@dataclass(frozen=True)
class Assignment:
    """The outcome of :func:`assign` over a fleet of M robots.

    Attributes:
        rows: ``(N,)`` fleet rows; ``rows[k]`` plays experiment robot k.
        ids: ``(N,)`` their robot ids (``fleet_ids[rows]``).
        idle: ``(M − N,)`` fleet rows that stay where they are (docked), ascending.
    """

    rows: IntArray
    ids: IntArray
    idle: IntArray

    @property
    def n(self) -> int:
        return int(len(self.rows))


def eligibility(charge: ArrayLike, pose_age: ArrayLike, status_age: ArrayLike,
                policy: AssignmentPolicy = AssignmentPolicy()) -> tuple[NDArray[np.bool_], list[str]]:
    """``(M,)`` eligible mask and, per robot, the reason it is not eligible ("" when it is).

    All inputs ``(M,)``: charge ∈ [0, 1] (NaN: unknown), ages in s (inf: never).
    """
    q = np.asarray(charge, dtype=float).reshape(-1)
    pa = np.broadcast_to(np.asarray(pose_age, dtype=float), q.shape)
    sa = np.broadcast_to(np.asarray(status_age, dtype=float), q.shape)
    nan = np.isnan(q)
    low = ~nan & (q < policy.min_charge)
    lost = ~(pa <= policy.max_pose_age)  # NaN ages count as lost
    silent = ~(sa <= policy.max_status_age)
    ok = ~(nan | low | lost | silent)
    reasons = np.full(q.shape, "", dtype=object)
    # one pass over the robots that are out, to write the words (not a per-tick path)
    for k in np.flatnonzero(~ok):
        why = []
        if nan[k]:
            why.append("battery reads NaN")
        if low[k]:
            why.append(f"battery {q[k]:.0%} < {policy.min_charge:.0%}")
        if lost[k]:
            why.append(f"not tracked for {pa[k]:.1f} s")
        if silent[k]:
            why.append(f"firmware silent for {sa[k]:.1f} s")
        reasons[k] = ", ".join(why)
    return ok, [str(r) for r in reasons]


def assign(n: int, ids: ArrayLike, charge: ArrayLike, pose_age: ArrayLike, status_age: ArrayLike, *,
           positions: ArrayLike | None = None, goals: ArrayLike | None = None,
           policy: AssignmentPolicy = AssignmentPolicy()) -> Assignment:
    """Pick ``n`` eligible robots of a fleet of M and map them to experiment ids 0…n−1.

    Args:
        n: robots the experiment needs.
        ids: ``(M,)`` robot ids of the fleet.
        charge, pose_age, status_age: ``(M,)`` as in :func:`eligibility`.
        positions: ``(M, 2)`` current robot positions, m (needed with ``goals``).
        goals: ``(n, 2)`` or ``(n, 3)`` start poses; robot k is the one closest overall (module docstring).
        policy: eligibility thresholds.

    Raises:
        AssignmentError: fewer than ``n`` eligible robots; names each robot left out and why.
        ValueError: bad shapes or ``n`` < 1.
    """
    ids = np.asarray(ids).reshape(-1)
    m = len(ids)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"the experiment must need at least one robot, got {n!r}")
    ok, reasons = eligibility(charge, pose_age, status_age, policy)
    if len(ok) != m:
        raise ValueError(f"charge has {len(ok)} entries for a fleet of {m} robots")
    cand = np.flatnonzero(ok)
    if len(cand) < n:
        out = "; ".join(f"robot {int(ids[k])}: {reasons[k]}" for k in np.flatnonzero(~ok))
        raise AssignmentError(f"the experiment needs {n} robots but only {len(cand)} of the fleet's {m} are charged "
                              f"(>= {policy.min_charge:.0%}) and healthy" + (f" ({out})" if out else ""))
    if goals is None:
        q = np.asarray(charge, dtype=float).reshape(-1)
        order = cand[np.lexsort((ids[cand], -q[cand]))][:n]
        rows = np.sort(order)
    else:
        from scipy.optimize import linear_sum_assignment

        g = np.asarray(goals, dtype=float)
        if g.ndim != 2 or g.shape[0] != n or g.shape[1] not in (2, 3):
            raise ValueError(f"goals must have shape ({n}, 2) or ({n}, 3), got {g.shape}")
        if positions is None:
            raise ValueError("assign: goals need the robots' positions")
        p = np.asarray(positions, dtype=float)
        if p.shape[0] != m or p.ndim != 2 or p.shape[1] < 2:
            raise ValueError(f"positions must have shape ({m}, 2), got {p.shape}")
        diff = p[cand, None, :2] - g[None, :, :2]
        cost = np.hypot(diff[..., 0], diff[..., 1])  # (candidates, n)
        r, c = linear_sum_assignment(cost)
        rows = np.empty(n, dtype=np.intp)
        rows[c] = cand[r]
    rows = rows.astype(np.intp)
    idle = np.setdiff1d(np.arange(m), rows).astype(np.intp)
    return Assignment(rows, ids[rows].astype(np.intp), idle)
