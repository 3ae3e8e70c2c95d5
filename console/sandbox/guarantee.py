"""A stated guarantee from verification runs: an upper bound on P(contact per run) (REFERENCE.md §17).

n independent raw runs (no barrier), x of them with a contact: the one-sided Clopper–Pearson upper
bound at confidence 1 − δ is the p with P(Binomial(n, p) ≤ x) = δ, i.e.
``scipy.stats.beta.ppf(1 − δ, x + 1, n − x)``; with x = 0 it is 1 − δ^(1/n) (≈ 3/n at 95 %: the rule
of three). The runs a target ε needs at 1 − δ when none fails: the smallest n with (1 − ε)^n ≤ δ,
i.e. n ≥ ln δ / ln(1 − ε) (ε = 1 %, δ = 5 % → 299). When runs do fail, more runs are needed for the same
ε: :func:`runs_needed` with ``failures`` = x gives the smallest n whose bound with x failures is ≤ ε.

Pure functions: every argument is checked and a ValueError names what is wrong.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.stats import beta

from swarmdeck.core.checks import in_range

#: the most runs :func:`runs_needed` will search (a target that needs more is refused with the count)
MAX_RUNS = 10_000_000


def _check_confidence(confidence: float) -> float:
    if isinstance(confidence, bool) or not in_range(confidence, 0.0, 1.0, lo_open=True, hi_open=True):
        raise ValueError(f"confidence must be a number strictly between 0 and 1 (e.g. 0.95), got {confidence!r}")
    return float(confidence)


def _check_epsilon(epsilon: float) -> float:
    if isinstance(epsilon, bool) or not in_range(epsilon, 0.0, 1.0, lo_open=True, hi_open=True):
        raise ValueError(f"epsilon (the target P(contact per run)) must be a number strictly between 0 and 1 "
                         f"(e.g. 0.01), got {epsilon!r}")
    return float(epsilon)


def _check_counts(runs: int, failures: int) -> None:
    if isinstance(runs, bool) or not in_range(runs, 1, integer=True):
        raise ValueError(f"runs must be a positive integer, got {runs!r}")
    if isinstance(failures, bool) or not in_range(failures, 0, integer=True):
        raise ValueError(f"failures must be a non-negative integer, got {failures!r}")
    if failures > runs:
        raise ValueError(f"more failures ({failures}) than runs ({runs})")


def upper_bound(runs: int, failures: int, confidence: float = 0.95) -> float:
    """One-sided Clopper–Pearson upper bound on the failure probability per run, in [0, 1].

    ``runs`` n ≥ 1 independent runs, ``failures`` x of them failed (0 ≤ x ≤ n), ``confidence`` 1 − δ in (0, 1).
    x = 0: 1 − δ^(1/n) exactly (the rule of three's exact form); x = n: 1.
    """
    _check_counts(runs, failures)
    delta = 1.0 - _check_confidence(confidence)
    if failures == 0:
        return float(-math.expm1(math.log(delta) / runs))  # 1 − δ^(1/n), accurate for large n
    if failures == runs:
        return 1.0
    return float(beta.ppf(1.0 - delta, failures + 1, runs - failures))


def runs_needed(epsilon: float, confidence: float = 0.95, failures: int = 0) -> int:
    """The fewest runs n whose bound (:func:`upper_bound`) with ``failures`` failures is ≤ ``epsilon``.

    ``failures`` = 0: the smallest n with (1 − ε)^n ≤ δ = 1 − confidence (ε = 0.01, 0.95 → 299).
    ``failures`` > 0: the bound falls as n grows with x fixed, so n is found by bisection. ValueError when more
    than :data:`MAX_RUNS` would be needed.
    """
    eps, conf = _check_epsilon(epsilon), _check_confidence(confidence)
    if isinstance(failures, bool) or not in_range(failures, 0, integer=True):
        raise ValueError(f"failures must be a non-negative integer, got {failures!r}")

    def enough(n: int) -> bool:
        return upper_bound(n, failures, conf) <= eps

    if failures == 0:  # closed form, then fixed against rounding of the logarithms
        n = max(1, math.ceil(math.log(1.0 - conf) / math.log1p(-eps)))
        if n > MAX_RUNS:
            raise ValueError(f"epsilon {eps:g} at confidence {conf:g} needs about {n} runs, more than {MAX_RUNS}")
        while n > 1 and enough(n - 1):
            n -= 1
        while not enough(n):
            n += 1
        return n
    lo, hi = failures, max(2 * failures + 1, 2)  # enough(lo) is False (bound 1 at n = x)
    while not enough(hi):
        if hi > MAX_RUNS:
            raise ValueError(f"epsilon {eps:g} at confidence {conf:g} with {failures} failures needs more than "
                             f"{MAX_RUNS} runs")
        lo, hi = hi, 2 * hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if enough(mid) else (mid, hi)
    return hi


def percent(p: float) -> str:
    """A probability as a percentage rounded UP (a bound rounded down would not be one): 0.00997 → "1.0 %"."""
    pct = 100.0 * p
    if pct >= 0.1:
        return f"{math.ceil(pct * 10 - 1e-9) / 10:.1f} %"
    digits = 1 - math.floor(math.log10(pct)) if pct > 0 else 1  # two significant digits
    return f"{math.ceil(pct * 10 ** digits - 1e-9) / 10 ** digits:.{digits}f} %"


@dataclass(frozen=True)
class Guarantee:
    """The stated bound of one verified script.

    Attributes:
        runs: raw runs (no barrier) it is computed from.
        contacts: raw runs with at least one contact (or without a measurement: counted as contacts).
        confidence: 1 − δ, in (0, 1).
        epsilon: the configured target P(contact per run) the bound must reach for a bypass (None: none).
    """

    runs: int
    contacts: int
    confidence: float = 0.95
    epsilon: float | None = None

    def __post_init__(self) -> None:
        _check_counts(self.runs, self.contacts)
        _check_confidence(self.confidence)
        if self.epsilon is not None:
            _check_epsilon(self.epsilon)

    @property
    def bound(self) -> float:
        """The upper bound on P(contact per run) at :attr:`confidence`."""
        return upper_bound(self.runs, self.contacts, self.confidence)

    @property
    def method(self) -> str:
        return "rule of three (exact: 1 - delta^(1/n))" if self.contacts == 0 else "Clopper-Pearson"

    @property
    def met(self) -> bool | None:
        """Whether the bound is at most :attr:`epsilon` (None: no ε configured)."""
        return None if self.epsilon is None else self.bound <= self.epsilon

    def statement(self) -> str:
        """"P(contact per run) ≤ 1.0 % at 95 % confidence (299 runs, 0 contacts)"."""
        conf = f"{100 * self.confidence:.10g}"
        return (f"P(contact per run) ≤ {percent(self.bound)} at {conf} % confidence "
                f"({self.runs} run{'s' if self.runs != 1 else ''}, {self.contacts} contact{'s' if self.contacts != 1 else ''})")

    def shortfall(self) -> str | None:
        """Why the bound does not reach :attr:`epsilon` (with the runs that would be needed), or None."""
        if self.epsilon is None or self.met:
            return None
        try:
            more = f"; {runs_needed(self.epsilon, self.confidence, self.contacts)} runs with {self.contacts} contacts " \
                   "would reach it"
        except ValueError as exc:
            more = f"; {exc}"
        if self.contacts == self.runs:
            more = ""
        return f"{self.statement()}: above the required {percent(self.epsilon)}{more}"

    def to_dict(self) -> dict:
        """JSON-ready: runs, contacts, confidence, bound, method, epsilon, met, runs_needed, statement."""
        needed = None
        if self.epsilon is not None:
            try:
                needed = runs_needed(self.epsilon, self.confidence, self.contacts)
            except ValueError:
                needed = None
        return {"runs": self.runs, "contacts": self.contacts, "confidence": float(self.confidence),
                "bound": self.bound, "method": self.method,
                "epsilon": None if self.epsilon is None else float(self.epsilon), "met": self.met,
                "runs_needed": needed, "statement": self.statement()}
