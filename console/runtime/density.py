"""The console's density φ(·, t): a moving bump, bumps painted in the browser, input contacts, merged.

:class:`MovingBump` is a *Density* (``.at(t) -> GaussianMixture``, see
:mod:`swarmdeck.coverage.density`); :meth:`BumpSet.snapshot` gives the painted
bumps at a time (or None). :func:`merge_mixtures` concatenates the bumps of several snapshots into one
snapshot (floors are not added: the merged floor is the given one), so the
coverage controller sees one φ and one analytic φ_t.
"""
from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.core.checks import require_in_range
from swarmdeck.core.smooth import smoothstep
from swarmdeck.coverage.density import GaussianMixture


@dataclass(frozen=True)
class MovingBump:
    """One Gaussian bump circling the arena centre (REFERENCE.md §5, scenario S1).

    φ = floor + weight · exp(−‖q − μ(t)‖² / (2σ²)), μ(t) = radius·(cos(2πt/period), sin(2πt/period)).
    Units: m, s. ``weight`` in the same arbitrary unit as the floor.
    """

    radius: float = 0.6
    period: float = 20.0
    sigma: float = 0.4
    weight: float = 1.0
    floor: float = 0.05

    def __post_init__(self) -> None:
        for name in ("sigma", "period"):
            require_in_range(getattr(self, name), f"moving density {name}", 0.0, lo_open=True)
        for name in ("radius", "weight", "floor"):
            require_in_range(getattr(self, name), f"moving density {name}", 0.0)

    def at(self, t: float) -> GaussianMixture:
        """Snapshot at time t [s] with exact μ̇."""
        a = 2.0 * math.pi * t / self.period
        om = 2.0 * math.pi / self.period
        mu = self.radius * np.array([[math.cos(a), math.sin(a)]])
        mu_dot = self.radius * om * np.array([[-math.sin(a), math.cos(a)]])
        return GaussianMixture(self.floor, mu=mu, sigma=[self.sigma], weight=[self.weight], mu_dot=mu_dot)


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

    def snapshot(self, t: float, floor: float = 0.05) -> GaussianMixture | None:
        """Bumps at run time t over ``floor`` (> 0: a bump fading in from weight 0 is still a valid
        density) with ramped weights and their exact rates; None when there are none."""
        with self._lock:
            gone = [k for k, b in self._bumps.items() if b.dying_since is not None and t - b.dying_since >= self.ramp]
            for k in gone:
                del self._bumps[k]
            bumps = list(self._bumps.values())
            if not bumps:
                return None
            mu = np.array([b.mu for b in bumps])
            vel = np.array([b.velocity for b in bumps])
            since = np.array([np.nan if b.moved_at is None else t - b.moved_at for b in bumps])
            sigma = np.array([b.sigma for b in bumps])
            w = np.array([b.weight for b in bumps])
            born = np.array([b.born for b in bumps])
            dying = np.array([np.nan if b.dying_since is None else b.dying_since for b in bumps])
        s_in, ds_in = smoothstep((t - born) / self.ramp)
        ds_in = np.where((t - born) / self.ramp < 1.0, ds_in, 0.0)
        out = np.where(np.isnan(dying), 0.0, (t - np.nan_to_num(dying)) / self.ramp)
        s_out, ds_out = smoothstep(1.0 - out)
        ds_out = np.where(np.isnan(dying), 0.0, ds_out)
        scale = s_in * s_out
        rate = (ds_in * s_out - s_in * ds_out) / self.ramp
        since = np.nan_to_num(since, nan=np.inf)
        moving = (since >= 0.0) & (since < self.extrapolate)
        mu = mu + vel * np.clip(since, 0.0, self.extrapolate)[:, None] * np.isfinite(since)[:, None]
        return GaussianMixture(floor, mu=mu, sigma=sigma, weight=w * scale, weight_dot=w * rate,
                               mu_dot=vel * moving[:, None])


def merge_mixtures(parts: Sequence[GaussianMixture | None], floor: float) -> GaussianMixture:
    """One snapshot holding every bump of ``parts`` (Nones skipped) over the given floor.

    Isotropic when every part is; otherwise all bumps are written as covariances.
    """
    ps = [p for p in parts if p is not None and p.n_bumps > 0]
    if not ps:
        return GaussianMixture(floor)
    mu = np.concatenate([p.mu for p in ps])
    w = np.concatenate([p.weight for p in ps])
    mu_dot = np.concatenate([p.mu_dot for p in ps])
    w_dot = np.concatenate([p.weight_dot for p in ps])
    if all(p.isotropic for p in ps):
        return GaussianMixture(floor, mu=mu, sigma=np.concatenate([p.sigma for p in ps]), weight=w,
                               mu_dot=mu_dot, sigma_dot=np.concatenate([p.sigma_dot for p in ps]), weight_dot=w_dot)
    return GaussianMixture(floor, mu=mu, weight=w, mu_dot=mu_dot, weight_dot=w_dot,
                           cov=np.concatenate([p.cov for p in ps]), cov_dot=np.concatenate([p.cov_dot for p in ps]))
