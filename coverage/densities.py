"""Analytic time-varying densities: bumps that move, grow and shrink, fade in and out.

An :class:`AnalyticDensity` is a floor plus bumps; each :class:`Bump` has a centre trajectory,
a width profile and a weight profile, each giving its value *and its exact time derivative*, so
``at(t)`` returns a :class:`GaussianMixture` snapshot with exact μ̇, σ̇, ẇ and hence an exact φ_t.

Profiles (scalar, value and d/dt): :class:`Constant`, :class:`Sine` (breathing width, pulsing
weight), :class:`Pulse` (smoothstep fade in at ``t_on`` and out at ``t_off``).
Trajectories ((2,), value and d/dt): :class:`Fixed`, :class:`Orbit` (circle),
:class:`Lissajous`, :class:`Linear`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.checks import require_in_range
from swarmdeck.core.smooth import smoothstep
from swarmdeck.coverage.density import GaussianMixture

__all__ = ["Constant", "Sine", "Pulse", "Fixed", "Orbit", "Lissajous", "Linear", "Bump",
           "AnalyticDensity", "s1_density", "moving_density"]

_TWO_PI = 2.0 * np.pi


# ---------------------------------------------------------------- scalar profiles
@dataclass(frozen=True)
class Constant:
    """value(t) = value."""

    value: float

    def __call__(self, t: float) -> tuple[float, float]:
        return float(self.value), 0.0


@dataclass(frozen=True)
class Sine:
    """value(t) = mean + amplitude · sin(2π t / period + phase); period [s] > 0."""

    mean: float
    amplitude: float
    period: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        require_in_range(self.period, "period", 0.0, lo_open=True)

    def __call__(self, t: float) -> tuple[float, float]:
        w = _TWO_PI / self.period
        arg = w * t + self.phase
        return (self.mean + self.amplitude * np.sin(arg), self.amplitude * w * np.cos(arg))


@dataclass(frozen=True)
class Pulse:
    """level · s((t − t_on)/ramp) · (1 − s((t − t_off)/ramp)): fades in over ``ramp`` seconds from
    ``t_on`` and out from ``t_off`` (smoothstep, so the rate stays finite). ``period`` > 0 repeats
    the pulse every ``period`` seconds."""

    level: float = 1.0
    t_on: float = 0.0
    t_off: float = float("inf")
    ramp: float = 0.4
    period: float | None = None

    def __post_init__(self) -> None:
        require_in_range(self.ramp, "ramp", 0.0, lo_open=True)
        require_in_range(self.level, "level", 0.0)
        if self.period is not None and not self.period > 0:
            raise ValueError(f"period must be > 0 or None, got {self.period!r}")

    def __call__(self, t: float) -> tuple[float, float]:
        if self.period is not None:
            t = t % self.period
        a, da = smoothstep((t - self.t_on) / self.ramp)
        b, db = smoothstep((t - self.t_off) / self.ramp) if np.isfinite(self.t_off) else (0.0, 0.0)
        val = self.level * a * (1.0 - b)
        rate = self.level * (da * (1.0 - b) - a * db) / self.ramp
        return float(val), float(rate)


# ---------------------------------------------------------------- trajectories
@dataclass(frozen=True)
class Fixed:
    """μ(t) = point [m]."""

    point: tuple[float, float]

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return np.asarray(self.point, dtype=float), np.zeros(2)


@dataclass(frozen=True)
class Orbit:
    """μ(t) = centre + radius (cos(2πt/period + phase), sin(…)); negative period turns clockwise."""

    centre: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.6
    period: float = 20.0
    phase: float = 0.0

    def __post_init__(self) -> None:
        if self.period == 0:
            raise ValueError("period must be non-zero")

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        w = _TWO_PI / self.period
        arg = w * t + self.phase
        c = np.asarray(self.centre, dtype=float)
        return (c + self.radius * np.array([np.cos(arg), np.sin(arg)]),
                self.radius * w * np.array([-np.sin(arg), np.cos(arg)]))


@dataclass(frozen=True)
class Lissajous:
    """μ(t) = centre + (ax sin(2πt/px + φx), ay sin(2πt/py + φy))."""

    centre: tuple[float, float] = (0.0, 0.0)
    amplitude: tuple[float, float] = (1.0, 0.5)
    period: tuple[float, float] = (24.0, 16.0)
    phase: tuple[float, float] = (0.0, 0.0)

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        w = _TWO_PI / np.asarray(self.period, dtype=float)
        arg = w * t + np.asarray(self.phase, dtype=float)
        a = np.asarray(self.amplitude, dtype=float)
        return np.asarray(self.centre, dtype=float) + a * np.sin(arg), a * w * np.cos(arg)


@dataclass(frozen=True)
class Linear:
    """μ(t) = start + velocity · t (m, m/s)."""

    start: tuple[float, float]
    velocity: tuple[float, float]

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        v = np.asarray(self.velocity, dtype=float)
        return np.asarray(self.start, dtype=float) + v * t, v


# ---------------------------------------------------------------- density
@dataclass(frozen=True)
class Bump:
    """One Gaussian bump: centre trajectory ``mu``, width ``sigma`` [m], peak ``weight``.

    Anisotropic bumps: ``aspect`` ≠ 1 stretches the bump along its major axis (std σ·aspect
    there, σ across), and ``angle`` [rad] (a profile, so it may rotate) turns that axis from +x:
    Σ = σ² R(θ) diag(aspect², 1) R(θ)ᵀ, with the exact Σ̇ from σ̇ and θ̇.
    """

    mu: Fixed | Orbit | Lissajous | Linear
    sigma: Constant | Sine | Pulse = Constant(0.3)
    weight: Constant | Sine | Pulse = Constant(1.0)
    aspect: float = 1.0
    angle: Constant | Sine | Pulse = Constant(0.0)

    def __post_init__(self) -> None:
        require_in_range(self.aspect, "aspect", 0.0, lo_open=True)

    @property
    def isotropic(self) -> bool:
        return self.aspect == 1.0

    def covariance(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Σ(t) and Σ̇(t) (2, 2) [m², m²/s]."""
        s, s_dot = self.sigma(t)
        th, th_dot = self.angle(t)
        c, si = np.cos(th), np.sin(th)
        rot = np.array([[c, -si], [si, c]])
        rot_dot = th_dot * np.array([[-si, -c], [c, -si]])
        d0 = np.diag([self.aspect ** 2, 1.0])
        shape = rot @ d0 @ rot.T
        shape_dot = rot_dot @ d0 @ rot.T + rot @ d0 @ rot_dot.T
        return s * s * shape, 2.0 * s * s_dot * shape + s * s * shape_dot


