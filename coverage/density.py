"""Densities φ(q, t) for coverage control: the Gaussian-mixture snapshot and the Density protocol.

A *Density* is any object with ``.at(t) -> GaussianMixture``. The snapshot carries the
parameters at time ``t`` together with their exact time derivatives, so that φ_t is analytic
(REFERENCE.md §5)::

    φ(q)   = floor + Σ_k g_k(q),             g_k = w_k exp(−½ (q − μ_k)ᵀ Σ_k⁻¹ (q − μ_k))
    φ_t(q) = Σ_k [ẇ_k e_k + g_k ((q − μ_k)ᵀ Σ_k⁻¹ μ̇_k + ½ (q − μ_k)ᵀ Σ_k⁻¹ Σ̇_k Σ_k⁻¹ (q − μ_k))]

For isotropic bumps Σ_k = σ_k² I and the bracket is ``(q−μ)·μ̇/σ² + ‖q−μ‖² σ̇/σ³``; the
ẇ term is written as ``ẇ_k e_k`` (e_k the unweighted exponential) so a bump fading in from
w = 0 has a finite φ_t. Units: q and μ in m, σ in m, w and floor in 1/m² (any consistent
scale: the coverage laws are invariant to scaling φ, the cost H is not), derivatives per s.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Density", "GaussianMixture", "merge_mixtures"]


@runtime_checkable
class Density(Protocol):
    """Anything that gives a Gaussian-mixture snapshot (with time derivatives) at time t [s]."""

    def at(self, t: float) -> GaussianMixture:  # pragma: no cover - protocol
        ...


def _vector(name: str, value: ArrayLike | None, k: int, default: float | None) -> NDArray[np.float64]:
    """A (k,) float array named ``name``; ``None`` gives ``default`` everywhere."""
    if value is None:
        if default is None:
            raise ValueError(f"{name} is required (shape ({k},))")
        return np.full(k, float(default))
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0 and k == 1:
        arr = arr.reshape(1)
    if arr.shape != (k,):
        raise ValueError(f"{name} must have shape ({k},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN/inf), got {arr}")
    return arr.copy()


def _points(name: str, value: ArrayLike | None, k: int | None) -> NDArray[np.float64]:
    """A (k, 2) float array named ``name``; ``None`` gives zeros (only when k is known)."""
    if value is None:
        if k is None:
            raise ValueError(f"{name} is required (shape (K, 2))")
        return np.zeros((k, 2))
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.shape == (2,) and k in (None, 1):
        arr = arr.reshape(1, 2)
    if arr.size == 0:
        arr = arr.reshape(0, 2)
    if arr.ndim != 2 or arr.shape[1] != 2 or (k is not None and arr.shape[0] != k):
        expect = f"({k}, 2)" if k is not None else "(K, 2)"
        raise ValueError(f"{name} must have shape {expect}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN/inf)")
    return arr.copy()


def _matrices(name: str, value: ArrayLike, k: int) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (k, 2, 2):
        raise ValueError(f"{name} must have shape ({k}, 2, 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN/inf)")
    if not np.allclose(arr, np.swapaxes(arr, 1, 2), rtol=1e-12, atol=1e-15):
        raise ValueError(f"{name} must be symmetric 2x2 matrices")
    return 0.5 * (arr + np.swapaxes(arr, 1, 2))


def _quadratic_coeffs(mat: NDArray[np.float64], mu: NDArray[np.float64]) -> NDArray[np.float64]:
    """Coefficients (6, K) of (q − μ_k)ᵀ A_k (q − μ_k) on the features [1, x, y, x², xy, y²]."""
    am = np.einsum("kab,kb->ka", mat, mu) if mu.shape[0] else np.zeros((0, 2))
    return np.stack([(mu * am).sum(axis=1), -2.0 * am[:, 0], -2.0 * am[:, 1],
                     mat[:, 0, 0], 2.0 * mat[:, 0, 1], mat[:, 1, 1]])


def _readonly(*arrays: NDArray[np.float64]) -> None:
    for a in arrays:
        a.setflags(write=False)


class GaussianMixture:
    """A snapshot of φ(·, t) = floor + Σ_k w_k exp(−‖q − μ_k‖² / (2σ_k²)) with its time derivatives.

    Parameters
    ----------
    floor : float, ≥ 0. Constant part of φ (1–5 % of a bump peak keeps every cell mass > 0).
    mu : (K, 2) bump centres [m].  sigma : (K,) bump widths [m], > 0.  weight : (K,) peaks, ≥ 0.
    mu_dot : (K, 2) [m/s], sigma_dot : (K,) [m/s], weight_dot : (K,) [1/s]; ``None`` = 0.
    cov, cov_dot : keyword-only alternative to ``sigma``/``sigma_dot`` for anisotropic bumps,
        (K, 2, 2) symmetric positive-definite covariances [m²] and their rates [m²/s].

    Derived: ``cov`` (K, 2, 2) and ``cov_dot`` always; ``std_min``/``std_max`` (K,) the smallest
    and largest standard deviation of each bump [m]; ``isotropic``.
    The snapshot is immutable and is itself a :class:`Density` (``at(t)`` returns ``self``).
    Raises ``ValueError`` naming the argument for NaN, negative weights or floor, σ ≤ 0,
    non-positive-definite covariances, wrong shapes, or a density with zero mass.
    """

    __slots__ = ("floor", "mu", "sigma", "weight", "mu_dot", "sigma_dot", "weight_dot",
                 "cov", "cov_dot", "isotropic", "std_min", "std_max", "_prec", "_qdot", "_cq", "_ct")
    floor: float
    mu: NDArray[np.float64]
    sigma: NDArray[np.float64]
    weight: NDArray[np.float64]
    mu_dot: NDArray[np.float64]
    sigma_dot: NDArray[np.float64]
    weight_dot: NDArray[np.float64]
    cov: NDArray[np.float64]
    cov_dot: NDArray[np.float64]
    isotropic: bool
    std_min: NDArray[np.float64]
    std_max: NDArray[np.float64]
    _prec: NDArray[np.float64]
    _qdot: NDArray[np.float64]
    _cq: NDArray[np.float64]
    _ct: NDArray[np.float64]

    def __init__(
        self,
        floor: float = 0.05,
        mu: ArrayLike | None = None,
        sigma: ArrayLike | None = None,
        weight: ArrayLike | None = None,
        mu_dot: ArrayLike | None = None,
        sigma_dot: ArrayLike | None = None,
        weight_dot: ArrayLike | None = None,
        *,
        cov: ArrayLike | None = None,
        cov_dot: ArrayLike | None = None,
    ) -> None:
        f = float(floor)
        if not np.isfinite(f) or f < 0.0:
            raise ValueError(f"floor must be a finite number >= 0, got {floor!r}")
        mu_arr = _points("mu", mu if mu is not None else np.zeros((0, 2)), None)
        k = mu_arr.shape[0]
        w = _vector("weight", weight, k, 1.0 if k == 0 else None)
        if np.any(w < 0.0):
            raise ValueError(f"weight must be >= 0, got {w}")
        w_dot = _vector("weight_dot", weight_dot, k, 0.0)
        m_dot = _points("mu_dot", mu_dot, k)
        if cov is not None:
            if sigma is not None or sigma_dot is not None:
                raise ValueError("give either sigma/sigma_dot (isotropic) or cov/cov_dot, not both")
            c = _matrices("cov", cov, k)
            eig = np.linalg.eigvalsh(c) if k else np.zeros((0, 2))
            if np.any(eig <= 0.0):
                raise ValueError("cov must be positive definite (every eigenvalue > 0)")
            c_dot = _matrices("cov_dot", cov_dot, k) if cov_dot is not None else np.zeros((k, 2, 2))
            s = np.sqrt(np.sqrt(np.linalg.det(c))) if k else np.zeros(0)
            s_dot = np.zeros(k)
            iso = False
            std_lo, std_hi = np.sqrt(eig[:, 0]), np.sqrt(eig[:, 1])
        else:
            if cov_dot is not None:
                raise ValueError("cov_dot needs cov")
            s = _vector("sigma", sigma, k, 1.0 if k == 0 else None)
            if np.any(s <= 0.0):
                raise ValueError(f"sigma must be > 0, got {s}")
            s_dot = _vector("sigma_dot", sigma_dot, k, 0.0)
            eye = np.eye(2)
            c = (s ** 2)[:, None, None] * eye
            c_dot = (2.0 * s * s_dot)[:, None, None] * eye
            iso = True
            std_lo, std_hi = s.copy(), s.copy()
        with np.errstate(over="ignore"):
            total = f + w.sum()
        if not np.isfinite(total):
            raise ValueError("floor + sum(weight) overflows: use weights of a sensible scale")
        if f == 0.0 and not np.any(w > 0.0):
            raise ValueError("density has zero mass: floor is 0 and no weight is > 0")
        prec = np.linalg.inv(c) if k else np.zeros((0, 2, 2))
        # ½ Σ⁻¹ Σ̇ Σ⁻¹: the quadratic form of the σ-rate term of φ_t
        qdot = 0.5 * prec @ c_dot @ prec if k else np.zeros((0, 2, 2))
        # Polynomial coefficients on the features F(q) = [1, x, y, x², xy, y²] (6, K):
        # (q − μ)ᵀ P (q − μ) = F·cq and (q − μ)ᵀ P μ̇ + (q − μ)ᵀ Q (q − μ) = F·ct, so the
        # evaluation is two small matrix products and one exp over (M, K) (no (M, K, 2) arrays).
        cq = _quadratic_coeffs(prec, mu_arr)  # type: ignore[arg-type]
        pm = np.einsum("kab,kb->ka", prec, m_dot) if k else np.zeros((0, 2))
        ct = _quadratic_coeffs(qdot, mu_arr)
        ct[0] -= (mu_arr * pm).sum(axis=1)
        ct[1:3] += pm.T
        ct = ct * w
        _readonly(mu_arr, s, w, m_dot, s_dot, w_dot, c, c_dot, prec, qdot, cq, ct, std_lo, std_hi)  # type: ignore[arg-type]
        object.__setattr__(self, "floor", f)
        for name, val in (("mu", mu_arr), ("sigma", s), ("weight", w), ("mu_dot", m_dot),
                          ("sigma_dot", s_dot), ("weight_dot", w_dot), ("cov", c),
                          ("cov_dot", c_dot), ("isotropic", iso), ("std_min", std_lo),
                          ("std_max", std_hi), ("_prec", prec), ("_qdot", qdot),
                          ("_cq", cq), ("_ct", ct)):
            object.__setattr__(self, name, val)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("GaussianMixture is immutable")

    # ------------------------------------------------------------------ protocol
    def at(self, t: float) -> GaussianMixture:
        """A snapshot is a (frozen-in-time) Density: returns itself for every t."""
        return self

    # ------------------------------------------------------------------ properties
    @property
    def n_bumps(self) -> int:
        """Number of Gaussian bumps K."""
        return int(self.mu.shape[0])

    @property
    def sigma_min(self) -> float:
        """Narrowest length scale [m]: min over bumps of √(smallest eigenvalue of Σ_k); inf if K = 0.

        Bumps with zero weight and zero weight rate do not count (they contribute nothing).
        """
        live = (self.weight > 0.0) | (self.weight_dot != 0.0)
        if not np.any(live):
            return float("inf")
        return float(self.std_min[live].min())

    @property
    def peak(self) -> float:
        """An upper bound of max φ: floor + Σ w_k [1/m²]."""
        return float(self.floor + self.weight.sum())

    # ------------------------------------------------------------------ evaluation
    def _check_q(self, q: ArrayLike) -> NDArray[np.float64]:
        arr = np.asarray(q, dtype=float)
        if arr.ndim < 1 or arr.shape[-1] != 2:
            raise ValueError(f"q must have shape (M, 2), got {arr.shape}")
        return arr

    def evaluate(self, q: ArrayLike) -> NDArray[np.float64]:
        """φ(q) for query points q (..., 2) [m]; returns shape (...,)."""
        return self._evaluate(q, rate=False)[0]

    def evaluate_dt(self, q: ArrayLike) -> NDArray[np.float64]:
        """Analytic φ_t(q) [1/(m² s)] for query points q (..., 2); returns shape (...,)."""
        return self._evaluate(q, rate=True)[1]

    def evaluate_both(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(φ(q), φ_t(q)) sharing one evaluation of the exponentials; shapes (...,)."""
        return self._evaluate(q, rate=True)

    def _evaluate(self, q: ArrayLike, rate: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """φ and (if ``rate``) φ_t at q (..., 2), in chunks of points.

        With many bumps, each chunk only evaluates the bumps within 9 standard deviations of the
        chunk's bounding box (the rest contribute < 3e-18 of their weight). Callers get the most
        from this when consecutive query points are close together.
        """
        arr = self._check_q(q)
        shape = arr.shape[:-1]
        flat = arr.reshape(-1, 2)
        m, k = flat.shape[0], self.n_bumps
        phi = np.full(m, self.floor)
        phi_t = np.zeros(m)
        if k == 0 or m == 0:
            return phi.reshape(shape), phi_t.reshape(shape)
        local = k > 8
        # Chunks keep the (M, K) temporaries small; products small enough for OpenBLAS to run
        # single-threaded use BLAS, larger ones einsum: a threaded GEMM on a busy CPU is 100×
        # slower in wall time than either (measured while other processes shared the cores).
        step = 1024 if local else max(1, 30000 // k)
        reach = 9.0 * self.std_max if local else None
        for lo in range(0, m, step):
            chunk = flat[lo:lo + step]
            cq, ct, w, wd = self._cq, self._ct, self.weight, self.weight_dot
            if local:
                gap = np.maximum(np.maximum(chunk.min(axis=0) - self.mu, self.mu - chunk.max(axis=0)), 0.0)
                near = np.hypot(gap[:, 0], gap[:, 1]) < reach
                if not near.any():
                    continue
                if not near.all():
                    cq, ct, w, wd = cq[:, near], ct[:, near], w[near], wd[near]
            x, y = chunk[:, 0], chunk[:, 1]
            feat = np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])
            small = chunk.shape[0] * cq.shape[1] * 6 < 200_000

            def poly(c: NDArray[np.float64], feat: NDArray[np.float64] = feat, small: bool = small) -> NDArray[np.float64]:
                return feat @ c if small else np.einsum("mf,fk->mk", feat, c)

            e = np.exp(-0.5 * poly(cq))
            phi[lo:lo + step] += np.einsum("mk,k->m", e, w)
            if rate:
                phi_t[lo:lo + step] = np.einsum("mk,k->m", e, wd) + np.einsum("mk,mk->m", e, poly(ct))
        return phi.reshape(shape), phi_t.reshape(shape)

    # ------------------------------------------------------------------ misc
    def to_dict(self) -> dict[str, Any]:
        """JSON-able parameters (lists of floats) for recording/drawing."""
        out: dict[str, Any] = {
            "floor": self.floor,
            "mu": self.mu.tolist(),
            "weight": self.weight.tolist(),
            "mu_dot": self.mu_dot.tolist(),
            "weight_dot": self.weight_dot.tolist(),
        }
        if self.isotropic:
            out["sigma"] = self.sigma.tolist()
            out["sigma_dot"] = self.sigma_dot.tolist()
        else:
            out["cov"] = self.cov.tolist()
            out["cov_dot"] = self.cov_dot.tolist()
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> GaussianMixture:
        """Inverse of :meth:`to_dict`; raises ValueError for malformed data."""
        if not isinstance(data, dict):
            raise ValueError(f"density parameters must be a dict, got {type(data).__name__}")
        known = {"floor", "mu", "sigma", "weight", "mu_dot", "sigma_dot", "weight_dot", "cov", "cov_dot"}
        extra = set(data) - known
        if extra:
            raise ValueError(f"unknown density parameters: {sorted(extra)}")
        kw = {k: data[k] for k in known - {"cov", "cov_dot"} if k in data}
        return cls(**kw, cov=data.get("cov"), cov_dot=data.get("cov_dot"))

    def __repr__(self) -> str:
        return (f"GaussianMixture(floor={self.floor}, K={self.n_bumps}, "
                f"sigma_min={self.sigma_min:.4g})")


def merge_mixtures(parts: Iterable[GaussianMixture | None], floor: float) -> GaussianMixture:
    """One snapshot holding every bump of ``parts`` (Nones and empty snapshots skipped) over ``floor``.

    The parts' own floors are not added: φ = floor + Σ_parts Σ_k g_k, and φ_t the sum of the
    parts' φ_t (each bump keeps its μ̇, σ̇/Σ̇, ẇ). Isotropic when every part is; otherwise every
    bump is written as a covariance. With no bumps at all: the constant ``floor``.
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
