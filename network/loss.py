"""Link loss models (REFERENCE.md §16): Bernoulli and Gilbert–Elliott, per directed link, vectorised.

A loss model decides, for each message of a tick, whether it is lost. Gilbert–Elliott keeps a two-state
Markov chain (Good/Bad) per directed link: each tick the link exists, a Good link turns Bad with probability
``p`` and a Bad link turns Good with probability ``r``; a message is lost with probability ``k_good`` on a
Good link and ``k_bad`` on a Bad one. The stationary P(Bad) is ``p / (p + r)``, the mean burst length ``1 / r``,
so the stationary loss rate is ``k_good · r/(p+r) + k_bad · p/(p+r)``. Links start in their stationary
distribution. States live in the :class:`LossState` the network owns; the models are frozen configuration.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

__all__ = ["BernoulliLoss", "GilbertElliottLoss", "LossModel", "LossState"]


def _probability(name: str, value: float) -> None:
    if not (isinstance(value, (int, float, np.floating)) and 0.0 <= float(value) <= 1.0):
        raise ValueError(f"{name} must be a probability in [0, 1], got {value!r}")


@dataclass
class LossState:
    """Per-link Gilbert–Elliott states: sorted link keys (sender · N + receiver) and whether each is Bad."""

    keys: NDArray[np.int64] = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    bad: NDArray[np.bool_] = field(default_factory=lambda: np.empty(0, dtype=bool))


@runtime_checkable
class LossModel(Protocol):
    """``advance`` the links present this tick; ``lost`` for the messages of a tick."""

    def advance(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> LossState: ...

    def lost(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> NDArray[np.bool_]: ...

    def stationary_loss(self) -> float: ...


@dataclass(frozen=True)
class BernoulliLoss:
    """Every message is lost independently with probability ``p``."""

    p: float

    def __post_init__(self) -> None:
        _probability("BernoulliLoss.p", self.p)

    def advance(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> LossState:
        return state

    def lost(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> NDArray[np.bool_]:
        return rng.random(len(keys)) < self.p

    def stationary_loss(self) -> float:
        return float(self.p)


@dataclass(frozen=True)
class GilbertElliottLoss:
    """Bursty loss: Good → Bad with probability ``p``, Bad → Good with ``r`` per tick; loss ``k_good``/``k_bad``."""

    p: float
    r: float
    k_good: float = 0.0
    k_bad: float = 1.0

    def __post_init__(self) -> None:
        for name in ("p", "r", "k_good", "k_bad"):
            _probability(f"GilbertElliottLoss.{name}", getattr(self, name))
        if self.p + self.r <= 0:
            raise ValueError("GilbertElliottLoss: p + r must be positive (else the chain never moves)")

    @property
    def p_bad(self) -> float:
        """Stationary probability of the Bad state, p / (p + r)."""
        return float(self.p) / (float(self.p) + float(self.r))

    def stationary_loss(self) -> float:
        return float(self.k_good) * (1.0 - self.p_bad) + float(self.k_bad) * self.p_bad

    def advance(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> LossState:
        """One tick of the chain for the links ``keys`` (sorted, unique); new links start stationary."""
        pos = np.searchsorted(state.keys, keys)
        known = pos < len(state.keys)
        known[known] = state.keys[pos[known]] == keys[known]
        bad = np.empty(len(keys), dtype=bool)
        bad[~known] = rng.random(int((~known).sum())) < self.p_bad
        was = state.bad[pos[known]]
        u = rng.random(len(was))
        bad[known] = np.where(was, u >= self.r, u < self.p)
        old_only = np.ones(len(state.keys), dtype=bool)
        old_only[pos[known]] = False
        all_keys = np.concatenate((state.keys[old_only], keys))
        all_bad = np.concatenate((state.bad[old_only], bad))
        order = np.argsort(all_keys, kind="stable")
        return LossState(all_keys[order], all_bad[order])

    def lost(self, state: LossState, keys: NDArray[np.int64], rng: np.random.Generator) -> NDArray[np.bool_]:
        """Whether each message on link ``keys`` (any order, repeats allowed; links already advanced) is lost."""
        pos = np.minimum(np.searchsorted(state.keys, keys), max(len(state.keys) - 1, 0))
        bad = state.bad[pos] if len(state.keys) else np.zeros(len(keys), dtype=bool)
        return rng.random(len(keys)) < np.where(bad, self.k_bad, self.k_good)