@dataclass(frozen=True)
class AnalyticDensity:
    """φ(q, t) = floor + Σ_k w_k(t) exp(−‖q − μ_k(t)‖² / (2σ_k(t)²)) with exact derivatives.

    ``at(t)`` raises ValueError when a profile gives σ ≤ 0 or w < 0 at t (naming the bump).
    """

    floor: float = 0.05
    bumps: tuple[Bump, ...] = field(default_factory=tuple)

    def at(self, t: float) -> GaussianMixture:
        """The snapshot at time t [s] with exact μ̇, σ̇, ẇ."""
        k = len(self.bumps)
        mu, mu_dot = np.zeros((k, 2)), np.zeros((k, 2))
        sig, sig_dot, w, w_dot = np.zeros(k), np.zeros(k), np.zeros(k), np.zeros(k)
        for i, b in enumerate(self.bumps):
            mu[i], mu_dot[i] = b.mu(t)
            sig[i], sig_dot[i] = b.sigma(t)
            w[i], w_dot[i] = b.weight(t)
        if np.any(w < -1e-12):
            k_bad = int(np.flatnonzero(w < -1e-12)[0])
            raise ValueError(f"bump {k_bad}: weight profile is negative at t = {t} ({w[k_bad]:.3g}); "
                             "weights must stay >= 0 (e.g. Sine mean >= amplitude)")
        w = np.maximum(w, 0.0)      # round-off of a fading weight
        if all(b.isotropic for b in self.bumps):
            return GaussianMixture(self.floor, mu, sig, w, mu_dot, sig_dot, w_dot)
        if np.any(sig <= 0):
            k_bad = int(np.flatnonzero(sig <= 0)[0])
            raise ValueError(f"bump {k_bad}: sigma profile is <= 0 at t = {t} ({sig[k_bad]:.3g})")
        cov, cov_dot = np.zeros((k, 2, 2)), np.zeros((k, 2, 2))
        for i, b in enumerate(self.bumps):
            cov[i], cov_dot[i] = b.covariance(t)
        return GaussianMixture(self.floor, mu, weight=w, mu_dot=mu_dot, weight_dot=w_dot,
                               cov=cov, cov_dot=cov_dot)


def s1_density(radius: float = 0.6, period: float = 20.0, sigma: float = 0.4, weight: float = 1.0,
               floor: float = 0.05) -> AnalyticDensity:
    """Scenario S1 (REFERENCE.md §5): φ = floor + weight · exp(−‖q − μ(t)‖²/(2σ²)),
    μ(t) = radius · (cos(2πt/period), sin(2πt/period)); by default 0.05, 1, σ = 0.4 m, 0.6 m, 20 s.

    The console's circling bump is this density with the operator's parameters (m, s).
    ValueError naming the parameter for σ or period ≤ 0 and for a negative radius, weight or floor.
    """
    for name, value in (("sigma", sigma), ("period", period)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"moving density {name} must be > 0, got {value!r}")
    for name, value in (("radius", radius), ("weight", weight), ("floor", floor)):
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"moving density {name} must be >= 0, got {value!r}")
    return AnalyticDensity(floor, (Bump(Orbit((0.0, 0.0), radius, period), Constant(sigma), Constant(weight)),))


def moving_density(bounds: Bounds = DEFAULT_BOUNDS
                   ) -> AnalyticDensity:
    """Demo density: one bump orbiting, one breathing on a Lissajous path, one elongated bump
    that rocks back and forth and fades in and out every 16 s, all scaled to ``bounds``."""
    b = Bounds.of(bounds)
    cx, cy = b.centre
    sx, sy = 0.5 * b.width, 0.5 * b.height
    s = min(sx, sy)
    return AnalyticDensity(0.05, (
        Bump(Orbit((cx - 0.35 * sx, cy), 0.45 * s, 20.0), Constant(0.25 * s), Constant(1.0)),
        Bump(Lissajous((cx + 0.4 * sx, cy), (0.3 * sx, 0.5 * sy), (18.0, 12.0)),
             Sine(0.22 * s, 0.08 * s, 10.0), Constant(0.8)),
        Bump(Fixed((cx, cy - 0.55 * sy)), Constant(0.2 * s), Pulse(1.0, 2.0, 10.0, 1.0, 16.0),
             aspect=2.0, angle=Sine(0.0, 0.6, 8.0)),
    ))
