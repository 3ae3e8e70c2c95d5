"""Bumps the operator paints in the browser (a thread-safe set with ids, drags and fades), and the
console's one density (:class:`ConsoleDensity`: circling bump + bumps + input contacts).

The density mathematics lives below the console: the circling bump is
:func:`swarmdeck.coverage.s1_density` with the operator's parameters, snapshots are
merged by :func:`swarmdeck.coverage.merge_mixtures`, and painted bumps fade in and
out and follow a drag exactly as touch contacts do (:func:`swarmdeck.inputs.density.fade`,
:func:`swarmdeck.inputs.density.extrapolate`). What is the console's own is the
editing: ids, per-bump σ and weight, drags from any browser tab, removal.
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.console.runtime.params import DensityParams
from swarmdeck.core.checks import require_in_range
from swarmdeck.coverage.densities import s1_density
from swarmdeck.coverage.density import GaussianMixture, merge_mixtures
from swarmdeck.inputs import density as touch  # the fades and drags of touch contacts


@dataclass
class Bump:
    """A bump the operator placed: centre (m), σ (m), peak weight; ramps in/out over ``BumpSet.ramp`` s."""

    id: int
    mu: tuple[float, float]
    sigma: float
    weight: float
    born: float
    dying_since: float | None = None
    velocity: tuple[float, float] = (0.0, 0.0)  # m/s, estimated from the last two drags
    moved_at: float | None = None  # run time of the last drag, s


@dataclass
class BumpSet:
    """Bumps painted in the browser (thread-safe: GUI threads edit, the loop reads).

    Weights ramp in over ``ramp`` s after :meth:`add` and out after :meth:`remove`
    with a smoothstep, so φ_t stays finite (REFERENCE.md §5). A bump being dragged
    (:meth:`move`) gets a velocity from its last two positions (if they are at most
    ``max_gap`` s apart) and is extrapolated along it for up to ``extrapolate`` s, with
    μ̇ reported, so the time-varying coverage laws see the motion (as the contact
    density does for touches). Times are the loop's run time (s), passed in by the caller.
    """

    ramp: float = 0.4
    extrapolate: float = 0.1
    max_gap: float = 0.5
    sigma_range: tuple[float, float] = (0.05, 1.0)
    weight_range: tuple[float, float] = (0.0, 5.0)
    max_bumps: int = 32
    _bumps: dict[int, Bump] = field(default_factory=dict)
    _next: int = 0
    revision: int = 0  # incremented on every change (lets callers cache snapshots)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def _check(self, sigma: float, weight: float) -> None:
        require_in_range(sigma, "bump sigma", *self.sigma_range, unit="m")
        require_in_range(weight, "bump weight", *self.weight_range)

    def add(self, mu: ArrayLike, sigma: float, weight: float, t: float) -> int:
        """Add a bump at ``mu`` (2,) m; returns its id. ValueError for bad values or too many bumps."""
        m = np.asarray(mu, dtype=float).reshape(-1)
        if m.shape != (2,) or not np.all(np.isfinite(m)):
            raise ValueError(f"bump centre must be a finite (x, y) in m, got {mu!r}")
        self._check(float(sigma), float(weight))
        with self._lock:
            if sum(b.dying_since is None for b in self._bumps.values()) >= self.max_bumps:
                raise ValueError(f"at most {self.max_bumps} bumps; remove one first")
            bid = self._next
            self._next += 1
            self._bumps[bid] = Bump(bid, (float(m[0]), float(m[1])), float(sigma), float(weight), float(t))
            self.revision += 1
            return bid

    def move(self, bid: int, mu: ArrayLike, t: float | None = None) -> None:
        """Put bump ``bid`` at ``mu`` (m) at run time ``t`` (s; None: a jump, no velocity)."""
        m = np.asarray(mu, dtype=float).reshape(-1)[:2]
        if m.shape != (2,) or not np.all(np.isfinite(m)):
            raise ValueError(f"bump centre must be a finite (x, y) in m, got {mu!r}")
        with self._lock:
            b = self._bumps.get(bid)
            if b is None:
                return
            if t is None:
                b.velocity, b.moved_at = (0.0, 0.0), None
            else:
                gap = None if b.moved_at is None else float(t) - b.moved_at
                if gap is not None and 0.0 < gap <= self.max_gap:
                    b.velocity = ((m[0] - b.mu[0]) / gap, (m[1] - b.mu[1]) / gap)
                elif gap is None or gap > self.max_gap:
                    b.velocity = (0.0, 0.0)
                b.moved_at = float(t)  # gap == 0 (same tick): keep the last velocity estimate
            b.mu = (float(m[0]), float(m[1]))
            self.revision += 1

    def update(self, bid: int, sigma: float | None = None, weight: float | None = None) -> None:
        with self._lock:
            b = self._bumps.get(bid)
            if b is None:
                raise ValueError(f"no bump {bid}")
            s = b.sigma if sigma is None else float(sigma)
            w = b.weight if weight is None else float(weight)
            self._check(s, w)
            b.sigma, b.weight = s, w
            self.revision += 1

    def remove(self, bid: int, t: float) -> None:
        """Start fading bump ``bid`` out (it disappears after ``ramp`` s)."""
        with self._lock:
            b = self._bumps.get(bid)
            if b is not None and b.dying_since is None:
                b.dying_since = float(t)
                self.revision += 1

    def live(self) -> list[Bump]:
        """Bumps not being removed (copies)."""
        with self._lock:
            return [Bump(**vars(b)) for b in self._bumps.values() if b.dying_since is None]

    def get(self, bid: int) -> Bump | None:
        with self._lock:
            b = self._bumps.get(bid)
            return None if b is None else Bump(**vars(b))

    def copy(self) -> BumpSet:
        """An independent copy (the bumps as they are now: what one tick sees)."""
        with self._lock:
            return BumpSet(self.ramp, self.extrapolate, self.max_gap, self.sigma_range, self.weight_range,
                           self.max_bumps, {k: Bump(**vars(b)) for k, b in self._bumps.items()}, self._next,
                           self.revision)

    def prune(self, t: float) -> None:
        """Forget the bumps that have faded out by run time ``t`` (s)."""
        with self._lock:
            self._prune(t)

    def _prune(self, t: float) -> None:
        gone = [k for k, b in self._bumps.items() if b.dying_since is not None and t - b.dying_since >= self.ramp]
        for k in gone:
            del self._bumps[k]

    def snapshot(self, t: float, floor: float = 0.05) -> GaussianMixture | None:
        """Bumps at run time t over ``floor`` (> 0: a bump fading in from weight 0 is still a valid
        density) with ramped weights and their exact rates; None when there are none."""
        with self._lock:
            self._prune(t)
            bumps = list(self._bumps.values())
            if not bumps:
                return None
            mu = np.array([b.mu for b in bumps])
            vel = np.array([b.velocity for b in bumps])
            moved = np.array([math.inf if b.moved_at is None else b.moved_at for b in bumps])  # inf: hold
            sigma = np.array([b.sigma for b in bumps])
            w = np.array([b.weight for b in bumps])
            born = np.array([b.born for b in bumps])
            dying = np.array([math.inf if b.dying_since is None else b.dying_since for b in bumps])
        scale, rate = touch.fade(t, born, dying, self.ramp)
        mu, mu_dot = touch.extrapolate(mu, vel, moved, t, self.extrapolate)
        return GaussianMixture(floor, mu=mu, sigma=sigma, weight=w * scale, weight_dot=w * rate, mu_dot=mu_dot)


class ConsoleDensity:
    """The one density the behaviours see: circling bump + browser bumps + input contacts (a Density).

    ``at(t)`` takes the loop's run time; the contact part is the snapshot the loop set for this tick
    (contacts live on the loop clock). The bumps are those of :meth:`freeze` (the loop freezes them at
    the start of every tick, so an edit from another thread lands whole at the next tick), or the live set.
    """

    def __init__(self, params: DensityParams, bumps: BumpSet) -> None:
        self.params = params
        self.bumps = bumps
        self.contacts: GaussianMixture | None = None
        self._view: BumpSet | None = None
        self._cache: tuple[Any, GaussianMixture] | None = None
        self._cache_contacts: GaussianMixture | None = None

    @property
    def params(self) -> DensityParams:
        """The operator's density parameters (setting them rebuilds the circling bump)."""
        return self._params

    @params.setter
    def params(self, p: DensityParams) -> None:
        self.moving = s1_density(p.radius, p.period, p.sigma, p.weight, p.floor)
        self._params = p

    def freeze(self, t: float) -> None:
        """From now on use the bumps as they are at run time ``t`` (s), faded-out ones forgotten."""
        self.bumps.prune(t)
        self._view = self.bumps.copy()

    def at(self, t: float) -> GaussianMixture:
        bumps = self.bumps if self._view is None else self._view
        key = (t, bumps.revision, self.params)
        if self._cache is not None and self._cache[0] == key and self._cache_contacts is self.contacts:
            return self._cache[1]
        parts = [self.moving.at(t) if self.params.moving else None, bumps.snapshot(t, self.params.floor),
                 self.contacts]
        snap = merge_mixtures(parts, self.params.floor)
        self._cache, self._cache_contacts = (key, snap), self.contacts
        return snap
