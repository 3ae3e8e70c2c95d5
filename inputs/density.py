"""Contacts → a time-varying Gaussian-mixture density with analytic φ_t.

One isotropic bump per contact (REFERENCE.md §5, "Density from touches")::

    φ(q, t) = floor + Σ_k w_k(t) exp(−‖q − μ_k(t)‖² / (2 σ_k(t)²))

* μ_k(t) = p_k + v_k · clip(t − t_k, 0, h): the contact's position p_k as of the
  last :meth:`ContactDensity.update` (at time t_k, the caller's clock — contact
  receive stamps are never mixed in, so listener and loop clocks may differ)
  extrapolated along its velocity v_k for at most ``extrapolate`` = h seconds;
  μ̇_k = v_k while 0 ≤ t − t_k < h, else 0 (exact derivative).
* w_k(t) = W · S((t − t_down)/T) · (1 − S((t − t_up)/T)), S(u) = 3u² − 2u³ on
  [0, 1] (smoothstep), T = ``fade`` (0.3–0.5 s), so a new touch fades in, a lifted or
  lost one fades out from where it was (its velocity set to 0) instead of
  vanishing; ẇ_k is the analytic derivative (S'(u) = 6u(1 − u)/T).
* σ_k = σ₀, except for a *pinch*: when a source has exactly two bumps,
  σ_p = clip(gain · ‖μ₁ − μ₂‖, σ_min, σ_max) with σ̇_p = gain · (μ₁ − μ₂)·(μ̇₁ − μ̇₂)/‖μ₁ − μ₂‖
  (0 where clipped), blended in by β = f₁ f₂ (the bumps' fade factors) so that σ
  stays continuous when the second finger lands or lifts:
  σ = σ₀ + β (σ_p − σ₀), σ̇ = β̇ (σ_p − σ₀) + β σ̇_p.

``ContactDensity`` is a Density: ``update(contacts, t)`` once per tick, then any
number of ``at(t)`` calls (the coverage controller's).
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import in_range, require_in_range
from swarmdeck.core.config import check_keys, field_names
from swarmdeck.core.smooth import inverse_smoothstep, smoothstep
from swarmdeck.coverage import GaussianMixture

from .contact import Contact


@dataclass(frozen=True)
class DensityConfig:
    """Bump parameters (defaults from REFERENCE.md §5).

    Attributes:
        floor: constant part of φ (1/m², relative to ``weight``); > 0 keeps cell masses positive.
        weight: peak W of one bump.
        sigma: σ₀ in m (0.15–0.4 on the default arena).
        fade: T in s, smoothstep fade-in/out time (> 0).
        pinch: two contacts of one source set σ by their distance.
        pinch_gain: σ_p per metre of finger distance.
        sigma_min, sigma_max: clip of σ_p in m.
        extrapolate: h in s, longest extrapolation of μ along the contact velocity.
        max_bumps: at most this many bumps (newest contacts beyond it are ignored).
    """

    floor: float = 0.05
    weight: float = 1.0
    sigma: float = 0.3
    fade: float = 0.4
    pinch: bool = True
    pinch_gain: float = 0.5
    sigma_min: float = 0.15
    sigma_max: float = 0.4
    extrapolate: float = 0.1
    max_bumps: int = 32

    def __post_init__(self) -> None:
        for k in ("weight", "sigma", "fade", "sigma_min", "sigma_max", "pinch_gain"):
            v = getattr(self, k)
            if not in_range(v, 0.0, lo_open=True):
                raise ValueError(f"density {k} must be a positive number, got {v!r}")
        if not in_range(self.floor, 0.0, lo_open=True):
            raise ValueError(f"density floor must be > 0 (keeps every Voronoi cell's mass positive), got {self.floor!r}")
        require_in_range(self.extrapolate, "density extrapolate", 0.0, unit="s")
        if self.sigma_min > self.sigma_max:
            raise ValueError(f"density sigma_min {self.sigma_min} exceeds sigma_max {self.sigma_max}")
        if not in_range(self.max_bumps, 1, integer=True):
            raise ValueError(f"density max_bumps must be an int >= 1, got {self.max_bumps!r}")

    @classmethod
    def from_dict(cls, d: dict) -> DensityConfig:
        """Build from a mapping (``[inputs.density]``); unknown keys are an error."""
        return cls(**check_keys(d, field_names(cls), "density", error=ValueError))


def fade(t: float, t_down: ArrayLike, t_up: ArrayLike, duration: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Fade factors of bumps that appear at ``t_down`` and disappear from ``t_up`` (s; arrays (K,)).

    f = S((t − t_down)/T) · (1 − S((t − t_up)/T)) with T = ``duration`` s and S the smoothstep, and
    its exact rate ḟ (1/s). ``t_up = inf``: not going; ``t_down = −inf``: fully in. Returns (f, ḟ), (K,).
    Used by :class:`ContactDensity` and by anything else whose bumps fade (the console's painted bumps).
    """
    with np.errstate(invalid="ignore"):
        s_in, ds_in = smoothstep((t - np.asarray(t_down, dtype=float)) / duration)
        s_o, ds_o = smoothstep((t - np.asarray(t_up, dtype=float)) / duration)
    s_out = 1.0 - s_o
    return s_in * s_out, (ds_in * s_out - s_in * ds_o) / duration


