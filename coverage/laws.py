"""Coverage laws (REFERENCE.md §5, notes/coverage.md §1.5); the speed limit is :func:`swarmdeck.core.kinematics.saturate`.

With b = κ(c − p) + ∂c/∂t and J = ∂c/∂p (2N × 2N, acting on flattened (N, 2) arrays):

=============  ============================  ==========================================
law            command                       closed-loop error e = p − c
=============  ============================  ==========================================
``lloyd``      u = κ(c − p)                  ė = −κ(I − J)e − ∂c/∂t
``lloyd-ff``   u = κ(c − p) + ∂c/∂t          ė = −κ(I − J)e − J ∂c/∂t
``tvd-d1``     u = (I + J) b   (default)     ė = −κ(I − J²)e − J² ∂c/∂t
``tvd-dk``     u = Σ_{l ≤ k} J^l b           ė = −κ(I − J^{k+1})e − J^{k+1} ∂c/∂t
``tvd-c``      u = (I − J)⁻¹ b               ė = −κe  (centralised, ill-conditioned)
=============  ============================  ==========================================

TVD-D1 per robot is u_i = b_i + Σ_{j ∈ N_i ∪ {i}} (∂c_i/∂p_j) b_j with the neighbours' nominal
b_j: one communication hop. TVD-C needs the whole (I − J)⁻¹ and can command thousands of m/s
near degenerate CVTs; it is only available behind ``allow_centralised=True``.
"""
from __future__ import annotations

import re
import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

__all__ = ["LAWS", "parse_law", "law_command"]

LAWS: tuple[str, ...] = ("lloyd", "lloyd-ff", "tvd-d1", "tvd-dk", "tvd-c")


def parse_law(law: str, hops: int = 2) -> tuple[str, int]:
    """Normalise a law name → (family, k). Accepts the names in :data:`LAWS`, ``"tvd-d<k>"``
    (e.g. ``"tvd-d2"``) and a few spellings (``"lloyd+ff"``, ``"tvd-d"``). Raises ValueError."""
    name = str(law).strip().lower().replace("_", "-")
    if name in ("lloyd",):
        return "lloyd", 0
    if name in ("lloyd-ff", "lloyd+ff", "lloydff", "lloyd-feedforward"):
        return "lloyd-ff", 0
    if name in ("tvd-c", "tvdc"):
        return "tvd-c", 0
    if name in ("tvd-dk", "tvd-d"):
        if int(hops) < 1:
            raise ValueError(f"hops must be >= 1 for tvd-dk, got {hops}")
        return "tvd-dk", int(hops)
    m = re.fullmatch(r"tvd-?d(\d+)", name)
    if m and int(m.group(1)) >= 1:
        return ("tvd-dk", int(m.group(1)))
    raise ValueError(f"unknown coverage law {law!r}; expected one of {', '.join(LAWS)} "
                     "or tvd-d<k> (k >= 1)")


def law_command(family: str, k: int, kappa: float, positions: NDArray[np.float64],
                centroids: NDArray[np.float64], dc_dt: NDArray[np.float64],
                jacobian: sp.sparray | None) -> NDArray[np.float64]:
    """Unsaturated command (N, 2) [m/s] of law ``family`` (from :func:`parse_law`).

    ``jacobian`` (2N × 2N) is needed by the tvd laws only. TVD-C raises RuntimeError if
    I − J is singular.
    """
    feedback = kappa * (centroids - positions)
    if family == "lloyd":
        return feedback
    b = feedback + dc_dt
    if family == "lloyd-ff":
        return b
    if jacobian is None:
        raise ValueError(f"law {family} needs the Jacobian")
    flat = b.reshape(-1)
    if family == "tvd-dk":
        out = flat.copy()
        term = flat
        for _ in range(k):
            term = jacobian @ term
            out += term
        return out.reshape(-1, 2)
    if family == "tvd-c":
        n2 = flat.size
        lhs = (sp.eye_array(n2, format="csc") - jacobian.tocsc())
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", spla.MatrixRankWarning)
            try:
                sol = spla.spsolve(lhs, flat)
            except RuntimeError as exc:  # pragma: no cover - scipy raises on singular
                raise RuntimeError(f"TVD-C: I - J is singular ({exc})") from exc
        if not np.all(np.isfinite(sol)):
            raise RuntimeError("TVD-C: I - J is singular")
        return np.asarray(sol).reshape(-1, 2)
    raise ValueError(f"unknown law family {family!r}")
