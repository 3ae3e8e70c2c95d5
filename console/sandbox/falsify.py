"""The falsifier's search: the cross-entropy method over the set-up errors and tracking offsets of one run.

Verification's raw runs draw their set-up error at random (:func:`~swarmdeck.console.sandbox.start_poses.perturb`);
the falsifier instead *searches* that error — and a constant tracking offset on top of the configured
tracking noise — for the run that comes closest to a contact (REFERENCE.md §17: searched runs are not
independent random runs and never enter the Clopper–Pearson bound).

A candidate is a point ``z`` of the box [−1, 1]^D, D = 6 N (robot-major: per robot the set-up error dx, dy,
dθ, then the tracking offset bx, by, bθ). :meth:`SearchSpace.decode` maps it into the tolerance: the
position error ``position`` · (zx, zy), scaled back onto the disc of radius ``position`` (2 cm) when outside
it; the heading error ``heading`` · zθ (±5°); the tracking offset ``offset_sigmas`` standard deviations of the
configured tracking noise · (zbx, zby, zbθ).

:func:`cross_entropy` minimises a batch objective over the box (the minimum clearance of each candidate's
run, m) with a budget of evaluations; :func:`uniform_search` spends the same budget on uniform candidates
(the baseline of the tests and bench/falsify_bench.py). Both are pure functions of their seed.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.checks import in_range
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION

#: the dimensions of one robot in a candidate: set-up error dx, dy, dθ and tracking offset bx, by, bθ
PER_ROBOT = 6
#: a constant tracking offset of at most this many standard deviations of the configured tracking noise
OFFSET_SIGMAS = 2.0
#: the cross-entropy method's settings: candidates per generation (at most), elite fraction, initial standard
#: deviation in box units, smoothing of the mean and deviation, the deviation's floor
POPULATION = 10
ELITE_FRACTION = 0.3
INITIAL_STD = 1.5
SMOOTHING = 0.9
MIN_STD = 0.1

#: a batch objective: candidates ``(P, D)`` in the box → their values ``(P,)`` (lower: closer to a contact)
Objective = Callable[[NDArray[np.float64]], NDArray[np.float64]]


@dataclass(frozen=True)
class Probe:
    """What one searched run changes: the set-up error added to each start pose and a constant tracking offset.

    Attributes:
        setup: ``(N, 3)`` [dx, dy, dθ] (m, m, rad) added to the start poses (within the fleet's tolerance).
        offset: ``(N, 3)`` [bx, by, bθ] (m, m, rad) added to every tracked pose (besides the random noise).
    """

    setup: tuple[tuple[float, float, float], ...]
    offset: tuple[tuple[float, float, float], ...]

    def to_dict(self) -> dict[str, list[list[float]]]:
        return {"setup": [[round(v, 9) for v in row] for row in self.setup],
                "offset": [[round(v, 9) for v in row] for row in self.offset]}


def _rows(a: NDArray[np.float64]) -> tuple[tuple[float, float, float], ...]:
    return tuple((float(x), float(y), float(t)) for x, y, t in a)


@dataclass(frozen=True)
class SearchSpace:
    """The tolerance the falsifier searches, for ``n_robots`` robots.

    Attributes:
        n_robots: robots of the run.
        position: radius of the set-up position error, m (the fleet's 2 cm).
        heading: largest set-up heading error, rad (5°).
        offset_xy: largest constant tracking offset in x and y, m (``OFFSET_SIGMAS`` × the noise's σ).
        offset_theta: largest constant tracking offset in θ, rad.
    """

    n_robots: int
    position: float = ACCEPT_POSITION
    heading: float = ACCEPT_HEADING
    offset_xy: float = 0.0
    offset_theta: float = 0.0

    def __post_init__(self) -> None:
        if not in_range(self.n_robots, 1, integer=True):
            raise ValueError(f"n_robots must be a positive integer, got {self.n_robots!r}")
        for name in ("position", "heading", "offset_xy", "offset_theta"):
            if not in_range(getattr(self, name), 0.0):
                raise ValueError(f"{name} must be a finite number >= 0, got {getattr(self, name)!r}")

    @classmethod
    def within_noise(cls, n_robots: int, pose_noise_xy: float, pose_noise_theta: float) -> SearchSpace:
        """The fleet's set-up tolerance and offsets of up to :data:`OFFSET_SIGMAS` σ of the tracking noise."""
        return cls(n_robots, offset_xy=OFFSET_SIGMAS * float(pose_noise_xy),
                   offset_theta=OFFSET_SIGMAS * float(pose_noise_theta))

    @property
    def dim(self) -> int:
        """D = 6 N."""
        return PER_ROBOT * self.n_robots

    def decode(self, z: NDArray[np.float64]) -> Probe:
        """The probe of candidate ``z`` ``(D,)`` (values outside [−1, 1] are clipped)."""
        z = np.clip(np.asarray(z, dtype=float).reshape(self.n_robots, PER_ROBOT), -1.0, 1.0)
        xy = self.position * z[:, :2]
        norm = np.hypot(xy[:, 0], xy[:, 1])
        xy = xy * np.minimum(1.0, self.position / np.maximum(norm, 1e-300))[:, None]
        setup = np.column_stack((xy, self.heading * z[:, 2]))
        offset = z[:, 3:] * np.array([self.offset_xy, self.offset_xy, self.offset_theta])
        return Probe(_rows(setup), _rows(offset))


@dataclass(frozen=True)
class SearchResult:
    """What a search found: every candidate it evaluated, in order, and their values.

    Attributes:
        candidates: ``(E, D)`` in the box, E ≤ the budget.
        values: ``(E,)`` the objective of each (m of clearance: 0 is a contact).
        generations: how many batches were evaluated.
    """

    candidates: NDArray[np.float64]
    values: NDArray[np.float64]
    generations: int

    @property
    def best(self) -> int:
        """Index of the lowest value (the first of equals)."""
        return int(np.argmin(self.values))

    def first_at_most(self, target: float) -> int | None:
        """How many evaluations it took to reach ``target`` or below (None: never)."""
        hits = np.flatnonzero(self.values <= target)
        return int(hits[0]) + 1 if len(hits) else None


def _check(dim: int, budget: int) -> None:
    if not in_range(dim, 1, integer=True):
        raise ValueError(f"the search needs at least one dimension, got {dim!r}")
    if not in_range(budget, 1, integer=True):
        raise ValueError(f"the falsification budget must be a positive integer number of runs, got {budget!r}")


def _values(objective: Objective, batch: NDArray[np.float64]) -> NDArray[np.float64]:
    values = np.asarray(objective(batch.copy()), dtype=float).reshape(-1)
    if len(values) != len(batch):
        raise ValueError(f"the objective gave {len(values)} values for {len(batch)} candidates")
    return np.where(np.isfinite(values), values, np.inf)  # a run that measured nothing is never the worst case


def cross_entropy(objective: Objective, dim: int, budget: int, seed: int, *, stop_at: float = 0.0,
                  population: int = POPULATION) -> SearchResult:
    """Minimise ``objective`` over [−1, 1]^``dim`` with at most ``budget`` evaluations (the cross-entropy method).

    Each generation draws ``population`` candidates from a Gaussian (clipped to the box), evaluates them in
    one batch (they run in parallel), and moves the Gaussian to the best :data:`ELITE_FRACTION` of every
    candidate so far (smoothed by :data:`SMOOTHING`; deviation at least :data:`MIN_STD`). It stops once a value
    is at most ``stop_at`` (a contact: nothing is closer) or the budget is spent; the last generation is cut
    to what is left of the budget. Deterministic given ``seed``.
    """
    _check(dim, budget)
    if not in_range(population, 2, integer=True):
        raise ValueError(f"population must be an integer >= 2, got {population!r}")
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    mean, std = np.zeros(dim), np.full(dim, INITIAL_STD)
    elite = max(2, int(round(ELITE_FRACTION * population)))
    candidates = np.empty((0, dim))
    values = np.empty(0)
    generations = 0
    while len(values) < budget:
        size = min(population, budget - len(values))
        batch = np.clip(mean + std * rng.standard_normal((size, dim)), -1.0, 1.0)
        candidates = np.vstack((candidates, batch))
        values = np.concatenate((values, _values(objective, batch)))
        generations += 1
        if values.min() <= stop_at:
            break
        best = candidates[np.argsort(values, kind="stable")[:elite]]
        mean = SMOOTHING * best.mean(axis=0) + (1 - SMOOTHING) * mean
        std = np.maximum(SMOOTHING * best.std(axis=0) + (1 - SMOOTHING) * std, MIN_STD)
    return SearchResult(candidates, values, generations)


def uniform_search(objective: Objective, dim: int, budget: int, seed: int, *, stop_at: float = 0.0,
                   population: int = POPULATION) -> SearchResult:
    """The same budget on candidates drawn uniformly from the box, in batches of ``population`` (the baseline)."""
    _check(dim, budget)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(2,)))
    candidates = np.empty((0, dim))
    values = np.empty(0)
    generations = 0
    while len(values) < budget:
        batch = rng.uniform(-1.0, 1.0, (min(population, budget - len(values)), dim))
        candidates = np.vstack((candidates, batch))
        values = np.concatenate((values, _values(objective, batch)))
        generations += 1
        if values.min() <= stop_at:
            break
    return SearchResult(candidates, values, generations)
