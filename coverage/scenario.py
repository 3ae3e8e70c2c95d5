"""Reference scenario S1 (REFERENCE.md §5): a deterministic regression target for the laws.

N = 9 robots on the grid x ∈ {−1, 0, 1}, y ∈ {−0.5, 0, 0.5}; φ = 0.05 + exp(−‖q − μ(t)‖²/(2·0.4²)),
μ(t) = 0.6 (cos(2πt/20), sin(2πt/20)); κ = 1; forward Euler dt = 0.033 s for 40 s (1212 steps);
positions clamped 1 mm inside the arena; no barrier, no saturation. Mean H and mean ‖p − c‖
are averaged over the 1212 ticks (t = 0 … 39.963 s).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.kinematics import saturate
from swarmdeck.coverage.controller import CoverageConfig
from swarmdeck.coverage.densities import s1_density
from swarmdeck.coverage.jacobian import centroid_jacobian
from swarmdeck.coverage.laws import law_command, parse_law
from swarmdeck.coverage.quadrature import QuadratureOptions, cell_moments
from swarmdeck.coverage.voronoi import bounded_voronoi

__all__ = ["S1_REFERENCE", "S1_T0", "S1Result", "s1_start", "s1_config", "run_s1", "run_s1_all",
           "format_s1_table"]

#: law → (mean H over [0, 40] s, mean ‖p − c‖) from REFERENCE.md §5.
S1_REFERENCE: dict[str, tuple[float, float]] = {
    "lloyd": (0.12325, 0.0464),
    "lloyd-ff": (0.11923, 0.0312),
    "tvd-d1": (0.11437, 0.0198),
    "tvd-d2": (0.11244, 0.0157),
}
#: t = 0 values: H, total mass, robot (−1, −0.5): centroid and ∂c/∂t.
S1_T0 = {"H": 0.159274, "mass": 1.306659, "c": (-1.04205, -0.62228),
         "dc_dt": (-0.0043961, -0.00083564)}

S1_BOUNDS = DEFAULT_BOUNDS
S1_DT = CONTROL_PERIOD
S1_STEPS = 1212


@dataclass(frozen=True)
class S1Result:
    """law; mean_H; mean_distance (mean over ticks of mean_i ‖p_i − c_i‖); H (steps,) series;
    max_speed [m/s] over the run; final positions (9, 2)."""

    law: str
    mean_H: float
    mean_distance: float
    H: NDArray[np.float64]
    max_speed: float
    positions: NDArray[np.float64]


def s1_start() -> NDArray[np.float64]:
    """The 3 × 3 start grid (9, 2) [m]."""
    return np.array([[x, y] for x in (-1.0, 0.0, 1.0) for y in (-0.5, 0.0, 0.5)])


def s1_config(law: str) -> CoverageConfig:
    """S1's controller settings: κ = 1, no saturation, accurate quadrature."""
    return CoverageConfig(law=law, kappa=1.0, max_speed=None, bounds=S1_BOUNDS,
                          quadrature=QuadratureOptions(resolution=1.0))


def run_s1(law: str, steps: int = S1_STEPS, dt: float = S1_DT,
           config: CoverageConfig | None = None) -> S1Result:
    """Run S1 with ``law`` (any name :func:`parse_law` accepts) and return its summary."""
    cfg = config if config is not None else s1_config(law)
    cfg = replace(cfg, law=law)
    density = s1_density()
    x0, x1, y0, y1 = S1_BOUNDS
    lo, hi = np.array([x0 + 1e-3, y0 + 1e-3]), np.array([x1 - 1e-3, y1 - 1e-3])
    p = s1_start()
    hs = np.empty(steps)
    ds = np.empty(steps)
    vmax = 0.0
    family, hops = parse_law(cfg.law, cfg.hops)
    needs_jacobian = family in ("tvd-dk", "tvd-c")
    for k in range(steps):
        t = k * dt
        snap = density.at(t)
        # the controller's pipeline without the drawing state (polygons, edges, packing)
        vor = bounded_voronoi(p, S1_BOUNDS)
        mom = cell_moments(vor, snap, cfg.quadrature)
        jac = centroid_jacobian(vor, mom, snap, cfg.edges) if needs_jacobian else None
        u = saturate(law_command(family, hops, cfg.kappa, p, mom.centroids, mom.dc_dt, jac),
                     cfg.max_speed)
        hs[k] = mom.cost_H
        ds[k] = float(np.hypot(*(mom.centroids - p).T).mean())
        vmax = max(vmax, float(np.hypot(u[:, 0], u[:, 1]).max()))
        p = np.clip(p + dt * u, lo, hi)
    return S1Result(law=law, mean_H=float(hs.mean()), mean_distance=float(ds.mean()), H=hs,
                    max_speed=vmax, positions=p)


def run_s1_all(progress: bool = False) -> dict[str, S1Result]:
    """Run S1 for every law of :data:`S1_REFERENCE` (``progress`` prints one line per law)."""
    out = {}
    for law in S1_REFERENCE:
        out[law] = run_s1(law)
        if progress:
            print(f"  {law}: done", flush=True)
    return out


def format_s1_table(results: dict[str, S1Result]) -> str:
    """Markdown table: mean H and mean ‖p − c‖ per law next to the reference values."""
    lines = ["| law | mean H | reference | rel. diff | mean ‖p − c‖ (m) | reference | max speed (m/s) |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for law, r in results.items():
        ref_h, ref_d = S1_REFERENCE.get(law, (float("nan"), float("nan")))
        lines.append(f"| {law} | {r.mean_H:.5f} | {ref_h:.5f} | {r.mean_H / ref_h - 1:+.1e} | "
                     f"{r.mean_distance:.4f} | {ref_d:.4f} | {r.max_speed:.3f} |")
    return "\n".join(lines)