def extrapolate(p: ArrayLike, v: ArrayLike, t_ref: ArrayLike, t: float,
                horizon: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centres (K, 2) m seen at ``p`` moving at ``v`` (K, 2) m/s at times ``t_ref`` (K,) s, at time ``t``.

    μ = p + v · clip(t − t_ref, 0, h), μ̇ = v while 0 ≤ t − t_ref < h, else 0 (h = ``horizon`` s):
    a contact keeps moving along its last velocity for at most h, then holds. Returns (μ, μ̇).
    """
    v = np.asarray(v, dtype=float)
    dt = t - np.asarray(t_ref, dtype=float)
    moving = (dt >= 0.0) & (dt < horizon)
    return np.asarray(p, dtype=float) + v * np.clip(dt, 0.0, horizon)[:, None], v * moving[:, None]


class _Bump:
    __slots__ = ("source", "p", "v", "t_ref", "t_down", "t_up")

    def __init__(self, source: str, p: np.ndarray, v: np.ndarray, t_ref: float, t_down: float) -> None:
        self.source = source
        self.p = p
        self.v = v
        self.t_ref = t_ref
        self.t_down = t_down
        self.t_up = math.inf


class ContactDensity:
    """A :class:`~swarmdeck.coverage.Density` driven by contacts.

    Call :meth:`update` with the current contacts (e.g. ``hub.poll(now).contacts``)
    once per tick; :meth:`at` then gives the mixture at any time with analytic
    μ̇, σ̇ and ẇ (see the module docstring for the formulas).
    """

    def __init__(self, config: DensityConfig | None = None) -> None:
        self.config = config or DensityConfig()
        self._bumps: dict[tuple[str, int], _Bump] = {}

    @property
    def n_bumps(self) -> int:
        """Bumps currently present (live or fading out)."""
        return len(self._bumps)

    def _fade(self, b: _Bump, t: float) -> float:
        return float(fade(t, [b.t_down], [b.t_up], self.config.fade)[0][0])

    def _mu(self, b: _Bump, t: float) -> np.ndarray:
        return extrapolate(b.p[None], b.v[None], [b.t_ref], t, self.config.extrapolate)[0][0]

    def update(self, contacts: Iterable[Contact], t: float) -> None:
        """Take the current contacts at time ``t`` (s): new ones start fading in,
        missing ones start fading out from their position at ``t``."""
        cfg = self.config
        seen = set()
        live = sum(1 for b in self._bumps.values() if b.t_up == math.inf)
        for c in contacts:
            key = c.key
            seen.add(key)
            b = self._bumps.get(key)
            p = np.array(c.position, dtype=float)
            v = np.array(c.velocity, dtype=float)
            if not (np.all(np.isfinite(p)) and np.all(np.isfinite(v))):
                continue
            if b is None:
                if live >= cfg.max_bumps:
                    continue
                self._bumps[key] = _Bump(c.source, p, v, float(t), float(t))
                live += 1
                continue
            if b.t_up < math.inf:  # came back while fading out: fade in from the current level
                f = self._fade(b, t)
                b.t_down = t - inverse_smoothstep(f) * cfg.fade
                b.t_up = math.inf
                live += 1
            b.p, b.v, b.t_ref = p, v, float(t)
        for key, b in list(self._bumps.items()):
            if key in seen:
                continue
            if b.t_up == math.inf:
                f = self._fade(b, t)
                b.p = self._mu(b, t)
                b.v = np.zeros(2)
                b.t_ref = t
                # fade out from the current level (continuous weight if still fading in)
                b.t_up = t - inverse_smoothstep(1.0 - f) * cfg.fade
                b.t_down = -math.inf
                # keep the weight continuous: w = W·f before, W·(1 − S(u)) after
            elif t - b.t_up >= cfg.fade:
                del self._bumps[key]

    def at(self, t: float) -> GaussianMixture:
        """The mixture at time ``t`` (s) with analytic time derivatives."""
        cfg = self.config
        bumps = list(self._bumps.values())
        k = len(bumps)
        if k == 0:
            return GaussianMixture(floor=cfg.floor, mu=np.zeros((0, 2)), sigma=np.zeros(0), weight=np.zeros(0))
        p = np.array([b.p for b in bumps])
        v = np.array([b.v for b in bumps])
        t_ref = np.array([b.t_ref for b in bumps])
        t_down = np.array([b.t_down for b in bumps])
        t_up = np.array([b.t_up for b in bumps])
        mu, mu_dot = extrapolate(p, v, t_ref, t, cfg.extrapolate)
        f, f_dot = fade(t, t_down, t_up, cfg.fade)
        weight = cfg.weight * f
        weight_dot = cfg.weight * f_dot
        sigma = np.full(k, cfg.sigma)
        sigma_dot = np.zeros(k)
        if cfg.pinch:
            by_source: dict[str, list[int]] = {}
            for i, b in enumerate(bumps):
                by_source.setdefault(b.source, []).append(i)
            for idx in by_source.values():
                if len(idx) != 2:
                    continue
                i, j = idx
                d_vec = mu[i] - mu[j]
                d = float(np.hypot(*d_vec))
                raw = cfg.pinch_gain * d
                sp = min(max(raw, cfg.sigma_min), cfg.sigma_max)
                sp_dot = 0.0
                if cfg.sigma_min < raw < cfg.sigma_max and d > 0:
                    sp_dot = cfg.pinch_gain * float(d_vec @ (mu_dot[i] - mu_dot[j])) / d
                beta = f[i] * f[j]
                beta_dot = f_dot[i] * f[j] + f[i] * f_dot[j]
                s = cfg.sigma + beta * (sp - cfg.sigma)
                s_dot = beta_dot * (sp - cfg.sigma) + beta * sp_dot
                sigma[[i, j]] = s
                sigma_dot[[i, j]] = s_dot
        return GaussianMixture(floor=cfg.floor, mu=mu, sigma=sigma, weight=weight,
                               mu_dot=mu_dot, sigma_dot=sigma_dot, weight_dot=weight_dot)
