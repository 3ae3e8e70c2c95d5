"""Benchmark: one coverage tick (pre-conditioning, Voronoi, cell integrals, Jacobian, TVD-D1 law,
state with polygons) for N = 10, 50, 100, 200 on the default arena and N = 1000 on a 10 m × 6 m
arena, on the demo density ``moving_density(bounds)`` (three bumps, σ 0.2–0.3 of the half-height).

Run: ``taskset -c 1 .venv/bin/python bench/bench_coverage.py`` (prints a markdown table).

Columns: median ms of the whole tick (process CPU time and wall time) and of its parts (CPU); the max centroid error [m] of the default
quadrature against a much finer one (resolution 0.3 σ, every fan triangle split at least once);
and the ratio of the tick to a baseline run in the same process: ``scipy.spatial.Voronoi`` of the
5N mirrored points alone (the textbook mirror trick, diagram only, no integrals).
"""
from __future__ import annotations

import sys

import harness  # first: pins BLAS before numpy loads
import numpy as np
from scipy.spatial import Voronoi

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.coverage import (
    CoverageConfig,
    QuadratureOptions,
    bounded_voronoi,
    cell_moments,
    centroid_jacobian,
    coverage_tick,
    moving_density,
    precondition_positions,
)

DEFAULT = DEFAULT_BOUNDS
LARGE = (-5.0, 5.0, -3.0, 3.0)


def _median_ms(fn, repeats: int, clock: str = "cpu") -> float:
    """Median ms of ``fn()`` after one untimed call; ``clock`` = process CPU time by default (robust on a
    shared machine: time spent waiting for the CPU does not count), ``"wall"`` for wall time."""
    return harness.measure(fn, repeats, clock=clock, warmup=1).median_ms


def _mirror_voronoi(p: np.ndarray, b: tuple[float, float, float, float]) -> None:
    x, y = p[:, 0], p[:, 1]
    Voronoi(np.concatenate([p, np.column_stack([2 * b[0] - x, y]), np.column_stack([2 * b[1] - x, y]),
                            np.column_stack([x, 2 * b[2] - y]), np.column_stack([x, 2 * b[3] - y])]))


def run(n: int, bounds: tuple[float, float, float, float], repeats: int) -> dict[str, float]:
    rng = np.random.default_rng(n)
    dens = moving_density(bounds).at(3.0)
    lo, hi = np.array(bounds)[[0, 2]], np.array(bounds)[[1, 3]]
    p, _ = precondition_positions(rng.uniform(lo, hi, (n, 2)), bounds)
    # a few Lloyd steps so that the cells look like a running swarm, not uniform noise
    for _ in range(5):
        p = cell_moments(bounded_voronoi(p, bounds), dens).centroids
    cfg = CoverageConfig(law="tvd-d1", bounds=bounds)
    vor = bounded_voronoi(p, bounds)
    mom = cell_moments(vor, dens, cfg.quadrature)
    ref = cell_moments(vor, dens, QuadratureOptions(resolution=0.3, min_level=1, max_level=7))
    return {
        "tick": _median_ms(lambda: coverage_tick(p, dens, cfg, 3.0), repeats),
        "wall": _median_ms(lambda: coverage_tick(p, dens, cfg, 3.0), repeats, "wall"),
        "voronoi": _median_ms(lambda: bounded_voronoi(p, bounds), repeats),
        "moments": _median_ms(lambda: cell_moments(vor, dens, cfg.quadrature), repeats),
        "jacobian": _median_ms(lambda: centroid_jacobian(vor, mom, dens, cfg.edges), repeats),
        "baseline": _median_ms(lambda: _mirror_voronoi(p, bounds), repeats),
        "error": float(np.abs(mom.centroids - ref.centroids).max()),
        "points": float(mom.n_points),
    }


def main() -> int:
    cases = [(10, DEFAULT, 60), (50, DEFAULT, 40), (100, DEFAULT, 40), (200, DEFAULT, 30),
             (1000, LARGE, 12)]
    print(f"# coverage tick — {harness.machine()}\n")
    print(harness.table_header(["N", "arena (m)", "tick CPU (ms)", "tick wall (ms)", "Voronoi", "integrals", "Jacobian",
                                "quadrature points", "max centroid error (m)",
                                "baseline: scipy Voronoi of 5N pts (ms)", "tick / baseline"],
                               [True, False] + [True] * 9))
    for n, b, reps in cases:
        r = run(n, b, reps)
        size = f"{b[1] - b[0]:g} × {b[3] - b[2]:g}"
        print(harness.table_row(n, size, f"{r['tick']:.2f}", f"{r['wall']:.2f}", f"{r['voronoi']:.2f}",
                                f"{r['moments']:.2f}", f"{r['jacobian']:.2f}", int(r['points']), f"{r['error']:.1e}",
                                f"{r['baseline']:.2f}", f"{r['tick'] / r['baseline']:.2f}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
